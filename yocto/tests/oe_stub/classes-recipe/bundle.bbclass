# openembedded-core's (or meta-rauc's) bundle class: empty for the parser (oe_stub/conf/bitbake.conf).
