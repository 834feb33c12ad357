"""The one error type of the bag package, shared by writing, reading and repairing."""


class BagError(OSError):
    """A bag cannot be written or read: the message names the file and what went wrong."""
