"""Reference governor of the shaper: clip the tracker's decision so the next sample keeps i and V in limits.

The decision ``v`` (``eta''`` at the end of the sample) enters the current at the next sample through
``eta'`` (slope ``dt`` or ``dt/2``) and the voltage through ``eta''`` directly (slope ``b1``) and through
``eta'`` -- so every limit is reachable in one sample: a one-step governor is enough. For each limited
quantity ``c(v)`` (current at ``t_{k+1}``, voltage at ``t_{k+1}`` and, with a held ``eta''``, also at
``t_k+``) the admissible ``v`` is found by linearising ``c`` at the current candidate (central finite
difference) and intersecting the intervals; three such passes absorb the curvature of ``w|w|`` and
``eta^3`` over one sample. Voltage limits take priority over the current limit when both cannot hold
(the drive cannot exceed its supply; a current overshoot is then reported, not hidden).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

Constraint = tuple[Callable[[float], float], float, bool]  # (c(v), limit, is_voltage)

PASSES = 3


def _interval(c: Callable[[float], float], limit: float, v: float) -> tuple[float, float] | None:
    """Admissible v for ``|c(v)| <= limit`` by linearisation at ``v``; None when c does not depend on v."""
    d = 1e-6 * (abs(v) + 1.0)
    c0 = c(v)
    s = (c(v + d) - c(v - d)) / (2.0 * d)
    if abs(s) * (abs(v) + 1.0) < 1e-12 * (abs(c0) + limit):
        return None
    a, b = v + (-limit - c0) / s, v + (limit - c0) / s
    return (a, b) if a <= b else (b, a)


def _intersect(lo: float, hi: float, iv: tuple[float, float] | None) -> tuple[float, float, bool]:
    if iv is None:
        return lo, hi, True
    a, b = max(lo, iv[0]), min(hi, iv[1])
    return (a, b, True) if a <= b else (lo, hi, False)


def govern(v: float, constraints: Sequence[Constraint]) -> tuple[float, bool]:
    """(admissible v closest to ``v``, True when ``v`` was changed)."""
    changed = False
    for _ in range(PASSES):
        if all(abs(c(v)) <= lim for c, lim, _ in constraints):
            return v, changed
        lo, hi = -float("inf"), float("inf")
        for want_voltage in (True, False):
            for c, lim, is_v in constraints:
                if is_v == want_voltage:
                    lo, hi, _ok = _intersect(lo, hi, _interval(c, lim, v))
        v = min(max(v, lo), hi)
        changed = True
    return v, changed
