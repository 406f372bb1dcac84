"""Exception types a user can act on.

Every error raised on purpose by slipreflex derives from :class:`SlipreflexError`,
so a caller can catch the whole family; each also derives from the built-in type
that describes it best (``ValueError`` for bad parameters and bad data), so
ordinary ``except ValueError`` code keeps working.
"""

from __future__ import annotations

__all__ = ["SlipreflexError", "ParameterError", "DataError", "DeviceError"]


class SlipreflexError(Exception):
    """Base class of every error slipreflex raises on purpose.

    Examples
    --------
    >>> try:
    ...     raise ParameterError("threshold must be >= 0, got -1")
    ... except SlipreflexError as err:
    ...     print(err)
    threshold must be >= 0, got -1
    """


class ParameterError(SlipreflexError, ValueError):
    """A parameter is out of range, NaN, or unknown; the message names it.

    Examples
    --------
    >>> isinstance(ParameterError("n must be >= 1"), ValueError)
    True
    """


class DataError(SlipreflexError, ValueError):
    """Input data is malformed; the message names the file, line or index.

    Examples
    --------
    >>> str(DataError("rec.csv, line 3: cell 'x' is not a number: 'abc'"))
    "rec.csv, line 3: cell 'x' is not a number: 'abc'"
    """


class DeviceError(SlipreflexError, OSError):
    """A serial port or device misbehaves; the message names the port.

    Examples
    --------
    >>> isinstance(DeviceError("/dev/ttyUSB0: no such port"), OSError)
    True
    """
