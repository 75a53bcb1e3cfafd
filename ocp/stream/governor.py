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

Quantities = Callable[[float], Sequence[float]]  # v -> the limited quantities (current, voltage, ...)

PASSES = 3


def _interval(q: Quantities, j: int, limit: float, v: float, c0: float) -> tuple[float, float] | None:
    """Admissible v for ``|q(v)[j]| <= limit`` by linearisation at ``v``; None when it does not depend on v."""
    d = 1e-6 * (abs(v) + 1.0)
    s = (q(v + d)[j] - q(v - d)[j]) / (2.0 * d)
    if abs(s) * (abs(v) + 1.0) < 1e-12 * (abs(c0) + limit):
        return None
    a, b = v + (-limit - c0) / s, v + (limit - c0) / s
    return (a, b) if a <= b else (b, a)


def govern(v: float, q: Quantities, limits: Sequence[float], is_voltage: Sequence[bool]) -> tuple[float, bool]:
    """(admissible v closest to ``v``, True when ``v`` was changed); ``q(v)[j]`` must stay within
    ``+-limits[j]``; voltages (``is_voltage[j]``) first."""
    changed = False
    for _ in range(PASSES):
        vals = q(v)
        if all(abs(c) <= lim for c, lim in zip(vals, limits, strict=True)):
            return v, changed
        lo, hi = -float("inf"), float("inf")
        for want_voltage in (True, False):
            for j, (lim, is_v) in enumerate(zip(limits, is_voltage, strict=True)):
                if is_v != want_voltage:
                    continue
                iv = _interval(q, j, lim, v, vals[j])
                if iv is not None and max(lo, iv[0]) <= min(hi, iv[1]):
                    lo, hi = max(lo, iv[0]), min(hi, iv[1])
        v = min(max(v, lo), hi)
        changed = True
    return v, changed
