"""Linear recursive filters of low order along the first axis: the IIR recursion as a banded triangular solve.

``sum_k a_k y[n-k] = sum_k b_k x[n-k]`` is, over the whole record, ``A y = B x`` with ``A`` lower triangular and
banded (``a_0`` on the diagonal, ``a_k`` on the k-th subdiagonal): LAPACK's ``dtbtrs`` runs the recursion in compiled
code for every column at once. It replaces ``scipy.signal``'s ``lfilter``/``filtfilt``/``butter`` here because that
namespace (and the ``scipy.stats`` it imports) is ~0.4 s of each CLI start, more than a typical log's filtering
takes; ``scipy.linalg`` is imported anyway. Same arithmetic up to rounding (``tests/test_filters.py`` holds them to
``scipy.signal`` as the oracle).
"""

from __future__ import annotations

import math

import numpy as np
from scipy.linalg import expm
from scipy.linalg.lapack import dtbtrs


def iir(b: np.ndarray | list[float], a: np.ndarray | list[float], x: np.ndarray,
        start: float | np.ndarray | None = None, backward: bool = False, overwrite: bool = False) -> np.ndarray:
    """``x`` (N,) or (N, K) filtered along axis 0 by ``b(z) / a(z)`` (coefficients of ``z^0, z^-1, ...``): from rest
    (``start`` None: every earlier input and output zero), or from the steady state of a constant input ``start``
    (a scalar, or (K,) per column: every earlier input that value, every earlier output its DC gain times it; what
    ``lfilter`` with ``zi = lfilter_zi(b, a) * start`` does). ``backward``: the same filter run from the last row to
    the first (``lfilter`` on ``x[::-1]``, reversed back; ``start`` then stands for the rows after the last), an upper
    triangular solve, no copy reversed. Same shape as ``x``, float (a 2-D result in Fortran order: each column
    contiguous, as the solve leaves it). ``overwrite``: ``x`` may be used as the result's buffer (it is, when it is a
    float array whose columns are contiguous); a numerator tap that is zero adds nothing and is skipped (its
    product's zero could only change the sign of a zero)."""
    den, num = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    m = max(den.size, num.size) - 1
    num, den = np.pad(num / den[0], (0, m + 1 - num.size)), np.pad(den / den[0], (0, m + 1 - den.size))
    y = np.asarray(x, dtype=float)
    flat = np.asfortranarray(y.reshape(y.shape[0], -1))  # (N, K), each column contiguous
    n = flat.shape[0]
    if n == 0:
        return y.copy()
    past_x = np.zeros(flat.shape[1]) if start is None else \
        np.array(np.broadcast_to(np.asarray(start, float), flat.shape[1:]))  # (a copy: x may be overwritten)
    past_y = past_x * (num.sum() / den.sum()) if start is not None else past_x
    if not num[1:].any() and (overwrite or not np.may_share_memory(flat, x)):  # (flat: x's buffer, or a copy made here)
        rhs = flat
        rhs *= num[0]
    else:
        rhs = num[0] * flat
    band = np.zeros((m + 1, n))
    for k in range(1, m + 1):  # row n takes x[n -+ k] and y[n -+ k]; those beyond the record are the start's
        if backward:
            if num[k] != 0.0:
                rhs[:n - k] += num[k] * flat[k:]
            rhs[max(n - k, 0):] += num[k] * past_x - den[k] * past_y
            band[m - k, k:] = den[k]  # (upper band storage: the k-th superdiagonal)
        else:
            if num[k] != 0.0:
                rhs[k:] += num[k] * flat[:n - k]
            rhs[:min(k, n)] += num[k] * past_x - den[k] * past_y
            band[k, :n - k] = den[k]
    out, info = dtbtrs(band, rhs, uplo="U" if backward else "L", diag="U", overwrite_b=1)
    if info != 0:  # (unit diagonal: never singular)
        raise ArithmeticError(f"dtbtrs failed: info {info}")
    return np.asarray(out).reshape(y.shape, order="F") if y.ndim > 1 else np.asarray(out)[:, 0]


def filtfilt(b: np.ndarray | list[float], a: np.ndarray | list[float], x: np.ndarray, padlen: int = 0,
             overwrite: bool = False) -> np.ndarray:
    """``x`` (N,) or (N, K) filtered forward and backward along axis 0 (zero phase, the magnitude squared), as
    ``scipy.signal.filtfilt(b, a, x, axis=0, padtype="odd", padlen=padlen)``: the record extended by ``padlen``
    samples at each end by odd reflection about its end values, each pass started at the steady state of its first
    input, the extension cut off after. (N, K) results are in Fortran order, as :func:`iir` leaves them.
    ``overwrite``: ``x`` may be used as the result's buffer (:func:`iir`)."""
    y = np.asarray(x, dtype=float)
    if padlen > 0:
        if padlen >= y.shape[0]:
            raise ValueError(f"padlen {padlen} must be under the record's length {y.shape[0]}")
        head = 2.0 * y[:1] - y[padlen:0:-1]
        tail = 2.0 * y[-1:] - y[-2:-padlen - 2:-1]
        y = np.concatenate([head, y, tail])
    y = iir(b, a, y, start=y[0], overwrite=overwrite or padlen > 0)  # (padded: a copy made here)
    y = iir(b, a, y, start=y[-1], backward=True, overwrite=True)  # (the forward pass's result: its own buffer)
    return y[padlen:y.shape[0] - padlen]


def butter2(wn: float) -> tuple[np.ndarray, np.ndarray]:
    """Second-order Butterworth low-pass (b (3,), a (3,)) at ``wn`` (0 < wn < 1) of the Nyquist frequency, by the
    bilinear transform with the cut-off prewarped, as ``scipy.signal.butter(2, wn)``."""
    if not 0.0 < wn < 1.0:
        raise ValueError(f"cut-off {wn} must lie in (0, 1) of the Nyquist frequency")
    k = math.tan(math.pi * wn / 2.0)
    q = 1.0 + math.sqrt(2.0) * k + k * k
    b = np.array([k * k, 2.0 * k * k, k * k]) / q
    a = np.array([1.0, 2.0 * (k * k - 1.0) / q, (1.0 - math.sqrt(2.0) * k + k * k) / q])
    return b, a


def zoh_transfer(a: np.ndarray, b: np.ndarray, dt: float) -> list[tuple[np.ndarray, np.ndarray]]:
    """``z' = a z + b u`` ((n, n), (n,)) sampled under a zero-order hold of ``dt`` [s]: for each state its transfer
    function from ``u`` (numerator (n + 1,), denominator (n + 1,), coefficients of ``z^0, z^-1, ...``), as
    ``scipy.signal.cont2discrete(..., method="zoh")`` then ``ss2tf``."""
    n = a.shape[0]
    m = np.zeros((n + 1, n + 1))
    m[:n, :n], m[:n, n] = a * dt, b * dt
    e = expm(m)
    ad, bd = e[:n, :n], e[:n, n]
    den = np.poly(ad)
    # (D = 0: det(zI - Ad + Bd C) - det(zI - Ad) = C adj(zI - Ad) Bd, the numerator of state j's C = e_j)
    return [(np.poly(ad - np.outer(bd, np.eye(n)[j])) - den, den) for j in range(n)]
