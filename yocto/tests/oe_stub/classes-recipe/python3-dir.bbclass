# openembedded-core's (or meta-rauc's) python3-dir class: empty for the parser (oe_stub/conf/bitbake.conf).
