"""The simulator's step compiled to C at run time with a C loop over the steps, cached on disk.

``CompiledStep(step).get()`` returns a driver ``(x0 (nx,), u (K,), dt (K,)) -> states (nx, K)`` that runs the
step ``(x (nx,), u, dt) -> x+`` K times in C, once it is built, else ``None`` and the caller keeps the CasADi
virtual machine (``mapaccum``). The step is CasADi's own generated C of the same expression graph (IEEE double
arithmetic, no fast-math, no contraction into fused multiply-adds), so the numbers are the same:

* the C source comes from ``casadi.CodeGenerator`` with a driver loop appended; its SHA-256 (with the flags and
  CasADi's version) names the shared library in the cache directory (``$THRUSTSHAPE_CACHE_DIR``, else
  ``$XDG_CACHE_HOME/thrustshape``, else ``~/.cache/thrustshape``; sub-folder ``sim``), so another process or a
  later run loads it at once;
* a library not on disk is built in a background thread by the C compiler on the ``PATH`` (``$CC``, ``cc``,
  ``gcc`` or ``clang``): the first simulations of a new plant run uncompiled, the later ones compiled; a
  failed build is remembered and never retried in the process;
* ``THRUSTSHAPE_SIM_COMPILE=0`` turns the compiled path off.
"""

from __future__ import annotations

import ctypes
import hashlib
import os
import shutil
import subprocess
import tempfile
import threading
from collections.abc import Callable
from functools import cache
from pathlib import Path

import casadi as ca
import numpy as np

FLAGS = ("-O2", "-fPIC", "-shared", "-ffp-contract=off", "-fno-fast-math")
BUILD_TIMEOUT_S = 120.0

_LOCK = threading.Lock()
_BUILT: dict[str, Callable[[np.ndarray, np.ndarray, np.ndarray], np.ndarray] | None] = {}  # key -> driver, or
# None when the build or the load failed
_BUILDING: set[str] = set()


def enabled() -> bool:
    """Whether the compiled path may be used: not turned off, and a C compiler is on the PATH."""
    return os.environ.get("THRUSTSHAPE_SIM_COMPILE", "1") != "0" and compiler() is not None


@cache
def compiler() -> str | None:
    """Path of the C compiler (``$CC``, else ``cc``, ``gcc``, ``clang``), None when there is none."""
    for name in (os.environ.get("CC"), "cc", "gcc", "clang"):
        path = shutil.which(name) if name else None
        if path:
            return path
    return None


def cache_dir() -> Path:
    """Where the compiled libraries are kept (see the module doc)."""
    root = os.environ.get("THRUSTSHAPE_CACHE_DIR")
    if root:
        return Path(root) / "sim"
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "thrustshape" / "sim"


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
    h = hashlib.sha256("\n".join([source, " ".join(FLAGS), str(ca.CasadiMeta.version())]).encode())
    return f"{fn.name()}_{h.hexdigest()[:20]}"


def _build(key: str, source: str, library: Path) -> None:
    """Compile ``source`` into ``library`` (atomic rename, so a concurrent reader never sees half a file)."""
    cc = compiler()
    ok = False
    try:
        library.parent.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryDirectory(dir=library.parent) as tmp:
            c_file = Path(tmp) / f"{key}.c"
            c_file.write_text(source, encoding="utf-8")
            out = Path(tmp) / library.name
            run = subprocess.run([str(cc), *FLAGS, str(c_file), "-o", str(out), "-lm"], capture_output=True,
                                 timeout=BUILD_TIMEOUT_S, check=False)
            if run.returncode == 0:
                os.replace(out, library)
                ok = True
    except (OSError, subprocess.SubprocessError):
        ok = False
    with _LOCK:
        _BUILDING.discard(key)
        if not ok:
            _BUILT[key] = None


Driver = Callable[[np.ndarray, np.ndarray, np.ndarray], np.ndarray]


class CompiledStep:
    """The compiled driver of one step function ``(x (nx,), u, dt) -> x+`` (C source and key computed once)."""

    def __init__(self, step: ca.Function) -> None:
        self.nx = int(step.size1_in(0))
        self.name = step.name()
        self.source = _source(step)
        self.key = _key(step, self.source)
        self.library = cache_dir() / f"{self.key}.so"

    def get(self, wait: bool = False) -> Driver | None:
        """The driver when it is built (loaded from the disk cache), else None after starting its build in the
        background (``wait``: build now). None when compiling is off or failed."""
        if not enabled():
            return None
        with _LOCK:
            if self.key in _BUILT:
                return _BUILT[self.key]
            if self.key in _BUILDING:
                return None
            if not self.library.exists():
                _BUILDING.add(self.key)
                if not wait:
                    threading.Thread(target=_build, args=(self.key, self.source, self.library), daemon=True,
                                     name=f"cc-{self.key}").start()
                    return None
        if wait and not self.library.exists():
            _build(self.key, self.source, self.library)
        return self._load()

    def _load(self) -> Driver | None:
        driver: Driver | None = None
        if self.library.exists():
            try:
                driver = self._driver(ctypes.CDLL(str(self.library)))
            except OSError:
                driver = None
        with _LOCK:
            _BUILT[self.key] = driver
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
