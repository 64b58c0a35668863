"""The exceptions thermokin raises: every one a ``ThermokinError``; bad input is also a ``ValueError``
and a missing file a ``FileNotFoundError``, so that ordinary ``except`` clauses catch them. The message is
the command line's: the file, line and field where the library names them."""


class ThermokinError(Exception):
    """Base of every thermokin error."""


class InputError(ThermokinError, ValueError):
    """Bad input: a value, a setting, a file's content (file, line and field named)."""


class MissingFileError(ThermokinError, FileNotFoundError):
    """A file that is not there."""


class RefusedError(ThermokinError):
    """A result refused as asked: the diagnosis does not beat the nominal model on data it never saw, so its
    robot is not exported unless forced (the command line's exit status 5)."""


__all__ = ["ThermokinError", "InputError", "MissingFileError", "RefusedError"]
