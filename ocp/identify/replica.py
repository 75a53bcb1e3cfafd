"""The method's own error: what an effect takes on the nominal plant's noise-free replica of a log.

The equations of :mod:`.regression` are written on the logged samples: derivatives from finite differences and
low-passes, a held command, rows of one sample. On a model-exact log they are not zero: that residual is the
method's, and effects absorb part of it (a drag asymmetry acting near zero speed on a rotor that spins up from rest, a
Stribeck band on the rows a sine turns slowly). On a log without noise that part was all the evidence, and such
effects were named (session 63: a 0/6 V square wave, a 1 Hz sine, a step down, each model-exact and noise-free).
:func:`artifacts` runs the nominal plant itself under the logged command (:func:`replica`), writes the same equations
on it, and asks of each adopted effect whether it takes more of the log's held-out error than of the replica's: what
it takes of the replica is the method's error under this very command, not a missing effect. Both falls are in the
log's noise units, so on a noisy log the replica's is far below any effect's and nothing changes.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import replace

import numpy as np

from ocp.errors import MissionError, SolverError
from ocp.identify.evidence import Fitted
from ocp.identify.holdout import Split
from ocp.identify.regression import CONSTANTS, Design, build
from ocp.identify.select import Selection, fit_model
from ocp.logs import Log, LogKind
from ocp.model.plant import DCMotorPlant
from ocp.simulate.open_loop import simulate_zoh


def replica(plant: DCMotorPlant, log: Log) -> Log:
    """``log`` with its measured channels replaced by ``plant``'s noise-free run under the logged command
    (zero-order hold, from the logged first speed and current): the same rows, the same channels; a speed the log
    differentiated from its angle is differentiated so again."""
    i0 = float(log.current[0]) if log.has("current") else 0.0
    run = simulate_zoh(plant, log.t, log.voltage, [float(log.omega[0]), i0])
    theta = None if log.theta is None else log.theta[0] + run.theta
    derived = log.theta is not None and np.allclose(log.omega, np.gradient(log.theta, log.t))
    nan = np.full(log.n, np.nan)
    return replace(log, current=run.x[1] if log.has("current") else nan,
                   thrust=run.thrust if log.has("thrust") else nan,
                   omega=np.gradient(theta, log.t) if derived and theta is not None else run.x[0], theta=theta)


def _falls(design: Design, before: Fitted, after: Fitted, sigma: np.ndarray) -> float:
    """The held-out mean square ``after`` takes off ``before``, summed over the equations, in units of ``sigma``
    (3,) [N m, V, N]."""
    return float(np.sum((before.per_eq ** 2 - after.per_eq ** 2) * (design.sigma / sigma) ** 2))


def simulated(plant: DCMotorPlant, log: Log) -> Log | None:
    """:func:`replica` of a time series with a command; None for a steady-state sweep, a log without voltage or a
    plant too stiff to run over the log."""
    if log.kind is not LogKind.TIME_SERIES or not log.has("voltage"):
        return None
    try:
        return replica(plant, log)
    except (MissionError, SolverError):
        return None


def artifacts(plant: DCMotorPlant, copy: Callable[[], Log | None], design: Design, final: Fitted, tol: float,
              share: float, sp: Split) -> list[str]:
    """The effects of ``final`` (adopted on ``design``, the log's equations on the rows of ``sp``) whose fall on
    the log's held-out error (beside the other items) is not ``share`` beyond the fall the same model takes of the
    nominal plant's replica of the log (``copy()``, :func:`simulated`; asked only where ``final`` holds an effect),
    both in the log's noise units: the method's own error, not a missing effect. ``share``: the selection's
    ``min_improvement`` (that much of an effect's fall must be its own). None is judged without a replica."""
    effects = [i for i in final.items if i not in CONSTANTS]
    run = copy() if effects else None
    if run is None:
        return []
    rep = build(plant.params, run, sp.train, sp.test, tuple(effects), None, raw_torque=True,
                folds=list(sp.folds) or None)
    on_rep = fit_model(rep, final.items, tol)
    out = []
    for e in effects:
        others = [i for i in final.items if i != e]
        if (1.0 - share) * _falls(design, fit_model(design, others, tol), final, design.sigma) \
                <= _falls(rep, fit_model(rep, others, tol), on_rep, design.sigma):
            out.append(e)
    return out


def unmasked(plant: DCMotorPlant, log: Log, design: Design, sel: Selection, pool: list[str],
             redo: Callable[[list[str]], Selection], tol: float, share: float,
             sp: Split) -> tuple[Selection, list[str]]:
    """``sel`` (a selection over ``pool`` on ``design``) redone by ``redo(pool)`` with its final model's
    :func:`artifacts` (on the rows of ``sp``) left out of the pool, until it adopts none; and a sentence for each
    effect so set aside. The replica is run once, where first asked for."""
    said, copy = [], functools.cache(lambda: simulated(plant, log))
    while fake := artifacts(plant, copy, design, sel.final, tol, share, sp):
        pool = [c for c in pool if c not in fake]
        said += [f"{e} is not named: it takes no more of this log's held-out error than of the nominal plant's own "
                 f"noise-free run under the logged command (the method's error under this command, not a missing "
                 f"effect)" for e in fake]
        sel = redo(pool)
    return sel, said
