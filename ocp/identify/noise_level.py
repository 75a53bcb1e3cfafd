"""The white-noise level of a sampled channel: the one estimate every noise unit of the model check is read in.

A smooth signal's second differences are small beside white noise's, whose ``d2 y = e_{k+2} - 2 e_{k+1} + e_k`` has
standard deviation ``sqrt(6) sigma``; the median absolute deviation (times 1.4826, a Gaussian's MAD to its standard
deviation) leaves the signal's curvature and outliers out. Biased high where the curvature is not small beside the
noise (a slowly logged, finely resolved speed: ``docs/model-check-history.md``, session 58) and zero on a quantized
channel whose second differences are mostly zero, where a sensor's level is their RMS (:func:`sensor_noise`).
"""

from __future__ import annotations

import math

import numpy as np


def white_noise(y: np.ndarray) -> float:
    """Per-sample white noise [``y``'s unit] of the samples ``y`` (N,) from their second differences' MAD /
    sqrt(6); 0 for fewer than three samples."""
    return _mad(np.diff(y, 2)) / math.sqrt(6.0)


def _mad(d: np.ndarray) -> float:
    """A Gaussian's standard deviation from the median absolute deviation of ``d`` (M,); 0 for none."""
    return float(1.4826 * np.median(np.abs(d - np.median(d)))) if d.size else 0.0


#: a MAD of second differences under this share of their RMS is a quantized sensor's whose samples mostly repeat
#: (:func:`sensor_noise`)
DEGENERATE = 1e-6


def sensor_noise(y: np.ndarray) -> float:
    """:func:`white_noise` of a sensor's samples ``y`` (N,), or their second differences' RMS / sqrt(6) where most of
    those are equal (the MAD under :data:`DEGENERATE` of the RMS): a quantized sensor whose reading steps now and then
    (a fast encoder's differenced speed on a slow rotor) reads zero by the MAD, and every misfit of that channel would
    then count as beyond its noise. The RMS counts the steps, which are its rounding."""
    d2 = np.diff(y, 2)
    mad, rms = _mad(d2), float(np.sqrt(np.mean(d2 * d2))) if d2.size else 0.0
    return (mad if mad > DEGENERATE * rms else rms) / math.sqrt(6.0)


def floored_noise(y: np.ndarray) -> float:
    """:func:`white_noise` of a time series ``y`` (N,) floored at 1e-3 of its RMS (a quantized or noise-free channel
    reads 0) and at 1e-12: an equation's noise level (:func:`ocp.identify.equations.noise`)."""
    return max(white_noise(y), 1e-3 * float(np.sqrt(np.mean(y * y))), 1e-12)
