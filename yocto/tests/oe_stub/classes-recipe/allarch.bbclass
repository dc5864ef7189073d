# openembedded-core's (or meta-rauc's) allarch class: empty for the parser (oe_stub/conf/bitbake.conf).
