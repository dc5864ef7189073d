"""Errors the edge boxes raise on purpose, each with a message a user can act on:

    EdgeError            base: catch this at the command line and print the message
    ├── SourceError      a frame source cannot be opened (unknown scheme, bad option,
    │                    missing file, device or Python module)
    ├── ModelError       a keypoint model cannot be opened (unknown name, bad option,
    │                    configuration or stream file)
    └── TriggerError     the trigger line cannot be requested (no GPIO chip, no gpiod,
                         line busy)

Bad data while running (an undecodable frame, an unpaired frame) is counted and dropped,
never raised.
"""


class EdgeError(Exception):
    pass


class SourceError(EdgeError):
    pass


class ModelError(EdgeError):
    pass


class TriggerError(EdgeError):
    pass
