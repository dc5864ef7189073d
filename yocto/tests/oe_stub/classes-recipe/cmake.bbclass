# openembedded-core's (or meta-rauc's) cmake class: empty for the parser (oe_stub/conf/bitbake.conf).
