"""Exception tree of thrustshape.

::

    ThrustshapeError                 root: catch this to catch everything we raise on purpose
    ├── ParameterError(ValueError)   a parameter file or value is wrong (names the key)
    ├── MissionError(ValueError)     a mission / profile / request is wrong (names the field)
    ├── LogError(ValueError)         a measurement log is unusable (names the column)
    └── SolverError(RuntimeError)    a numerical solve failed in a way the caller must see

Every leaf also subclasses the matching builtin so generic ``except ValueError`` code keeps working.
The service maps the tree to problem+json answers in one handler.
"""

from __future__ import annotations


class ThrustshapeError(Exception):
    """Root of all errors raised on purpose by thrustshape.

    ``field`` names the offending input (a parameter key, a mission field path, a log column),
    ``reason`` says what is wrong with it.
    """

    def __init__(self, field: str, reason: str) -> None:
        self.field = field
        self.reason = reason
        super().__init__(f"{field}: {reason}")


class ParameterError(ThrustshapeError, ValueError):
    """A motor/propeller parameter set is invalid."""


class MissionError(ThrustshapeError, ValueError):
    """A mission, profile or reference request is invalid."""


class LogError(ThrustshapeError, ValueError):
    """A measurement log cannot be used."""


class SolverError(ThrustshapeError, RuntimeError):
    """A numerical solve failed."""
