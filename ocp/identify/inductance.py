"""What a log can say about the inductance ``L`` beside what mimics its error (issue #11), eq. dc_electrical.

An inductance error ``x`` leaves ``x L i'`` in the armature equation; a command timing error of ``d`` samples leaves
``-d dt R i'``, and a current filter of time constant ``t_f`` raises the apparent inductance by ``R t_f``. The
functions here set ``L``'s box in the regression (:attr:`.regression.Design.unresolved`, ``slack``, ``one_sided``,
``above``, ``lag_inductance``) from what the alignment measured, and judge a named ``L`` against the timing that
mimics it on held-out free runs (:func:`inductance_wins`), and say when an unconfirmed delay explains it as well
(:func:`delay_rival`).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from ocp.errors import SolverError
from ocp.identify.align import SKEW_FRACTION
from ocp.identify.evidence import IMPLAUSIBLE_FACTOR
from ocp.identify.explain import KEYS
from ocp.identify.realign import realign
from ocp.identify.regression import Design
from ocp.logs import Log
from ocp.model.effects import make_effect
from ocp.model.plant import DCMotorPlant

#: the grid [samples] of command timings within the conventions a named ``L``'s rival is tried at (:func:`timings`)
TIMING_STEP = 0.25

#: why a named ``L`` above nominal under two samples is left unnamed when the nominal one predicts the speed as well
#: (:func:`filter_mimics`)
FILTER_MIMICS = ("L/R is under two samples and the nominal L predicts the held-out speed as well as this higher one: a "
                 "current sensor's filter raises the apparent inductance as much, and moves no speed")
#: why a named ``L`` is left unresolved when the timing that mimics it predicts as well (:func:`inductance_wins`)
TIMING_MIMICS = ("the nominal L under a command timing the logging conventions explain predicts the held-out speed "
                 "and current as well: the log cannot tell the inductance from the timing")


def open_timing(design: Design, plant: DCMotorPlant, log: Log, tolerance: float, max_skew: float) -> None:
    """``L`` where the command timing is not identified (flat alignment residual): a timing error of ``d`` samples
    within the conventions (``|d|`` up to ``max_logging_skew + SKEW_FRACTION``) leaves ``-d dt R i'`` in eq.
    dc_electrical, as an inductance error ``x = d dt R / L`` does. Up to that ``x`` it widens ``L``'s calibration
    box (:attr:`.regression.Design.slack`), and an error beyond both is still named (e.g. 43 % at an L/R of 11
    samples, where the timing mimics at most 25 %). Where the box would reach a factor of two below nominal
    (``tol + x >= 1 - 1 / IMPLAUSIBLE_FACTOR``: L/R under about 7 samples), no plausible error is left to name on
    that side: ``L`` is unresolved, with the reason (as it is when the selection names ``L`` beyond a factor two
    (:func:`.diagnose._explain`): a timing error beyond the conventions, an unconfirmed delay, is the likelier
    cause)."""
    x = (max_skew + SKEW_FRACTION) * log.dt * plant.params.R / plant.params.L
    if tolerance + x < 1.0 - 1.0 / IMPLAUSIBLE_FACTOR:
        design.slack["L"] = x
        return
    design.unresolved.setdefault("L", "the command timing is not identifiable in this log (flat alignment "
                                      "residual): an inductance error cannot be told from a sub-sample timing error")


def timed_inductance(design: Design, plant: DCMotorPlant, log: Log, tolerance: float, timing: float) -> None:
    """``L`` where L/R is under two samples but the command timing is measured (to ``timing`` samples,
    :func:`.align.spread`): a current filter of time constant ``t_f`` (eq. dc_electrical on the filtered current:
    ``L i' + R (i + t_f i')``) only RAISES the apparent inductance, by ``R t_f``; what can lower it is a timing
    error ``d`` the alignment left, ``-d dt R i'``. So ``L`` is boxed at ``tol`` widened by that timing error,
    ``x = timing dt R / L``, and above nominal also by the filter the torque equation measures
    (:func:`filter_headroom`); an apparent ``L`` below the box can only be a smaller inductance, and is named; one
    above it is named only where it also predicts the held-out speed better than the nominal ``L``
    (:func:`filter_mimics`: the torque equation measures a filter of a fraction of a sample too loosely to bound
    ``L`` alone). Unnamed above nominal, ``L`` stays nominal in the calibrated plant (:func:`.explain.applied`). Where
    the box would reach a factor two below nominal (L/R under about a third of a sample on a sharp alignment),
    nothing plausible is left to name."""
    x = timing * log.dt * plant.params.R / plant.params.L
    if tolerance + x >= 1.0 - 1.0 / IMPLAUSIBLE_FACTOR:
        return
    design.one_sided["L"] = (design.unresolved.pop("L") + f"; named below nominal beyond {100 * (tolerance + x):.0f} "
                             f"% (the timing measured to {timing:.2g} samples), above it also beyond the current "
                             "filter the torque equation measures, where it predicts the held-out speed better (a "
                             "filter raises L, not the speed's error); unnamed above nominal, it calibrates nothing")
    design.slack["L"] = x


def filter_headroom(design: Design, plant: DCMotorPlant, log: Log) -> None:
    """``L``'s calibration box widened ABOVE nominal by the current filter the torque equation measures: the
    current lag ``l`` [samples] each model fits (the ``current_lag`` nuisance, where the true current is
    ``i + l dt i'``) raises the apparent inductance in eq. dc_electrical by ``R l dt``, a relative ``l dt R / L``
    that is the logger's, not the motor's (a clean 10 kHz log with a 0.3-sample filter showed ``L`` 20 % high). A
    lead (``l < 0``) widens nothing (:func:`.select.fit_model`)."""
    if "L" not in design.unresolved:
        design.lag_inductance = log.dt * plant.params.R / plant.params.L


def inductance_wins(plant: DCMotorPlant, final: DCMotorPlant, named: Sequence[str], log: Log, shift: float | None,
                    tau: float, heldout: Callable[[DCMotorPlant, Log], float], min_improvement: float,
                    max_skew: float, searched: bool = True) -> bool:
    """Whether ``final`` (``plant`` explained, its ``L`` named at a relative error ``x``) predicts the held-out speed
    and current (``heldout``: free run, noise units) better by ``min_improvement`` than its rival: the nominal ``L``
    under the best command timing the conventions explain (:func:`timings`, ``tau`` the nominal L/R in samples: a
    lag ``d`` samples long leaves ``-d dt R i'``, an L error ``x L i'``), the adopted effects as fitted, and the other
    constants either as calibrated beside ``L`` or nominal but for the other ``named`` ones, whichever predicts
    better (calibrated beside a wrong ``L``, they may have taken part of it: proving ground 3099, a clean 1 kHz log
    whose ``L`` fitted -45 %, free run 10.1 noise units against 9.98 with the other constants nominal at the
    mimicking lag, 15.8 with them as calibrated; nominal, they miss what calibration is for: blind rig 211, a clean
    chirp's lag found 0 for 1, ``L`` +62 %, 1.99 against 4.4 nominal at 1.08 samples, 2.04 calibrated at 0.75).
    ``shift``: the lag [samples] the log is realigned by for ``final``; None when ``final`` holds an ``input_delay``
    (then that delay is moved by ``x tau`` samples, the other ``named`` constants as fitted, every other nominal).
    The alignment's search carries the sensors' noise, and a lag a sample off is an ``L`` error of ``1 / tau``
    (proving ground: clean 2 kHz log 23172, lag 2.22 for 1.13 samples at an L/R of 2.36: ``L`` -49 %). Not
    ``searched``, beside a delay the alignment measured and did not confirm, the rival is the mimicking lag alone,
    the other constants nominal but for the ``named`` ones: the question there is the delay, which
    :func:`delay_rival` offers beside a named ``L`` (proving ground 6180, an 11-sample delay beside an ``L`` 29 %
    high: any timing within the conventions took ``L`` too, and left neither named nor offered). A plant too stiff
    to free-run keeps ``L`` named."""
    x = final.params.L / plant.params.L - 1.0
    keys = [key for c in named if c != "L" and c in KEYS for key in KEYS[c]]
    params = plant.params.model_copy(update={key: getattr(final.params, key) for key in keys})
    try:
        if shift is None:
            moved = tuple(make_effect("input_delay", {"delay": max(float(getattr(e, "delay", 0.0)) + x * tau * log.dt,
                                                                   0.0)})
                          if e.name == "input_delay" else e for e in final.effects)
            own, rival = heldout(final, log), heldout(DCMotorPlant(params, moved), log)
        else:
            top, mimic = max_skew + SKEW_FRACTION, shift + x * tau
            lags = timings(mimic, top) if searched else [mimic] if 0.0 <= mimic <= top else []
            if not lags:
                return True
            own = heldout(final, realign(log, shift, tau, max_skew))
            forms = [DCMotorPlant(p, final.effects) for p in
                     ((final.params.model_copy(update={"L": plant.params.L}), params) if searched else (params,))]
            for lag in lags:  # (the first rival that predicts as well decides: the rest need not run)
                late = realign(log, lag, tau, max_skew)
                if any(own > (1.0 - min_improvement) * heldout(rival, late) for rival in forms):
                    return False
            return True
    except SolverError:
        return True
    return own <= (1.0 - min_improvement) * rival


def timings(mimic: float, top: float) -> list[float]:
    """The command lags [samples] a named ``L``'s rival is tried at: the conventions' ``0..top`` on a
    :data:`TIMING_STEP` grid, and ``mimic`` (the lag that mimics the ``L`` error) where it lies within. A longer lag
    is a delay, which the alignment judged already (a 10 kHz log's ``L`` 40 % off, mimicked by 3.9 samples)."""
    return sorted({*np.arange(0.0, top + 1e-9, TIMING_STEP).tolist(), *([mimic] if 0.0 <= mimic <= top else [])})


def filter_mimics(plant: DCMotorPlant, final: DCMotorPlant, log: Log, shift: float | None, tau: float, max_skew: float,
                  speed: Callable[[DCMotorPlant, Log], float]) -> bool:
    """Whether the nominal ``L`` predicts the held-out speed (``speed``: free-run error, noise units) at least as
    well as ``final``'s ``L`` above nominal (``shift``, ``tau``: as for :func:`inductance_wins`). A current filter
    raises the apparent inductance in eq. dc_electrical but leaves the torque the rotor integrates alone, so a plant
    given that inductance predicts the speed worse; a true inductance error changes the charge each current
    transient delivers within a sample, and the speed shows it (proving ground 14198: ``L`` 47 % high at an L/R of
    0.52 samples, held-out speed 17.7 noise units with the nominal ``L``, 7.5 with the named one; 3046 of the
    ``constant`` draws, a ``k`` error logged through a 0.56-sample filter: ``L`` fitted 87 % high, speed 0.79 with
    the nominal ``L``, 0.98 with it). A plant too stiff to free-run, or an ``L`` below nominal, is not mimicked.
    ``max_skew``: the conventions' whole samples ``shift`` is read from (:func:`.realign.switched`)."""
    if final.params.L <= plant.params.L:
        return False
    moved = log if shift is None else realign(log, shift, tau, max_skew)
    try:
        return speed(DCMotorPlant(final.params.model_copy(update={"L": plant.params.L}), final.effects), moved) \
            <= speed(final, moved)
    except SolverError:
        return False


def delay_rival(current: Callable[[float], float], lag: float, short: float, noise: float,
                margin: float) -> dict[str, object] | None:
    """An ambiguity entry (as :func:`.diagnose.diagnose` reports them) for a named ``L`` beside a delay the alignment
    measured but did not confirm: where the command ``lag`` samples late predicts the armature's held-out current
    (``current``: its error [A] per lag [samples], :func:`.align.armature_error`, each lag with its best L/R; ``noise``
    [A] the current's noise level) within ``margin`` of the lag ``short`` [samples] the conventions explain, or better
    (not by enough to be called). On a smooth command dead time and a slower armature look alike: the inductance
    error may be the delay (proving ground 6168: a 9.5-sample delay at 10 kHz under a chirp, named an ``L`` error;
    6180: an 11-sample delay beside an ``L`` 29 % high, fitted +108 %).
    None where the delay predicts worse, or either error is undefined (a short log)."""
    late, near = current(lag), current(short)
    if not late <= (1.0 + margin) * near:
        return None
    return {"adopted": "param:L", "alternative": "input_delay", "score": near / noise,
            "alternative_score": late / noise,
            "reason": f"a command delay of {lag:.2f} samples, measured by the alignment beyond the logging "
                      "conventions, predicts the armature's held-out current at least as well as this inductance "
                      f"error ({late / noise:.3g} vs {near / noise:.3g} noise units, each with its best L/R): on this "
                      "log dead time and a slower armature look alike"}
