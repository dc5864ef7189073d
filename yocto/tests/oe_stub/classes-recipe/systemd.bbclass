# openembedded-core's (or meta-rauc's) systemd class: empty for the parser (oe_stub/conf/bitbake.conf).
