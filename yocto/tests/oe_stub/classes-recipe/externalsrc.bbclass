# openembedded-core's externalsrc class, of which the parser needs one effect: the recipe's
# source folder is EXTERNALSRC and its build folder EXTERNALSRC_BUILD (oe_stub/conf/bitbake.conf).
python () {
    if d.getVar('EXTERNALSRC'):
        d.setVar('S', d.getVar('EXTERNALSRC'))
        if d.getVar('EXTERNALSRC_BUILD'):
            d.setVar('B', d.getVar('EXTERNALSRC_BUILD'))
}
