"""Exceptions of the mocap Python tools.

    MocapError             base of everything raised on purpose
    +-- InputError         a file or message is malformed or inconsistent
    +-- DataMissingError   an optional data set (e.g. ../shared) is not present
"""


class MocapError(Exception):
    pass


class InputError(MocapError):
    pass


class DataMissingError(MocapError):
    pass
