"""Applying a measured alignment to a log: the command moved later by the lag, a fraction of a sample read as a drive
switching within the row (:func:`switched`); the lag itself is measured by :mod:`.align`."""

from __future__ import annotations

import math
from dataclasses import replace

from ocp.identify.align import Alignment, shifted
from ocp.logs import Log, LogKind


def switched(samples: float, tau: float, top: float = math.inf) -> float:
    """The lag [samples] whose linear interpolation (:func:`shifted`) gives each held row the voltage that drives an
    armature of time constant ``tau`` [samples] (the nominal L/R) over the row as the drive does, which switches from
    the old command to the new one ``f`` of a row late (``samples = m + f``, ``m`` whole). A slow armature integrates
    the two levels: ``f`` itself (the interpolation); one that settles within the row shows only the new level at the
    row's end: ``m`` (its current samples cannot tell when in the row the drive switched; the torque equation's
    ``switch_phase`` nuisance can, :func:`.columns.nuisance_columns`).

    The estimate's fraction is read from the whole sample nearest it, on either side: a lag measured a little short
    of ``m + 1`` on a fast armature is ``m + 1``, not ``m`` (its interpolation-equivalent lag is the whole sample, and
    a free fit's noise or a lagging speed sensor puts the estimate either side of it: the blind rig's 619 at 0.99 for
    1 and 626 at 1.84 for 2 were each applied a whole sample short as ``m``). With ``d = samples - n``,
    ``n`` the nearest whole sample, the lag is ``n + sign(d) g(|d|)``, ``g`` the fraction's map above: ``samples``
    itself for a slow armature, ``n`` for a fast one. ``top`` [samples]: the most whole samples the lag may be read
    from (a lag within the logging conventions: at most their skew, so that their 0.75-sample fraction for the
    drive's update instant is not read as a further whole sample); beyond it, the whole sample below."""
    n = math.floor(samples + 0.5)
    n = n if n <= top else math.floor(samples)
    d = samples - n
    x = 1.0 / max(tau, 1e-9)
    # eq:dc_electrical over the row, exact for held levels: i1 = a i0 + (1 - a) v / R with
    # v = V_new - (V_new - V_old) (b - a) / (1 - a), a = exp(-x), b = exp(-x (1 - f)), x = 1 / tau
    f = abs(d)
    g = math.exp(-x * (1.0 - f)) * math.expm1(-x * f) / math.expm1(-x) if x < 700.0 else 0.0
    return n + math.copysign(g, d)


def realign(log: Log, samples: float, tau: float | None = None, top: float = math.inf) -> Log:
    """The log with its command moved ``samples`` later, so that row k's command drives k -> k+1 (eq. ZOH); with the
    armature's nominal L/R ``tau`` [samples], a fraction of a sample as a drive switching within the row
    (:func:`switched`, read from at most ``top`` whole samples), else interpolated."""
    if samples <= 0 or log.kind is LogKind.STEADY_STATE:
        return log
    lag = samples if tau is None else switched(samples, tau, top)
    return Log(log.t, shifted(log.voltage, lag), log.current, log.omega, log.theta, log.thrust, log.kind,
               log.source)


def applying(align: Alignment, log: Log, own: float, tau: float, top: float) -> tuple[Alignment, Log]:
    """``align`` with the lag the equations see (:attr:`Alignment.applied`) and ``log`` realigned by it: the
    alignment less ``own`` [samples] (the plant's own delay), read by :func:`switched` with the nominal L/R ``tau``
    [samples] from at most ``top`` whole samples."""
    lag = switched(max(align.samples - own, 0.0), tau, top)
    return replace(align, applied=lag), realign(log, lag)  # (the lag read once: realign interpolates it as it is)
