"""The simulator's step compiled to C at run time with a C loop over the steps, cached on disk.

``CompiledStep(step).get()`` returns a driver ``(x0 (nx,), u (K,), dt (K,)) -> states (nx, K)`` that runs the
step ``(x (nx,), u, dt) -> x+`` K times in C, once it is built, else ``None`` and the caller keeps the CasADi
virtual machine (``mapaccum``). The step is CasADi's own generated C of the same expression graph (IEEE double
arithmetic, no fast-math, no contraction into fused multiply-adds), so the numbers are the same:

* the C source comes from ``casadi.CodeGenerator`` with a driver loop appended; its SHA-256 (with the flags and
  CasADi's version) names the shared library in the cache's sub-folder ``sim`` (:mod:`ocp.native`: where, the
  compiler, the background build), so another process or a later run loads it at once;
* the first simulations of a new plant run uncompiled, the later ones compiled; a failed build is remembered and
  never retried in the process;
* ``THRUSTSHAPE_SIM_COMPILE=0`` turns the compiled path off.
"""

from __future__ import annotations

import ctypes
import hashlib
import threading
from collections.abc import Callable
from pathlib import Path

import casadi as ca
import numpy as np

from ocp import native

FLAGS = ("-O2", *native.SAFE_MATH)
SWITCH = "THRUSTSHAPE_SIM_COMPILE"

_LOCK = threading.Lock()
_LOADED: dict[str, Callable[[np.ndarray, np.ndarray, np.ndarray], np.ndarray] | None] = {}  # key -> driver, or
# None when the load failed


def enabled() -> bool:
    """Whether the compiled path may be used: not turned off, and a C compiler is on the PATH."""
    return native.enabled(SWITCH)


def compiler() -> str | None:
    """Path of the C compiler, None when there is none (:func:`ocp.native.compiler`)."""
    return native.compiler()


def cache_dir() -> Path:
    """Where the compiled steps are kept (:func:`ocp.native.cache_dir`)."""
    return native.cache_dir("sim")


_DRIVER = """
#include <stdlib.h>
CASADI_SYMBOL_EXPORT int {name}_drive(const casadi_real* x0, const casadi_real* u, const casadi_real* dt,
                                     long long steps, casadi_real* out) {{
  casadi_int sz_arg, sz_res, sz_iw, sz_w;
  const casadi_real* arg[16];
  casadi_real* res[16];
  casadi_int* iw;
  casadi_real* w;
  long long k;
  int flag = 0;
  if ({name}_work(&sz_arg, &sz_res, &sz_iw, &sz_w) || sz_arg > 16 || sz_res > 16) return 1;
  iw = (casadi_int*) malloc(sizeof(casadi_int) * (sz_iw > 0 ? sz_iw : 1));
  w = (casadi_real*) malloc(sizeof(casadi_real) * (sz_w > 0 ? sz_w : 1));
  if (!iw || !w) {{ free(iw); free(w); return 2; }}
  for (k = 0; k < steps && !flag; ++k) {{
    arg[0] = k ? out + (k - 1) * {nx} : x0;
    arg[1] = u + k;
    arg[2] = dt + k;
    res[0] = out + k * {nx};
    flag = {name}(arg, res, iw, w, 0);
  }}
  free(iw);
  free(w);
  return flag;
}}
"""


def _source(fn: ca.Function) -> str:
    gen = ca.CodeGenerator(fn.name(), {"with_header": False})
    gen.add(fn)
    return str(gen.dump()) + _DRIVER.format(name=fn.name(), nx=int(fn.size1_in(0)))


def _key(fn: ca.Function, source: str) -> str:
    h = hashlib.sha256("\n".join([source, " ".join(FLAGS), native.version_tag()]).encode())
    return f"{fn.name()}_{h.hexdigest()[:20]}"


Driver = Callable[[np.ndarray, np.ndarray, np.ndarray], np.ndarray]


class CompiledStep:
    """The compiled driver of one step function ``(x (nx,), u, dt) -> x+`` (C source and key computed once)."""

    def __init__(self, step: ca.Function) -> None:
        self.nx = int(step.size1_in(0))
        self.name = step.name()
        self.source = _source(step)
        self.key = _key(step, self.source)

    def get(self, wait: bool = False) -> Driver | None:
        """The driver when it is built (loaded from the disk cache), else None after starting its build in the
        background (``wait``: build now). None when compiling is off or failed."""
        if not enabled():
            return None
        with _LOCK:
            if self.key in _LOADED:
                return _LOADED[self.key]
        path = native.library(self.key, "sim", lambda: self.source, FLAGS, wait=wait)
        if path is None:
            return None
        try:
            driver: Driver | None = self._driver(ctypes.CDLL(str(path)))
        except OSError:
            driver = None
        with _LOCK:
            _LOADED[self.key] = driver
        return driver

    def _driver(self, lib: ctypes.CDLL) -> Driver:
        fn = getattr(lib, f"{self.name}_drive")
        dbl = ctypes.POINTER(ctypes.c_double)
        fn.argtypes = [dbl, dbl, dbl, ctypes.c_longlong, dbl]
        fn.restype = ctypes.c_int
        nx = self.nx

        def drive(x0: np.ndarray, u: np.ndarray, dt: np.ndarray) -> np.ndarray:
            x0c, uc, dtc = (np.ascontiguousarray(a, dtype=np.float64).ravel() for a in (x0, u, dt))
            if x0c.size != nx or uc.size != dtc.size:
                raise ValueError(f"compiled step: x0 needs {nx} values, u and dt one per step")
            out = np.empty((uc.size, nx))  # row k: the state after step k (C order: out[k * nx + i])
            flag = fn(x0c.ctypes.data_as(dbl), uc.ctypes.data_as(dbl), dtc.ctypes.data_as(dbl), uc.size,
                      out.ctypes.data_as(dbl))
            if flag:
                raise RuntimeError(f"compiled step failed (code {flag})")
            return out.T

        return drive
