"""Preview (look-ahead) linear-quadratic tracker of the shaper, designed once per (hold, dt, bandwidth, N).

The shaper moves a shaping coordinate ``eta`` (see :mod:`ocp.stream.inverse`) along a chain of
integrators sampled every ``dt``; its decision at sample k is ``v_k = eta''(t_{k+1})``:

* ``hold="zoh"`` -- state ``z = (eta, eta')``, ``eta''`` held at ``v_k`` over the sample (chain 2);
* ``hold="foh"`` -- state ``z = (eta, eta', eta'')``, ``eta''`` ramps linearly from ``eta''_k`` to
  ``v_k`` (chain 3, constant jerk; ``eta''`` is continuous).

The cost is ``sum_k (eta_k - r_k)^2 + sum_j q_j (eta^(j) / omega_c^j)^2 + (w_k / omega_c^n)^2`` with
``w = eta''`` (zoh, n = 2) or the jerk ``(v_k - eta''_k)/dt`` (foh, n = 3), ``omega_c = 2 pi bandwidth``,
and the derivative weights ``q = (2)`` or ``(3, 3)``: by the return-difference identity
``p(s)p(-s) = 1 - q_1 s^2 + q_2 s^4 - ... + (-1)^n s^(2n)`` the continuous-time optimum then has all its
poles at ``-omega_c`` (``p = (s + 1)^n``, critically damped). Critical damping matters: Butterworth
poles make the preview gains oscillate, and the shaped speed then rings across zero before a step
(spurious micro-reversals). The design is done in the normalised time ``omega_c t`` and mapped back.

The reference ``r`` is known ``N`` samples ahead (the look-ahead) and held beyond. The optimal
infinite-horizon law is (tracking LQ, value ``z'Pz - 2 g_k'z``; ``g_k = A_c' g_{k+1} + C' r_k``)::

    v_k = -K z_k + sum_{j>=0} F_j r_{k+1+j},   F_j = (R + B'PB)^-1 B' (A_c')^j C'

and the held tail folds into the last gain: ``F_tail = (R + B'PB)^-1 B' (A_c')^(N-1) (I - A_c')^-1 C'``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache
from typing import Literal

import numpy as np
from scipy.linalg import solve_discrete_are

Hold = Literal["zoh", "foh"]


@dataclass(frozen=True)
class PreviewGains:
    """One tracker design (SI, real time).

    Attributes:
        A: (n, n) state transition over one sample, state ``z = (eta, eta', [eta''])``
        B: (n,) input vector of ``v = eta''(t_{k+1})``
        K: (n,) state feedback [v per unit of each state]
        F: (N,) preview gains on ``r_{k+1} .. r_{k+N}`` (the last holds the tail)
    """

    A: np.ndarray
    B: np.ndarray
    K: np.ndarray
    F: np.ndarray


def chain_matrices(hold: Hold, h: float) -> tuple[np.ndarray, np.ndarray]:
    """(A, B) of the sampled chain for a sample period ``h`` (exact integration of the held eta'')."""
    if hold == "zoh":
        return np.array([[1.0, h], [0.0, 1.0]]), np.array([h * h / 2.0, h])
    # eta'' ramps from eta''_k to v: eta' gains (eta''_k + v) h / 2, eta gains (2 eta''_k + v) h^2 / 6
    A = np.array([[1.0, h, h * h / 3.0], [0.0, 1.0, h / 2.0], [0.0, 0.0, 0.0]])
    return A, np.array([h * h / 6.0, h / 2.0, 1.0])


def _normalised_design(hold: Hold, h: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(A, B, K, M) in normalised time (omega_c = 1, rho = 1); M = (R + B'PB)^-1 B'."""
    A, B = chain_matrices(hold, h)
    n = A.shape[0]
    Bc = B.reshape(n, 1)
    if hold == "zoh":
        Q, R, S = np.diag([1.0, 2.0]), np.array([[1.0]]), np.zeros((n, 1))
    else:  # jerk = (v - eta'')/h  ->  cost (v^2 - 2 v eta'' + eta''^2) / h^2
        j = 1.0 / h**2
        Q, R, S = np.diag([1.0, 3.0, 3.0 + j]), np.array([[j]]), np.array([[0.0], [0.0], [-j]])
    P = solve_discrete_are(A, Bc, Q, R, s=S)
    H = R + Bc.T @ P @ Bc
    K = np.linalg.solve(H, Bc.T @ P @ A + S.T).ravel()
    M = np.linalg.solve(H, Bc.T).ravel()
    return A, B, K, M


@lru_cache(maxsize=32)
def design(hold: Hold, dt: float, bandwidth: float, n_preview: int) -> PreviewGains:
    """The tracker for sample period ``dt`` [s], ``bandwidth`` [Hz] and ``n_preview`` samples of look-ahead."""
    wc = 2.0 * math.pi * bandwidth
    h = wc * dt
    A, B, K, M = _normalised_design(hold, h)
    n = A.shape[0]
    Ac_T = (A - np.outer(B, K)).T
    C = np.zeros(n)
    C[0] = 1.0
    F = np.empty(n_preview)
    g = C.copy()
    for j in range(n_preview - 1):
        F[j] = M @ g
        g = Ac_T @ g
    F[-1] = M @ np.linalg.solve(np.eye(n) - Ac_T, g)
    # back to real time: state k scaled by wc^-k, v (an eta'' level) by wc^2
    scale = wc ** np.arange(n, dtype=float)
    A_real, B_real = chain_matrices(hold, dt)
    return PreviewGains(A=A_real, B=B_real, K=K * wc**2 / scale, F=F * wc**2)
