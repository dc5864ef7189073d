# openembedded-core's (or meta-rauc's) base class: empty for the parser (oe_stub/conf/bitbake.conf).
