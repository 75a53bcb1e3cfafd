"""How many independent rows a mean square over correlated rows is worth, measured from the noise itself.

The held-out score is a root mean square over rows that are not independent (low-passed channels, the
torque rows' speed view). For a zero-mean Gaussian sequence with autocorrelation ``rho_k`` the mean of
squares over ``n`` rows has relative variance ``(2 / n) sum_k rho_k^2`` (all lags, both signs), so it is
worth ``n / sum_k rho_k^2`` independent rows. :func:`independence` measures ``rho_k`` on the rows the
richest fit leaves (the noise, :func:`ocp.identify.regression.build`) instead of assuming a correlation
time from the filters: a noise dominated by a differentiated speed stays independent after the speed
view, a current noise does not. An unexplained signal ``s`` adds a cross term ``2 s eps`` to each square,
whose worth depends on ``sum_k |rho_k|`` instead (:func:`independence`).
"""

from __future__ import annotations

import numpy as np


def _autocorrelation(x: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """Autocorrelation ``rho_k`` (N,) of ``x`` (N,) over the rows in ``mask`` (N,): each lag's mean product
    over the pairs of rows that both lie in ``mask``, divided by the mean square (lag 0)."""
    n = x.size
    y = np.where(mask, x - x[mask].mean(), 0.0)
    m = mask.astype(float)
    acf = np.fft.irfft(np.abs(np.fft.rfft(y, 2 * n)) ** 2)[:n]
    pairs = np.rint(np.fft.irfft(np.abs(np.fft.rfft(m, 2 * n)) ** 2)[:n])
    with np.errstate(invalid="ignore", divide="ignore"):
        per = np.where(pairs > 0, acf / np.maximum(pairs, 1.0), 0.0)
    return per / per[0] if per[0] > 0 else np.zeros(n)


def independence(resid: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """(2, E) fractions of independent rows per equation of the residuals ``resid`` (E, N) over the rows in
    ``mask`` (N,): row 0 for a mean of squares of the noise, ``1 / sum_k rho_k^2`` (module doc); row 1 for its
    cross term with an unexplained signal ``s``, ``var sum s eps <= n S sum_k |rho_k|`` whatever the shape of
    ``s``, so ``1 / sum_k |rho_k|``. The sums run over the lags until ``rho_k`` first falls inside its own
    two-standard-error band ``2 / sqrt(n)`` (beyond that it cannot be told from zero)."""
    n = int(mask.sum())
    out = np.ones((2, resid.shape[0]))
    if n < 8:
        return out
    band = 2.0 / np.sqrt(n)
    for e, r in enumerate(resid):
        rho = _autocorrelation(r, mask)
        small = np.flatnonzero(np.abs(rho[1:]) < band)
        lags = rho[1:int(small[0]) + 1 if small.size else rho.size]
        for row, total in enumerate((1.0 + 2.0 * float(np.sum(lags**2)), 1.0 + 2.0 * float(np.sum(np.abs(lags))))):
            out[row, e] = min(1.0, max(1.0 / total, 1.0 / n))
    return out
