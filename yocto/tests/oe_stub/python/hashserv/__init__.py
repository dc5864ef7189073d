"""A stand-in for BitBake's hash equivalence client (bitbake/lib/hashserv), which PyPI's
bitbake-setup does not ship but bb.siggen imports. Parsing never calls it: any call is refused."""


def is_valid_unihash(unihash: str) -> bool:
    raise NotImplementedError("hashserv stand-in: the layer's tests parse, they do not run a signature server")


def create_client(*args, **kwargs):
    raise NotImplementedError("hashserv stand-in: the layer's tests parse, they do not run a signature server")
