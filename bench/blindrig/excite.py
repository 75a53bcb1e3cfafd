"""Excitations: open-loop voltage commands and closed-loop speed references on the nominal sample grid.

Every excitation returns an :class:`Excitation` holding, per logged row, whether the speed controller is in
charge (``closed``), the open-loop command [V] and the speed reference [rad/s].
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

OPEN_KINDS = ("chirp", "steps", "prbs", "ramp")
CLOSED_KINDS = ("pi_sine", "pi_steps", "pi_random")
KINDS = (*CLOSED_KINDS, *OPEN_KINDS, "mix")
KIND_WEIGHTS = (0.14, 0.14, 0.10, 0.12, 0.12, 0.12, 0.12, 0.14)


@dataclass
class Excitation:
    """An excitation on n rows.

    Attributes:
        kind: excitation kind (one of KINDS); parts: kinds of the segments (mix) or [kind].
        closed: per row, True where the PI speed controller computes the command.
        cmd: per row open-loop command [V] (ignored where closed).
        ref: per row speed reference [rad/s] (ignored where open).
        reverses: whether the intended excitation takes the rotor through zero speed both ways.
        info: drawn settings (amplitudes [V or rad/s], periods [s], ...).
    """

    kind: str
    parts: list[str]
    closed: np.ndarray
    cmd: np.ndarray
    ref: np.ndarray
    reverses: bool
    info: dict = field(default_factory=dict)


def _hold_levels(rng: np.random.Generator, t: np.ndarray, hold: tuple[float, float], lo: float, hi: float,
                 reverses: bool, sign: float, ramp_frac: float = 0.0) -> np.ndarray:
    """Piecewise-constant random levels (with optional linear transitions) on times t [s].

    Levels are drawn in [-hi, -lo] U [lo, hi] alternating in sign when ``reverses`` (so every step is a
    reversal at least half of the time), else in sign * [lo, hi].
    """
    edges = [t[0]]
    while edges[-1] < t[-1]:
        edges.append(edges[-1] + rng.uniform(*hold))
    n_lev = len(edges)
    mags = rng.uniform(lo, hi, n_lev)
    if reverses:
        signs = np.where(rng.random(n_lev) < 0.7, -1.0, 1.0)
        signs = np.cumprod(signs) * sign
    else:
        signs = np.full(n_lev, sign)
    lev = mags * signs
    lev[0] = 0.0 if rng.random() < 0.5 else lev[0]
    idx = np.searchsorted(np.asarray(edges), t, side="right") - 1
    out = lev[idx]
    if ramp_frac > 0.0:  # linear transitions of ramp_frac of each hold, starting at the edge
        e = np.asarray(edges)
        start = e[idx]
        dur = np.maximum(ramp_frac * (np.append(e[1:], e[-1] + hold[1])[idx] - start), 1e-9)
        prev = np.where(idx > 0, lev[np.maximum(idx - 1, 0)], 0.0)
        frac = np.clip((t - start) / dur, 0.0, 1.0)
        out = prev + (out - prev) * frac
    return out


def _open(rng: np.random.Generator, kind: str, t: np.ndarray, dt: float, Vs: float, tau: float,
          reverses: bool, info: dict) -> np.ndarray:
    """Open-loop command [V] of one kind on times t [s]; Vs supply [V], tau mechanical time [s]."""
    sign = float(rng.choice([-1.0, 1.0]))
    T = t[-1] - t[0] + dt
    if kind == "chirp":
        amp = rng.uniform(0.3, 0.9) * Vs
        f0 = rng.uniform(0.05, 0.3)
        f1 = float(np.clip(rng.uniform(0.5, 3.0) / (2 * np.pi * tau), 2 * f0, 0.1 / dt))
        ph = 2 * np.pi * f0 * T / np.log(f1 / f0) * (np.exp(np.log(f1 / f0) * (t - t[0]) / T) - 1.0)
        off = 0.0 if reverses else sign * rng.uniform(1.02, 1.2) * amp * 0.5
        amp = amp if reverses else amp * 0.5
        info.update(chirp_amp_V=amp, chirp_f0_Hz=f0, chirp_f1_Hz=f1, offset_V=off)
        return off + amp * np.sin(ph)
    if kind == "steps":
        hold = (max(3 * tau, 0.15, 4 * dt), max(6 * tau, 1.5, 8 * dt))
        info.update(hold_s=hold)
        return _hold_levels(rng, t, hold, 0.15 * Vs, 0.9 * Vs, reverses, sign) if reverses else \
            _hold_levels(rng, t, hold, 0.25 * Vs, 0.9 * Vs, False, sign)
    if kind == "prbs":
        bit = float(np.clip(rng.uniform(1.0, 4.0) * tau, 2 * dt, 0.5))
        n_bits = int(np.ceil(T / bit)) + 1
        bits = rng.integers(0, 2, n_bits) * 2.0 - 1.0
        amp = rng.uniform(0.4, 0.9) * Vs
        idx = np.minimum(((t - t[0]) / bit).astype(int), n_bits - 1)
        if reverses:
            off = rng.uniform(-0.1, 0.1) * Vs
            out = off + amp * bits[idx]
        else:
            mid = sign * rng.uniform(0.45, 0.6) * Vs
            out = mid + 0.35 * Vs * bits[idx]
            off = mid
        info.update(prbs_bit_s=bit, prbs_amp_V=amp, offset_V=off)
        return np.clip(out, -Vs, Vs)
    if kind == "ramp":
        per = T / rng.uniform(1.0, 3.0)
        amp = rng.uniform(0.5, 0.95) * Vs
        tri = 2.0 * np.abs(2.0 * (((t - t[0]) / per + 0.25) % 1.0) - 1.0) - 1.0
        if reverses:
            out = amp * tri * sign
        else:
            out = sign * (0.5 * Vs + 0.4 * Vs * tri)
        info.update(ramp_period_s=per, ramp_amp_V=amp)
        return out
    raise ValueError(kind)


def _closed(rng: np.random.Generator, kind: str, t: np.ndarray, dt: float, w_top: float, tau: float,
            reverses: bool, info: dict) -> np.ndarray:
    """Speed reference [rad/s] of one closed-loop kind on times t [s]; w_top top speed [rad/s]."""
    sign = float(rng.choice([-1.0, 1.0]))
    T = t[-1] - t[0] + dt
    if kind == "pi_sine":
        per = float(np.clip(rng.uniform(0.5, 4.0), 20 * tau, max(T / 1.5, 20 * tau)))
        a = rng.uniform(0.3, 0.8) * w_top
        if reverses:
            off = rng.uniform(-0.1, 0.1) * a
        else:
            a = rng.uniform(0.15, 0.35) * w_top
            off = sign * (a + rng.uniform(0.1, 0.4) * w_top)
        info.update(sine_period_s=per, sine_amp=a, sine_offset=off)
        return off + a * np.sin(2 * np.pi * (t - t[0]) / per)
    hold = (max(5 * tau, 0.2, 4 * dt), max(10 * tau, 1.5, 8 * dt))
    info.update(hold_s=hold)
    ramp = 0.0 if kind == "pi_steps" else rng.uniform(0.2, 0.8)
    return _hold_levels(rng, t, hold, (0.1 if reverses else 0.2) * w_top, 0.85 * w_top, reverses, sign, ramp)


def make_excitation(rng: np.random.Generator, n: int, dt: float, Vs: float, w_top: float, tau: float,
                    reverses: bool, kind: str | None = None) -> Excitation:
    """Draw an excitation of n rows at period dt [s] for supply Vs [V], top speed w_top [rad/s] and
    mechanical time tau [s]; ``kind`` None draws one from KINDS."""
    if kind is None:
        kind = str(rng.choice(KINDS, p=np.asarray(KIND_WEIGHTS) / sum(KIND_WEIGHTS)))
    t = np.arange(n) * dt
    parts = [kind]
    if kind == "mix":
        parts = [str(x) for x in rng.choice(OPEN_KINDS + CLOSED_KINDS, 2, replace=False)]
    closed = np.zeros(n, dtype=bool)
    cmd = np.zeros(n)
    ref = np.zeros(n)
    cuts = np.linspace(0, n, len(parts) + 1).astype(int)
    info: dict = {}
    for j, part in enumerate(parts):
        sl = slice(cuts[j], cuts[j + 1])
        sub: dict = {}
        if part in CLOSED_KINDS:
            closed[sl] = True
            ref[sl] = _closed(rng, part, t[sl], dt, w_top, tau, reverses, sub)
        else:
            cmd[sl] = _open(rng, part, t[sl], dt, Vs, tau, reverses, sub)
        info[f"part{j}_{part}"] = sub
    return Excitation(kind, parts, closed, np.clip(cmd, -Vs, Vs), ref, reverses, info)
