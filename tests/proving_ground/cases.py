"""Draw one proving-ground case from a seed: rig, hidden physics, logger, excitation; run it; say the truth.

Motors span a 5 W hobby motor to a 500 W drive (J, R, L, k over decades). A case is clean, one effect,
two effects, one wrong nominal constant (5-50 %), or an effect plus a wrong constant. Every drawn
discrepancy must be visible: replayed open loop under the logged commands, the log without it must differ
from the log with it by at least ``VISIBLE`` noise levels (RMS, in some channel as the logger records it: an
encoder's speed is a difference of angles, the current filtered; a ripple the rig shows at its sample instants
but the log averages out is not a discrepancy of the log); amplitudes are doubled
(up to twice) until it is, a constant error raised to 50 %, else the draw is replaced (the next draw of the
same seed); the criterion is checked again under the commands the final log holds. ``expected`` is the exact
verdict a correct model check gives: the effects, plus ``param:<name>`` for a constant off by more than
``TOLERANCE``.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from tests.proving_ground.excite import OPEN_LOOP, open_loop, pi_loop
from tests.proving_ground.logger import Logger, draw_logger, logged, noise_levels, record
from tests.proving_ground.physics import Truth, run

EFFECTS = ("coulomb_friction", "stribeck", "drag_asymmetry", "thrust_asymmetry", "force_offset", "voltage_deadband",
           "brush_drop", "current_offset", "input_delay", "thrust_lag", "cogging")
CONSTANTS = ("J", "B", "c_tau", "c_f", "k", "R", "L")
TOLERANCE = 0.10
VISIBLE = 1.5
MAX_SAMPLES = 6000
MAX_ATTEMPTS = 20


@dataclass
class Drawn:
    """A drawn rig's record: ``columns`` its logged signals in SI; ``nominal`` the constants the user believes (J,
    B, c_tau, c_f, k_t, k_e, R, L); ``expected`` the labels (effect names, ``param:<key>``); ``truth`` the rig."""

    seed: int
    kind: str
    columns: dict[str, np.ndarray]
    nominal: dict[str, float]
    expected: frozenset[str]
    truth: Truth


@dataclass
class Case(Drawn):
    """One log with its truth. ``columns``: t, voltage, current, omega, thrust (+ theta); how it was logged and
    excited; the constants' drawn errors."""

    logger: Logger
    excitations: tuple[str, ...]
    constant_error: dict[str, float] = field(default_factory=dict)
    meta: dict[str, Any] = field(default_factory=dict)


def draw_motor(rng: np.random.Generator) -> tuple[Truth, float]:
    """A motor + propeller from 5 W to 500 W; returns it and its mechanical time constant [s]."""
    power = math.exp(rng.uniform(math.log(5.0), math.log(500.0)))
    v = float(rng.choice([6.0, 12.0, 24.0])) if power < 60 else float(rng.choice([24.0, 36.0, 48.0]))
    w0 = math.exp(rng.uniform(math.log(150.0), math.log(1200.0)))  # no-load speed [rad/s]
    k = v / w0
    r = v * v / (rng.uniform(5.0, 12.0) * power)
    el = r * math.exp(rng.uniform(math.log(1e-4), math.log(3e-3)))
    w_op = 0.7 * w0
    tau_op = k * (v - k * w_op) / r * 0.85
    c_tau = tau_op / w_op**2
    tau_m = math.exp(rng.uniform(math.log(0.01), math.log(0.15)))
    j = tau_m * k * k / r
    b = rng.uniform(0.02, 0.1) * tau_op / w_op
    c_f = c_tau * rng.uniform(15.0, 45.0)
    return Truth(J=j, B=b, c_tau=c_tau, c_f=c_f, k=k, R=r, L=el, v_max=v), tau_m


def _scales(t: Truth) -> dict[str, float]:
    w_op = 0.7 * t.v_max / t.k
    tau_op = t.c_tau * w_op**2
    return {"w0": t.v_max / t.k, "tau": tau_op, "i": tau_op / t.k, "F": t.c_f * w_op**2, "v": t.v_max}


def draw_effect(name: str, t: Truth, dt: float, rng: np.random.Generator) -> dict[str, float]:
    s, u = _scales(t), rng.uniform
    sign = float(rng.choice([-1.0, 1.0]))
    return {
        "coulomb_friction": lambda: {"tau_c": u(0.04, 0.12) * s["tau"]},
        "stribeck": lambda: {"tau_s": u(0.08, 0.2) * s["tau"], "omega_s": u(0.02, 0.06) * s["w0"]},
        "drag_asymmetry": lambda: {"dc_tau": sign * u(0.2, 0.5) * t.c_tau},
        "thrust_asymmetry": lambda: {"dc_f": sign * u(0.2, 0.5) * t.c_f},
        "force_offset": lambda: {"f0": sign * u(0.03, 0.1) * s["F"]},
        "voltage_deadband": lambda: {"v_db": u(0.04, 0.1) * s["v"]},
        "brush_drop": lambda: {"v_b": u(0.03, 0.08) * s["v"]},
        "current_offset": lambda: {"i0": sign * u(0.03, 0.1) * s["i"]},
        "input_delay": lambda: {"delay": u(4.0, 10.0) * dt},
        "thrust_lag": lambda: {"tau": max(u(0.02, 0.08), 4 * dt)},
        "cogging": lambda: {"amplitude": u(0.05, 0.15) * s["tau"], "periods": float(rng.integers(1, 65)),
                            "phase": u(0, 2 * math.pi)},
    }[name]()


def draw_shape(name: str, p: dict[str, float], rng: np.random.Generator) -> dict[str, float]:
    """Effect ``name``'s parameters ``p`` with a shape the identifier's catalogue does not have (``shapes=True``
    cases): Stribeck friction decaying as ``exp(-|w / omega_s|^delta)``, ``delta`` 0.5-2 (the catalogue: 2), and
    a ripple with harmonics at two and three times its count (0.1-0.5 and 0-0.25 of its amplitude; the catalogue:
    a pure sine). Other effects unchanged."""
    if name == "stribeck":
        return {**p, "delta": rng.uniform(0.5, 2.0)}
    if name == "cogging":
        return {**p, "h2": rng.uniform(0.1, 0.5), "phase2": rng.uniform(0, 2 * math.pi),
                "h3": rng.uniform(0.0, 0.25), "phase3": rng.uniform(0, 2 * math.pi)}
    return p


def _scale(name: str, p: dict[str, float], f: float) -> dict[str, float]:
    keys = {"stribeck": ("tau_s",), "cogging": ("amplitude",), "input_delay": ("delay",), "thrust_lag": ("tau",)}
    return {k: v * f if k in keys.get(name, (next(iter(p)),)) else v for k, v in p.items()}


def _nominal(t: Truth, errors: dict[str, float]) -> dict[str, float]:
    """What the user believes: true = nominal (1 + e) for each wrong constant."""
    val = {c: getattr(t, c) / (1.0 + errors.get(c, 0.0)) for c in CONSTANTS}
    return {"J": val["J"], "B": val["B"], "c_tau": val["c_tau"], "c_f": val["c_f"], "k_t": val["k"], "k_e": val["k"],
            "R": val["R"], "L": val["L"]}


def _lag(t: Truth, lg: Logger) -> float:
    return lg.skew * lg.dt + t.e("input_delay", "delay")


def _substeps(t: Truth, lg: Logger, tau_m: float) -> int:
    h = min(tau_m / 150.0, 5e-4, t.e("thrust_lag", "tau", 1.0) / 20.0)
    if "cogging" in t.effects:
        top = t.e("cogging", "periods") * (3 if t.e("cogging", "h3") else 2 if t.e("cogging", "h2") else 1)
        h = min(h, max(0.25 / (top * 0.3 * t.v_max / t.k), 2e-5))
    return max(4, math.ceil(lg.dt / h))


def _replay(x: Truth, cmds: np.ndarray, lg: Logger, tau_m: float) -> np.ndarray:
    return run(x, lambda k, _s: float(cmds[k]), cmds.size, lg.dt, _lag(x, lg), _substeps(x, lg, tau_m))[0]


def replay(case: Case, cmds: np.ndarray, rng: np.random.Generator, **change: Any) -> dict[str, np.ndarray]:
    """Log columns of ``case``'s rig, with ``change`` (:class:`.physics.Truth` fields), recorded by its logger under
    the commands ``cmds`` (N,) [V] from rest (e.g. a log's commands rectified to one sign: a rotor turning one way)."""
    truth = replace(case.truth, **change)
    return record(case.logger, _replay(truth, cmds, case.logger, case.meta["tau_m"]), cmds, rng)


def _visible(a: Truth, b: Truth, cmds: np.ndarray, lg: Logger, tau_m: float, sig: np.ndarray) -> bool:
    """Whether replaying ``cmds`` on ``a`` and ``b`` gives logs differing by >= VISIBLE noise levels ``sig`` (3,):
    the channels as logged (:func:`logged`: an encoder's speed, the filtered current), not the rig's instants."""
    outs = [logged(lg, _replay(x, cmds, lg, tau_m)) for x in (a, b)]
    d = np.sqrt(np.mean((outs[0] - outs[1]) ** 2, axis=1)) / sig
    return bool(np.max(d) >= VISIBLE)


def _kind(rng: np.random.Generator) -> str:
    return str(rng.choice(["clean", "one", "one", "one", "two", "two", "constant", "constant+one"]))


def make_case(seed: int, kind: str | None = None, shapes: bool = False) -> Case:
    """Case number ``seed`` (deterministic). ``kind``: clean, one, two, constant, constant+one (random if None).
    ``shapes``: Stribeck friction and ripples shaped unlike the catalogue's (:func:`draw_shape`, from a stream of
    their own: the rig, logger and excitation are drawn as without, unless a visibility redraw intervenes).

    A draw whose discrepancy cannot be made visible is replaced by the next draw of the same seed, with the
    same kind, effects and wrong constant (rig, logger, excitation and sizes drawn anew)."""
    labels: tuple[list[str], str | None] | None = None
    for attempt in range(MAX_ATTEMPTS):
        rng = np.random.default_rng(seed if attempt == 0 else [seed, attempt])
        shape = np.random.default_rng([seed, attempt, 1299709]) if shapes else None
        case, kind, labels = _attempt(seed, rng, kind, labels, shape)
        if case is not None:
            return case
    raise RuntimeError(f"proving-ground seed {seed}: no visible draw in {MAX_ATTEMPTS} attempts")


Labels = tuple[list[str], str | None]  # the hidden effects, the wrong constant


def hidden(seed: int, kind: str | None = None) -> Labels:
    """The hidden effects and the wrong constant of ``make_case(seed, kind)`` (of its first draw, which a redraw
    keeps), without generating the log."""
    return _head(np.random.default_rng(seed), kind)[5:]


def _head(rng: np.random.Generator, kind: str | None
          ) -> tuple[Truth, float, dict[str, float], Logger, str, list[str], str | None]:
    """The first draws of an attempt: rig (and its time constant, scales), logger, kind, effects, wrong constant."""
    truth, tau_m = draw_motor(rng)
    sc = _scales(truth)
    lg = draw_logger(rng, tau_m, sc["w0"], sc["i"], sc["F"], truth.v_max)
    kind = kind or _kind(rng)
    n_eff = {"clean": 0, "one": 1, "two": 2, "constant": 0, "constant+one": 1}[kind]
    drawn = [str(x) for x in rng.choice(EFFECTS, size=n_eff, replace=False)]
    const = str(rng.choice(CONSTANTS)) if kind.startswith("constant") else None
    return truth, tau_m, sc, lg, kind, drawn, const


def _attempt(seed: int, rng: np.random.Generator, kind: str | None, labels: Labels | None,
             shape: np.random.Generator | None = None) -> tuple[Case | None, str, Labels]:
    """One draw of case ``seed`` from ``rng`` (its kind and labels when not given), with its kind and labels;
    no case when a drawn discrepancy stays invisible (module doc). ``shape``: effects reshaped (:func:`draw_shape`)
    from this stream."""
    truth, tau_m, sc, lg, kind, drawn, const = _head(rng, kind)
    names, const = (drawn, const) if labels is None else labels
    errors: dict[str, float] = {}
    if const is not None:
        errors[const] = float(rng.choice([-1.0, 1.0]) * rng.uniform(0.05, 0.5))
    truth.effects = {nm: draw_effect(nm, truth, lg.dt, rng) for nm in names}
    if shape is not None:
        truth.effects = {nm: draw_shape(nm, p, shape) for nm, p in truth.effects.items()}
    nominal = _nominal(truth, errors)
    exc = _excitations(rng)
    seconds = min(max(80 * tau_m, 3.0), 15.0) * len(exc)
    n = int(min(seconds * lg.rate, MAX_SAMPLES))
    cmds = _commands(exc, n, lg, truth, nominal, tau_m, rng)
    _, cmds = run(truth, _closed(cmds, exc, n, lg, nominal, truth, tau_m, np.random.default_rng(seed + 1)), n,
                  lg.dt, _lag(truth, lg), _substeps(truth, lg, tau_m))  # the commands issued, for the replays
    sig = noise_levels(lg)
    for nm in names:  # each hidden effect must show in the log: doubled up to twice, else the draw is replaced
        for doubling in range(3):
            if _shows(truth, nm, cmds, lg, tau_m, sig):
                break
            if doubling == 2:
                return None, kind, (names, const)
            truth.effects[nm] = _scale(nm, truth.effects[nm], 2.0)
    for c, e in list(errors.items()):  # the wrong constant too (else it is a calibration detail): at most 50 %
        if abs(e) > TOLERANCE and not _believed(truth, c, e, cmds, lg, tau_m, sig):
            errors[c] = float(np.sign(e) * 0.5)
            nominal = _nominal(truth, errors)
            if not _believed(truth, c, errors[c], cmds, lg, tau_m, sig):
                return None, kind, (names, const)
    truth_log, issued = run(truth, _closed(cmds, exc, n, lg, nominal, truth, tau_m, rng), n, lg.dt,
                            _lag(truth, lg), _substeps(truth, lg, tau_m))
    # the criterion once more, under the commands the log really holds (its PI loops saw other noise)
    if not (all(_shows(truth, nm, issued, lg, tau_m, sig) for nm in names)
            and all(_believed(truth, c, e, issued, lg, tau_m, sig) for c, e in errors.items() if abs(e) > TOLERANCE)):
        return None, kind, (names, const)
    cols = record(lg, truth_log, issued, rng)
    expected = frozenset(names) | {f"param:{c}" for c, e in errors.items() if abs(e) > TOLERANCE}
    return Case(seed, kind, cols, nominal, expected, truth, lg, tuple(exc), errors,
                {"tau_m": tau_m, "n": n, "power_w": sc["tau"] * sc["w0"] * 0.7}), kind, (names, const)


def _believed(truth: Truth, c: str, e: float, cmds: np.ndarray, lg: Logger, tau_m: float, sig: np.ndarray) -> bool:
    """Whether constant ``c`` believed off by ``e`` (true = believed (1 + e)) is visible under ``cmds``."""
    return _visible(truth, replace(truth, **{c: getattr(truth, c) / (1.0 + e)}), cmds, lg, tau_m, sig)


def _shows(truth: Truth, name: str, cmds: np.ndarray, lg: Logger, tau_m: float, sig: np.ndarray) -> bool:
    """Whether effect ``name`` of ``truth`` is visible under ``cmds`` (:func:`_visible` without it)."""
    return _visible(truth, replace(truth, effects={k: v for k, v in truth.effects.items() if k != name}),
                    cmds, lg, tau_m, sig)


def _excitations(rng: np.random.Generator) -> list[str]:
    pool = [*OPEN_LOOP, "pi", "pi"]
    return [str(x) for x in rng.choice(pool, size=int(rng.integers(1, 4)), replace=False)]


def _commands(exc: list[str], n: int, lg: Logger, truth: Truth, nominal: dict[str, float], tau_m: float,
              rng: np.random.Generator) -> np.ndarray:
    """The open-loop parts' commands (n,) [V] (closed-loop parts: zeros, filled during the run)."""
    bounds = np.linspace(0, n, len(exc) + 1).astype(int)
    out = np.zeros(n)
    for kind, a, b in zip(exc, bounds[:-1], bounds[1:], strict=True):
        if kind != "pi":
            out[a:b] = open_loop(kind, b - a, lg.dt, truth.v_max, tau_m, rng)
    return np.round(out / lg.q_v) * lg.q_v


def _closed(cmds: np.ndarray, exc: list[str], n: int, lg: Logger, nominal: dict[str, float], truth: Truth,
            tau_m: float, rng: np.random.Generator) -> Callable[[int, np.ndarray], float]:
    """Command function of the whole run: the open-loop commands, PI loops in the closed-loop parts."""
    bounds = np.linspace(0, n, len(exc) + 1).astype(int)
    loops = {int(a): pi_loop(n, lg.dt, nominal, truth.v_max, tau_m, rng, lg.speed_noise())
             for kind, a in zip(exc, bounds[:-1], strict=True) if kind == "pi"}
    part = np.searchsorted(bounds[1:], np.arange(n), side="right")

    def command(k: int, sensed: np.ndarray) -> float:
        a = int(bounds[part[k]])
        if a in loops:
            return float(np.round(loops[a](k - a, sensed) / lg.q_v) * lg.q_v)
        return float(cmds[k])

    return command
