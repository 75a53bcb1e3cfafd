"""Which constants a log's sampling resolves: a time constant under two samples is within a row, and the log cannot
tell an error of the constant that sets it from the loggers' own timing (a current filter, a sub-sample command
skew, an encoder's differencing window). Such a constant is calibrated as a free nuisance and never named
(:attr:`.regression.Design.unresolved`, :mod:`.select`).
"""

from __future__ import annotations

import numpy as np

from ocp.logs import Log, LogKind
from ocp.model.params import MotorParams

#: the fewest samples per L/R that resolve ``L`` (:func:`unresolved`), and those advised (:func:`advised_rate`): rigs at
#: 0.01-1.9 samples re-logged under voltage steps had an ``L`` error named in 26 and 36 of 41 (bench/logging_rate.py)
ARMATURE_SAMPLES, ADVISED_SAMPLES = 2.0, 4.0
#: the fewest samples per rotor time constant (:func:`rotor_tau`) that resolve ``J``: the armature's rule (the blind
#: rig, ``bench/blind_check.py``, has rotors under two samples that the proving ground hardly draws: a clean 500 Hz
#: log of a 3.97 ms rotor, 1.98 samples, came back with ``J`` 53 % low; the proving ground's 1,000 logs hold two,
#: 190 and 30068, neither with ``J`` wrong)
ROTOR_SAMPLES = ARMATURE_SAMPLES


def rotor_tau(p: MotorParams, w: np.ndarray) -> float:
    """Rotor time constant [s] at the logged speeds ``w`` (N,) [rad/s]: ``J / (k_t k_e / R + B + 2 c_tau rms(w))``
    (nominal)."""
    rms = float(np.sqrt(np.mean(w * w))) if w.size else 0.0
    return p.J / (p.k_t * p.k_e / p.R + p.B + 2.0 * p.c_tau * rms)


def unresolved(p: MotorParams, log: Log) -> dict[str, str]:
    """Constants this log cannot resolve from logger artefacts, with the reason: the inductance when the
    electrical time constant L/R is under two samples (a current filter or a fraction of a sample of
    command timing then looks the same), the inertia when the rotor's is (module doc)."""
    out = {}
    tau = rotor_tau(p, log.omega) if log.kind is LogKind.TIME_SERIES else np.inf
    if tau < ROTOR_SAMPLES * log.dt:
        out["J"] = (f"the rotor's time constant ({1e3 * tau:.3g} ms at these speeds) is under two samples "
                    f"({1e3 * ROTOR_SAMPLES * log.dt:.3g} ms): the log cannot tell an inertia error from the timing of "
                    f"its current and speed sensors; logged at {ADVISED_SAMPLES / tau / 1e3:.3g} kHz or faster it can")
    if log.kind is LogKind.STEADY_STATE or slow_armature(p, log.dt):
        out["L"] = (f"L/R = {1e3 * p.L / p.R:.3g} ms is under two samples ({1e3 * ARMATURE_SAMPLES * log.dt:.3g} ms): "
                    "the log cannot tell an inductance error from current filtering or sub-sample command timing; "
                    f"logged at {advised_rate(p) / 1e3:.3g} kHz or faster (voltage steps, any excitation) it can")
    return out


def slow_armature(p: MotorParams, dt: float) -> bool:
    """Whether samples ``dt`` [s] apart are too few per electrical time constant L/R to resolve ``L``."""
    return p.L / p.R < ARMATURE_SAMPLES * dt


def advised_rate(p: MotorParams) -> float:
    """The logging rate [Hz] that checks ``L``: :data:`ADVISED_SAMPLES` samples per electrical time constant L/R."""
    return ADVISED_SAMPLES * p.R / p.L
