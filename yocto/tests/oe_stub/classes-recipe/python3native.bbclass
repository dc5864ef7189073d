# openembedded-core's (or meta-rauc's) python3native class: empty for the parser (oe_stub/conf/bitbake.conf).
