"""The exceptions bikedyn raises.

Every one is a :class:`Error` (catch that for anything bikedyn refuses) and
also the built-in kind a Python user expects: a bad parameter is a
``ValueError``, a missing file a ``FileNotFoundError``, a failed write an
``OSError``. Messages are the command line's: they name the file, line and
field at fault.
"""


class Error(Exception):
    """Base class of every error bikedyn raises."""


class InvalidArgumentError(Error, ValueError):
    """An argument of a call is out of range or malformed (a NaN speed, an
    empty speed list, an unknown integration method)."""


class ParameterError(Error, ValueError):
    """A bicycle's parameters are missing, malformed or non-physical (the
    message names the file or dict, the line and the field)."""


class ModelError(Error, ValueError):
    """No generated model can represent the bicycle, an unknown model was
    named, or the asked-for form (canonical matrices) does not exist for it."""


class DataError(Error, ValueError):
    """Measured runs or logs could not be processed (the message names the
    run folder or log file and what is wrong)."""


class ComputationError(Error, RuntimeError):
    """A linearization, eigenvalue or integration step failed (singular
    matrices, non-finite values, a step size underflow)."""


class OutputError(Error, OSError):
    """A report, table or plot could not be written; nothing half-written
    is left behind."""


class NotFoundError(Error, FileNotFoundError):
    """A parameter file, run folder or log that does not exist."""


class TooLargeError(Error, MemoryError):
    """A request whose result would exceed the size bikedyn allows (the
    message gives the limit); split it into smaller calls."""


class InternalError(Error, RuntimeError):
    """A defect in bikedyn itself (a caught Rust panic); please report it."""


__all__ = [
    "Error",
    "InvalidArgumentError",
    "ParameterError",
    "ModelError",
    "DataError",
    "ComputationError",
    "OutputError",
    "NotFoundError",
    "TooLargeError",
    "InternalError",
]
