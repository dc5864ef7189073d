# openembedded-core's (or meta-rauc's) core-image class: empty for the parser (oe_stub/conf/bitbake.conf).
