"""The one error type of the command line: a bad argument, reported on one line, status 2."""


class UsageError(Exception):
    """A bad command-line argument: reported on one line, exit status 2."""
