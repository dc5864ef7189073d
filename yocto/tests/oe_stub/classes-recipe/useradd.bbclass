# openembedded-core's (or meta-rauc's) useradd class: empty for the parser (oe_stub/conf/bitbake.conf).
