# openembedded-core's (or meta-rauc's) pkgconfig class: empty for the parser (oe_stub/conf/bitbake.conf).
