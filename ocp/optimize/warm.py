"""Warm starts that IPOPT uses (issue 14 item 2): the solver options, the memory and when to use it.

IPOPT ignores the multipliers it is given unless ``warm_start_init_point=yes``; with it, a small initial
barrier (``mu_init``) and small pushes off the bounds keep a start that is already nearly optimal where it is.
Those options are fixed when a solver is built, and they hurt a start from a rough guess (the
continuous-voltage reversal did not converge in 1,000 iterations with them), so a program keeps two solvers:
the cold one and the warm one (the Radau program builds it on its first warm start; the flat program with the
program, from the cold solver's derivative functions, :func:`build_solver`).

A program remembers its last solution, primal and dual (:class:`Memory`; the flat program its last
:data:`MEMORIES`). A later solve starts from it when asked (``warm=True``: the Radau program's back-off rounds)
or, by default (``warm=None``), when the new call is plausibly close (:func:`distances`, :func:`pick`: same phase
signs and weights, desired thrust, durations, scales (and the flat program's plant constants) within ``CLOSE``
relative, the same bound pattern). Batch items and repeated requests of one structure so start warm; anything
else starts cold.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np

#: IPOPT options of a program's warm solver (on top of the cold solver's)
WARM_OPTIONS: dict[str, object] = {
    "ipopt.warm_start_init_point": "yes",
    # a start that is already nearly optimal passes the cold solver's tolerance at once, however far it is from
    # the new optimum in objective (a 2 % change of thrust on the 2 s reversal: 1 iteration, +1.8 % objective);
    # a tighter one costs a few Newton steps
    "ipopt.tol": 1e-10,
    "ipopt.mu_init": 1e-4,
    "ipopt.warm_start_bound_push": 1e-6,
    "ipopt.warm_start_bound_frac": 1e-6,
    "ipopt.warm_start_slack_bound_push": 1e-6,
    "ipopt.warm_start_slack_bound_frac": 1e-6,
    "ipopt.warm_start_mult_bound_push": 1e-6,
}
#: largest relative change (max norm, against the larger magnitude) of the desired thrust, durations, scales
#: and finite bounds for which a previous solution is taken as a start
CLOSE = 0.25
#: past solves a program remembers (:func:`pick`): batch items of one structure start from the nearest
MEMORIES = 8


@dataclass(frozen=True)
class Memory:
    """The last solve of a program: decision vector, multipliers and the data it was solved for (scaled).

    Shapes: ``x``, ``lam_x``, ``lbx``, ``ubx`` (n,); ``lam_g`` (n_g,); ``p`` (n_params,).
    """

    x: np.ndarray
    lam_x: np.ndarray
    lam_g: np.ndarray
    p: np.ndarray
    lbx: np.ndarray
    ubx: np.ndarray


def _rel(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Largest relative difference of each row of ``a`` (k, m) from ``b`` (m,): shape (k,) (0 for m = 0)."""
    scale = np.maximum(np.maximum(np.abs(a), np.abs(b)), 1e-12)
    return np.max(np.abs(a - b) / scale, axis=1, initial=0.0)


def distances(memories: Sequence[Memory], p: np.ndarray, lbx: np.ndarray, ubx: np.ndarray,
              exact: Mapping[str, slice], near: Mapping[str, slice], fd: slice) -> np.ndarray:
    """How far each solve in ``memories`` (k) is from parameters ``p`` and bounds ``lbx``/``ubx``, shape (k,): the
    largest of the relative changes of the ``near`` slices (durations, scales), of the desired thrust ``fd``
    (scaled, against its largest value) and of the finite bounds (scaled, absolute); ``inf`` where the sizes, an
    ``exact`` slice (signs, weights) or the pattern of finite bounds differ."""
    out = np.full(len(memories), math.inf)
    ok = [k for k, m in enumerate(memories) if m.p.shape == p.shape and m.lbx.shape == lbx.shape]
    if not ok:
        return out
    P = np.stack([memories[k].p for k in ok])  # (k, n_params)
    admissible = np.ones(len(ok), bool)
    for s in exact.values():
        admissible &= np.all(P[:, s] == p[s], axis=1)
    change = np.zeros(len(ok))
    for s in near.values():
        change = np.maximum(change, _rel(P[:, s], p[s]))
    peak = max(float(np.max(np.abs(p[fd]))), 1e-12)
    change = np.maximum(change, np.max(np.abs(P[:, fd] - p[fd]), axis=1, initial=0.0) / peak)
    for name, new in (("lbx", lbx), ("ubx", ubx)):
        old, finite = np.stack([getattr(memories[k], name) for k in ok]), np.isfinite(new)
        admissible &= np.all(np.isfinite(old) == finite, axis=1)
        change = np.maximum(change, np.max(np.abs(old[:, finite] - new[finite]), axis=1, initial=0.0))
    out[ok] = np.where(admissible, change, math.inf)
    return out


#: the Radau program's parameter parts that must be equal / within CLOSE for a warm start (:func:`start_from`)
RADAU_EXACT, RADAU_NEAR = ("sigma", "weights"), ("dur", "xscale", "uscale", "fscale")


def start_from(mem: Memory | None, warm: bool | None, p: np.ndarray, lbx: np.ndarray, ubx: np.ndarray,
               slices: Mapping[str, slice], exact: tuple[str, ...] = RADAU_EXACT,
               near: tuple[str, ...] = RADAU_NEAR) -> bool:
    """Whether a solve starts from ``mem``: asked (``warm=True``, same size) or, ``warm=None``, when it is
    plausibly close (:func:`distances` within ``CLOSE``; ``slices``: the program's parameter layout,
    ``exact``/``near``: the names of its parts that must be equal / within ``CLOSE``, ``slices["fd"]`` the desired
    thrust)."""
    return pick([] if mem is None else [mem], warm, p, lbx, ubx, slices, exact, near) is not None


def pick(memories: Sequence[Memory], warm: bool | None, p: np.ndarray, lbx: np.ndarray, ubx: np.ndarray,
         slices: Mapping[str, slice], exact: tuple[str, ...], near: tuple[str, ...],
         limit: float = CLOSE) -> Memory | None:
    """The memory (of a program's last few solves, oldest first) a solve starts from: none (``warm=False``), the
    latest of the right size (``warm=True``), or (``warm=None``) the nearest (:func:`distances`) within ``limit``."""
    sized = [m for m in memories if m.x.size == lbx.size]
    if warm is False or not sized:
        return None
    if warm:
        return sized[-1]
    far = distances(sized, p, lbx, ubx, {k: slices[k] for k in exact}, {k: slices[k] for k in near}, slices["fd"])
    best = int(np.argmin(far))
    return sized[best] if far[best] <= limit else None


def warm_args(mem: Memory, lbx: np.ndarray, ubx: np.ndarray) -> dict[str, np.ndarray]:
    """A solver call's start from ``mem``: its primal (clipped into the new bounds ``lbx``/``ubx``) and duals."""
    return {"x0": np.clip(mem.x, lbx, ubx), "lam_x0": mem.lam_x, "lam_g0": mem.lam_g}


def remember(sol: Mapping[str, Any], p: np.ndarray, lbx: np.ndarray, ubx: np.ndarray) -> Memory:
    """The memory of a solver call's result ``sol`` (CasADi's x, lam_x, lam_g) for parameters ``p`` and bounds."""
    return Memory(x=np.asarray(sol["x"]).ravel(), lam_x=np.asarray(sol["lam_x"]).ravel(),
                  lam_g=np.asarray(sol["lam_g"]).ravel(), p=p.copy(), lbx=lbx.copy(), ubx=ubx.copy())


#: the derivative functions a warm solver takes from its program's cold solver instead of deriving them again
#: (the flat program's symbolic Hessian is most of its ~2 s build; with them the warm build takes ~0.3 s)
SHARED = {"hess_lag": "nlp_hess_l", "jac_g": "nlp_jac_g", "grad_f": "nlp_grad_f"}


def build_solver(name: str, nlp: dict[str, ca.SX], options: Mapping[str, object], callback: object,
                 cold: ca.Function | None = None) -> ca.Function:
    """A program's warm solver: its cold ``options`` with :data:`WARM_OPTIONS`, the same iteration ``callback``;
    the cold solver ``cold`` (built from the same ``nlp``) lends its derivative functions (:data:`SHARED`)."""
    shared = {} if cold is None else {opt: cold.get_function(fn) for opt, fn in SHARED.items()}
    return ca.nlpsol(name, "ipopt", nlp, {**options, **WARM_OPTIONS, **shared, "iteration_callback": callback})  # type: ignore[dict-item]
