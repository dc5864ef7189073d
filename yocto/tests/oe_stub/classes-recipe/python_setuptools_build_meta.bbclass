# openembedded-core's (or meta-rauc's) python_setuptools_build_meta class: empty for the parser (oe_stub/conf/bitbake.conf).
