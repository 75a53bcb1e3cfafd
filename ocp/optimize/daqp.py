"""Dense convex QPs by DAQP, the dual active-set solver that ships inside CasADi's wheel, called through ctypes.

CasADi's own DAQP interface (``ca.conic(..., "daqp", ...)``) sets every constraint inactive before each solve; the
flat program's SQP (:mod:`ocp.optimize.sqp`) solves a sequence of QPs whose active rows hardly change, so it passes
the previous QP's working set instead (DAQP's ``sense`` flags, :func:`working_set`). On ``user-sine-1hz-b``'s first
QP (60 free variables, 634 rows, 48 of them active at its optimum) a cold solve took 171 DAQP iterations and 4.2 ms
of CPU, one started from its own working set 1 iteration and 0.9 ms (the rest is DAQP's setup: the factor of the
Hessian and the rows in its coordinates).

The problem is ``min 0.5 x'Hx + f'x`` subject to ``lower <= (x; A x) <= upper``: ``H`` (n, n) symmetric positive
definite, ``A`` (m, n) dense, bounds (n + m,) with infinite entries allowed. The library and the structure layouts
are those of the headers CasADi ships (``casadi/include/daqp``); :func:`available` is False where the library
cannot be loaded, and the caller then uses another solver.
"""

from __future__ import annotations

import ctypes
import os
import re
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import Any

import casadi as ca
import numpy as np

# constraint flags of DAQP's ``sense`` (constants.h)
ACTIVE, LOWER, IMMUTABLE = 1, 2, 4
EQUALITY = ACTIVE | IMMUTABLE  # an equality row: always in the working set
OPTIMAL = 1  # DAQP's exit flag of a solved QP (EXIT_OPTIMAL)
INF = 1e30  # DAQP_INF: bounds beyond it are absent
#: DAQP's tolerance on a row's violation (its default 1e-6 is of rows normalised by their norm in the Hessian's
#: factor: with a badly conditioned Hessian a QP answer broke its linearised current rows by 1e-3)
PRIMAL_TOL = 1e-9

_DP, _IP = ctypes.POINTER(ctypes.c_double), ctypes.POINTER(ctypes.c_int)


class _Problem(ctypes.Structure):
    _fields_ = [("n", ctypes.c_int), ("m", ctypes.c_int), ("ms", ctypes.c_int), ("H", _DP), ("f", _DP),
                ("A", _DP), ("bupper", _DP), ("blower", _DP), ("sense", _IP)]


class _Result(ctypes.Structure):
    _fields_ = [("x", _DP), ("lam", _DP), ("fval", ctypes.c_double), ("soft_slack", ctypes.c_double),
                ("exitflag", ctypes.c_int), ("iter", ctypes.c_int), ("nodes", ctypes.c_int),
                ("solve_time", ctypes.c_double), ("setup_time", ctypes.c_double)]


class _Settings(ctypes.Structure):
    _fields_ = [
        ("primal_tol", ctypes.c_double), ("dual_tol", ctypes.c_double), ("zero_tol", ctypes.c_double),
        ("pivot_tol", ctypes.c_double), ("progress_tol", ctypes.c_double), ("cycle_tol", ctypes.c_int),
        ("iter_limit", ctypes.c_int), ("fval_bound", ctypes.c_double),
        ("eps_prox", ctypes.c_double), ("eta_prox", ctypes.c_double), ("rho_soft", ctypes.c_double),
        ("rel_subopt", ctypes.c_double), ("abs_subopt", ctypes.c_double)]


#: the C structures mirrored above, with the header that declares each (CasADi's ``include/daqp``)
_HEADERS = {"DAQPProblem": ("types.h", _Problem), "DAQPSettings": ("types.h", _Settings),
            "DAQPResult": ("api.h", _Result)}


def header_fields(text: str, name: str) -> list[str]:
    """The field names, in order, of ``typedef struct{ ... }name;`` in the C header ``text`` (comments dropped;
    empty when the structure is not there)."""
    text = re.sub(r"/\*.*?\*/|//[^\n]*", "", text, flags=re.S)
    found = re.search(r"typedef\s+struct\s*\{([^{}]*)\}\s*" + name + r"\s*;", text)
    if found is None:
        return []
    return [re.sub(r"\[.*\]", "", decl).split()[-1].lstrip("*")
            for decl in found.group(1).split(";") if decl.strip()]


def _layout_matches(include: str) -> bool:
    """Whether the headers CasADi ships declare the structures as this module mirrors them (a CasADi whose DAQP
    changed its layout must not be called with these: the SQP then leaves the flat program to IPOPT)."""
    try:
        texts = {f: Path(include, f).read_text(encoding="utf-8") for f in ("types.h", "api.h")}
    except OSError:
        return False
    return all(header_fields(texts[f], name) == [fd[0] for fd in cls._fields_]
               for name, (f, cls) in _HEADERS.items())


def _self_test(lib: ctypes.CDLL, settings: _Settings) -> bool:
    """One QP with a known answer: min 0.5 |x|^2 - x_0 - x_1 s.t. x_0 + x_1 <= 1 has x = (0.5, 0.5) with the row's
    multiplier 0.5 (a library built in single precision, or reading the structures otherwise, fails it)."""
    H, f, A = np.eye(2), np.array([-1.0, -1.0]), np.array([[1.0, 1.0]])
    up, lo = np.array([INF, INF, 1.0]), np.array([-INF, -INF, -INF])
    flags, x, lam = np.zeros(3, np.int32), np.zeros(2), np.zeros(3)
    prob = _Problem(2, 3, 2, _ptr(H), _ptr(f), _ptr(A), _ptr(up), _ptr(lo), _ptr(flags, _IP))
    res = _Result()
    res.x, res.lam = _ptr(x), _ptr(lam)
    lib.daqp_quadprog(ctypes.byref(res), ctypes.byref(prob), ctypes.byref(settings))
    return res.exitflag == OPTIMAL and bool(np.allclose(x, 0.5, atol=1e-12) and abs(lam[2] - 0.5) < 1e-12)


@lru_cache(maxsize=1)
def _library() -> tuple[ctypes.CDLL, _Settings] | None:
    """CasADi's ``libdaqp.so`` with the settings this module solves with, or ``None`` where it cannot be loaded,
    its headers declare other structures than this module's, or it fails :func:`_self_test`."""
    root = os.path.dirname(ca.__file__)
    if not _layout_matches(os.path.join(root, "include", "daqp")):
        return None
    try:
        lib = ctypes.CDLL(os.path.join(root, "libdaqp.so"))
    except OSError:
        return None
    lib.daqp_default_settings.argtypes = [ctypes.POINTER(_Settings)]
    lib.daqp_default_settings.restype = None
    lib.daqp_quadprog.argtypes = [ctypes.POINTER(_Result), ctypes.POINTER(_Problem), ctypes.POINTER(_Settings)]
    lib.daqp_quadprog.restype = None
    settings = _Settings()
    lib.daqp_default_settings(ctypes.byref(settings))
    settings.primal_tol = PRIMAL_TOL
    return (lib, settings) if _self_test(lib, settings) else None


def available() -> bool:
    """Whether DAQP's library could be loaded."""
    return _library() is not None


@dataclass(frozen=True)
class QPResult:
    """One DAQP solve: the primal ``x`` (n,), the multipliers ``lam`` (n + m,) of the bounds then the rows
    (negative at a lower bound, positive at an upper one, zero off the working set), DAQP's exit flag and
    iterations."""

    x: np.ndarray
    lam: np.ndarray
    exitflag: int
    iterations: int

    @property
    def success(self) -> bool:
        return self.exitflag == OPTIMAL


def _ptr(a: np.ndarray, kind: Any = _DP) -> Any:
    return a.ctypes.data_as(kind)


def solve(H: np.ndarray, f: np.ndarray, A: np.ndarray, lower: np.ndarray, upper: np.ndarray,
          sense: np.ndarray) -> QPResult:
    """Solve the QP (see the module's docstring) starting from the working set ``sense`` ((n + m,) int32 flags:
    :data:`ACTIVE`, :data:`LOWER`, :data:`EQUALITY` for the rows whose bounds are equal)."""
    loaded = _library()
    if loaded is None:
        raise RuntimeError("DAQP's library is not available")
    lib, settings = loaded
    n, m = f.size, A.shape[0]
    H, f, A = (np.ascontiguousarray(a, dtype=float) for a in (H, f, A))
    lo, up = np.maximum(lower, -INF), np.minimum(upper, INF)
    flags = np.ascontiguousarray(sense, dtype=np.int32)
    x, lam = np.zeros(n), np.zeros(n + m)
    prob = _Problem(n, n + m, n, _ptr(H), _ptr(f), _ptr(A), _ptr(up), _ptr(lo), _ptr(flags, _IP))
    res = _Result()
    res.x, res.lam = _ptr(x), _ptr(lam)
    lib.daqp_quadprog(ctypes.byref(res), ctypes.byref(prob), ctypes.byref(settings))
    return QPResult(x=x, lam=lam, exitflag=int(res.exitflag), iterations=int(res.iter))


def working_set(lam: np.ndarray, base: np.ndarray) -> np.ndarray:
    """The ``sense`` flags (n + m,) that start a QP from the rows active in ``lam`` (multipliers (n + m,) of a
    solved one, or of a remembered NLP solve), over ``base`` (the equality flags)."""
    out = base.copy()
    active = lam != 0.0
    out[active] |= ACTIVE
    out[active & (lam < 0.0)] |= LOWER
    return out
