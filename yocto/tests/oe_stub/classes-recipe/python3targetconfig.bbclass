# openembedded-core's (or meta-rauc's) python3targetconfig class: empty for the parser (oe_stub/conf/bitbake.conf).
