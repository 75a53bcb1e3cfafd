"""Separating rival explanations: simulate each under a command, and how far apart they stay in noise units.

The criterion of :mod:`.design` (T-optimal discrimination, Atkinson & Fedorov 1975, linearised): for rivals a, b
with outputs ``y`` (omega [rad/s], current [A], thrust [N]) weighted by the log's noise ``sigma``, the difference
``d = (y_a - y_b) / sigma`` over the samples a logger at the log's rate would take, minus what ``b`` explains by
refitting (its own items freely, every other constant within about the tolerance: a Gaussian prior), is the
separation ``z`` [noise standard deviations]; the smaller of the two directions counts. Arrays (N,) in SI.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np
from scipy.special import ndtr

from ocp.identify.predict import CHANNELS, free_run
from ocp.logs import log_from_arrays
from ocp.model.effects import CATALOGUE, load_plant, plant_to_mapping
from ocp.model.plant import DCMotorPlant

#: relative constants a rival may move to explain a difference (k: k_t and k_e together)
CONSTANTS: dict[str, tuple[str, ...]] = {"J": ("J",), "B": ("B",), "c_tau": ("c_tau",), "c_f": ("c_f",),
                                         "k": ("k_t", "k_e"), "R": ("R",)}
MAX_SIM_SAMPLES = 6000  # rivals are simulated on at most this many samples (z is scaled to the log's rate)


@dataclass(frozen=True)
class Rival:
    """One explanation: its items (effects and ``param:<key>``) and its plant."""

    name: str
    items: tuple[str, ...]
    plant: DCMotorPlant


def confusion(z: float) -> float:
    """Misclassification probability of the likelihood-ratio test between two Gaussian hypotheses ``z``
    noise standard deviations apart (equal priors): ``Phi(-z/2)``."""
    return float(ndtr(-z / 2.0))


def with_effect(plant: DCMotorPlant, name: str, values: dict[str, float]) -> DCMotorPlant:
    data = plant_to_mapping(plant)
    data["effects"] = {**data["effects"], name: values}
    return load_plant(data)


def with_constant(plant: DCMotorPlant, const: str, rel: float) -> DCMotorPlant:
    data = plant_to_mapping(plant)
    for key in CONSTANTS[const]:
        data[key] = float(data[key]) * (1.0 + rel)
    return load_plant(data)


def simulate(plant: DCMotorPlant, t: np.ndarray, voltage: np.ndarray, x0: tuple[float, float] = (0.0, 0.0)
             ) -> np.ndarray:
    """Outputs (3, N) -- omega [rad/s], current [A], thrust [N] -- of ``plant`` from ``x0`` (speed [rad/s],
    current [A]; default rest) under the held ``voltage`` (N,) on the uniform grid ``t`` (N,)."""
    n = t.size
    zeros = np.zeros(n)
    w, i = zeros.copy(), zeros.copy()
    w[0], i[0] = x0
    log = log_from_arrays(t, voltage, i, zeros, omega=w, source="design")
    fr = free_run(plant, log, segment_s=n * (t[1] - t[0]))
    y = np.zeros((3, n))
    for k, ch in enumerate(CHANNELS):
        y[k, fr.idx] = fr.channel(ch)
    return y


def sensitivities(rival: Rival, t: np.ndarray, voltage: np.ndarray, y0: np.ndarray, sigma: np.ndarray,
                  tolerance: float, x0: tuple[float, float]) -> tuple[np.ndarray, np.ndarray]:
    """Weighted output sensitivities (3N, P) of a rival to its effects' fitted parameters and the relative
    constants (forward differences, 1e-3 relative steps), and each column's prior weight (P,): 0 for the
    rival's own items (free), ``1 / tolerance`` for the other constants (calibration moves them by about the
    tolerance, as in :func:`ocp.identify.diagnose`)."""
    plant = rival.plant
    cols, weights = [], []
    for const in CONSTANTS:
        if float(getattr(plant.params, CONSTANTS[const][0])) != 0.0:
            cols.append((simulate(with_constant(plant, const, 1e-3), t, voltage, x0) - y0) / 1e-3)
            weights.append(0.0 if f"param:{const}" in rival.items else 1.0 / tolerance)
    data = plant_to_mapping(plant)
    for eff in plant.effects:
        for key in getattr(CATALOGUE.get(eff.name), "fitted", ()):
            value = float(data["effects"][eff.name][key])
            if value == 0.0:
                continue
            moved = with_effect(plant, eff.name, {**data["effects"][eff.name], key: value * (1 + 1e-3)})
            cols.append((simulate(moved, t, voltage, x0) - y0) / 1e-3)  # per relative change of the parameter
            weights.append(0.0 if eff.name in rival.items else 1.0 / tolerance)
    if not cols:
        return np.zeros((y0.size, 0)), np.zeros(0)
    return np.column_stack([(c / sigma[:, None]).ravel() for c in cols]), np.array(weights)


def _left(d: np.ndarray, s: np.ndarray, w: np.ndarray) -> float:
    """What a rival cannot explain of the weighted difference ``d`` (M,): ``min_x |d - s x|^2 + |w x|^2``
    over relative parameter changes ``x`` (P,), ``s`` (M, P) its sensitivities, ``w`` (P,) the prior weights;
    returns the square root of the minimum."""
    if s.shape[1] == 0:
        return float(np.linalg.norm(d))
    a = np.vstack([s, np.diag(w)])
    b = np.concatenate([d, np.zeros(w.size)])
    x, *_ = np.linalg.lstsq(a, b, rcond=1e-12)
    return float(np.linalg.norm(b - a @ x))


def _nested_left(ra: Rival, rb: Rival, d: np.ndarray, sa: tuple[np.ndarray, np.ndarray],
                 sb: tuple[np.ndarray, np.ndarray]) -> float:
    """What the rival that is refitted cannot explain of ``d = (y_a - y_b) / sigma``: the smaller of both
    directions, except for nested rivals (one's items within the other's, e.g. a plant and the same plant
    with a probe effect), where only the larger one can be the truth to reveal (the larger one explains the
    smaller by switching its extra effect off)."""
    ia, ib = set(ra.items), set(rb.items)
    if ia < ib:  # b true, a refits
        return _left(-d, *sa)
    if ib < ia:
        return _left(d, *sb)
    return min(_left(d, *sb), _left(-d, *sa))


def pair_separations(rivals: list[Rival], t: np.ndarray, voltage: np.ndarray, sigma: np.ndarray, rate: float,
                     tolerance: float | None, x0: tuple[float, float] = (0.0, 0.0), detect: bool = False
                     ) -> tuple[dict[str, float], dict[str, float]]:
    """Separation z per rival pair (module doc) and the RMS difference / noise, on a logger at ``rate`` [Hz].
    ``detect``: only the first rival against each other one (would each probe effect show?), not every pair."""
    dt = float(t[-1] - t[0]) / (t.size - 1)
    scale = math.sqrt(max(dt * rate, 1e-12))  # samples of the logger per simulated sample
    ys = [simulate(r.plant, t, voltage, x0) for r in rivals]
    sens = [sensitivities(r, t, voltage, y, sigma, tolerance, x0) if tolerance else None
            for r, y in zip(rivals, ys, strict=True)]
    z, rms = {}, {}
    pairs = [((0, rivals[0]), (k, r)) for k, r in enumerate(rivals) if k] if detect else \
        itertools.combinations(enumerate(rivals), 2)
    for (a, ra), (b, rb) in pairs:
        d = ((ys[a] - ys[b]) / sigma[:, None]).ravel()
        key = f"{ra.name} vs {rb.name}"
        rms[key] = float(np.sqrt(np.mean(d * d)))
        sa, sb = sens[a], sens[b]
        left = float(np.linalg.norm(d)) if sa is None or sb is None else _nested_left(ra, rb, d, sa, sb)
        z[key] = left * scale
    return z, rms


def held_on_grid(t: np.ndarray, v: np.ndarray, dt_log: float) -> tuple[np.ndarray, np.ndarray]:
    """The command resampled (held) on the simulation grid: the log's step, at most MAX_SIM_SAMPLES."""
    dt = max(dt_log, float(t[-1] - t[0]) / (MAX_SIM_SAMPLES - 1))
    grid = np.arange(t[0], t[-1] + 0.5 * dt, dt)
    idx = np.clip(np.searchsorted(t, grid, side="right") - 1, 0, t.size - 1)
    return grid - grid[0], np.asarray(v, float)[idx]
