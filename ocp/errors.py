"""Exception tree of thrustshape.

::

    ThrustshapeError                 root: catch this to catch everything we raise on purpose
    ├── ParameterError(ValueError)   a parameter file or value is wrong (names the key)
    ├── MissionError(ValueError)     a mission / profile / request is wrong (names the field)
    │   └── InfeasibleError          no reference within the limits exists (names the binding limit)
    ├── LogError(ValueError)         a measurement log is unusable (names the column)
    └── SolverError(RuntimeError)    a numerical solve failed in a way the caller must see

Every leaf also subclasses the matching builtin so generic ``except ValueError`` code keeps working.
The service maps the tree to problem+json answers in one handler.
"""

from __future__ import annotations

from collections.abc import Collection, Mapping
from typing import Any


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


class InfeasibleError(MissionError):
    """Nothing within the mission's limits reproduces it, not even the analytic fallback with its hold
    levels lowered and its time stretched; ``field`` names the binding limit (e.g. ``limits.current``)."""


class LogError(ThrustshapeError, ValueError):
    """A measurement log cannot be used."""


class SolverError(ThrustshapeError, RuntimeError):
    """A numerical solve failed."""


#: the tags pydantic puts into the location of a tagged-union member: mission segment kinds
SEGMENT_TAGS = frozenset({"hold", "ramp", "reversal", "sine"})
_TYPE_NAMES = frozenset({"str", "int", "float", "bool"})
_TYPE_PREFIXES = ("dict[", "list[", "function-", "literal[")


def validation_location(err: Mapping[str, Any], tags: Collection[str] = SEGMENT_TAGS) -> tuple[str, str]:
    """(dotted field path, reason) of one pydantic validation error, as the user wrote the input.

    Union tags in ``tags`` and pydantic's type/validator names are dropped from the location
    (``segments.1.reversal.duration`` -> ``segments.1.duration``); a :class:`ThrustshapeError` raised
    inside a validator keeps its own field (appended to the location unless it already ends it) and
    reason. The path is "" for an error on the whole input.
    """
    loc = [str(p) for p in err.get("loc", ()) if str(p) not in tags]
    reason = {"extra_forbidden": "unknown field", "missing": "missing field"}.get(str(err.get("type", "")),
                                                                                   str(err.get("msg", "invalid")))
    ctx_err = (err.get("ctx") or {}).get("error")
    loc = [p for p in loc if p not in _TYPE_NAMES and not p.startswith(_TYPE_PREFIXES)]
    if isinstance(ctx_err, ThrustshapeError):
        head = ".".join(loc)
        if not head or ctx_err.field == "params" or head.endswith(ctx_err.field):
            return head or ctx_err.field, ctx_err.reason
        return f"{head}.{ctx_err.field}", ctx_err.reason
    return ".".join(loc), reason.removeprefix("Value error, ")
