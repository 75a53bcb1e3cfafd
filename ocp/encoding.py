"""The core's one JSON encoder: every ``to_dict()`` of a result goes through :func:`jsonable`.

Strict JSON has no non-finite numbers, so they have one spelling everywhere (the CLI's ``--json``, the
service's answers, gallery files):

* ``+inf`` / ``-inf`` -> the strings ``"inf"`` / ``"-inf"`` (an unbounded value keeps its sign: the ideal
  command at a reversal it cannot make);
* ``NaN`` -> ``null`` (no value: a quantity that does not exist for this answer).

A result may decide that an unbounded quantity has no value instead: a comparison stores the peaks of a shape
whose ideal command is unbounded as ``None`` and its unbounded samples as NaN (both ``null``: the page leaves a
gap), while a closed-form reference keeps them (``"inf"``).

Dataclasses become objects of their fields (a field with ``metadata={"json": False}`` is left out; an object
with a ``__json__()`` method chooses its own fields), enums their values, numpy arrays lists, numpy scalars plain
numbers.
"""

from __future__ import annotations

import dataclasses
import math
from enum import Enum
from typing import Any

import numpy as np


def number(x: float) -> float | str | None:
    """A float in the core's JSON spelling (see the module doc)."""
    if math.isfinite(x):
        return x
    if math.isnan(x):
        return None
    return "inf" if x > 0 else "-inf"


def jsonable(obj: Any) -> Any:
    """``obj`` as plain JSON values (dict, list, str, int, float, bool, None); non-finite floats spelled
    once (module doc)."""
    if isinstance(obj, bool | np.bool_):
        return bool(obj)
    if isinstance(obj, Enum):
        return obj.value
    if isinstance(obj, float | np.floating):
        return number(float(obj))
    if isinstance(obj, int | np.integer):
        return int(obj)
    if isinstance(obj, np.ndarray):
        if obj.dtype.kind in "fiub" and (obj.dtype.kind != "f" or bool(np.isfinite(obj).all())):
            return obj.tolist()  # every element already a finite float, an int or a bool: nothing to spell
        return [jsonable(v) for v in obj.tolist()]
    if isinstance(obj, dict):
        return {str(k): jsonable(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [jsonable(v) for v in obj]
    if hasattr(obj, "__json__") and not isinstance(obj, type):
        return jsonable(obj.__json__())
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        return {f.name: jsonable(getattr(obj, f.name)) for f in dataclasses.fields(obj) if f.metadata.get("json", True)}
    return obj
