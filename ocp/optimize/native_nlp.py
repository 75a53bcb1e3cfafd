"""The flat program's NLP functions compiled to C, once per structure and machine, for the SQP solver.

The SQP (:mod:`ocp.optimize.sqp`) spends ~60 % of a solve evaluating five CasADi functions in CasADi's virtual
machine: objective, rows, gradient, Jacobian and the Hessian of the Lagrangian (``sine``'s: 150k instructions,
0.56 ms a call). CasADi's generated C of the same graphs, built with ``-O1``, evaluates them 4-12x faster
(Hessian 0.045 ms, Jacobian 0.024 ms); building it takes ~25 s of one core for a 70-variable program (``-O2``:
190 s), so it is done where it pays:

* the library is named by a **fingerprint** of the functions (their sparsities and instruction counts, and their
  outputs at a fixed pseudo-random point, computed in the virtual machine: two different graphs cannot agree on
  all of them by chance) with the flags and CasADi's version, and kept on disk (:mod:`ocp.native`, sub-folder
  ``nlp``): a later process, or another worker, loads it at once;
* a program looks for its library on its first solve and every :data:`HOT_CALLS` solves after; it starts the
  build (in the background, at the lowest CPU priority) only after :data:`HOT_CALLS` solves in the process, so
  one-off structures never pay for it;
* a loaded library is **checked** against the virtual machine at the fingerprint point (relative
  :data:`CHECK_RTOL`; the same arithmetic gives the same numbers); a library that fails is removed and never used;
* ``THRUSTSHAPE_NLP_COMPILE=0`` turns the compiled path off (the solver keeps the virtual machine).
"""

from __future__ import annotations

import hashlib
from collections.abc import Mapping

import casadi as ca
import numpy as np

from ocp import native

SWITCH = "THRUSTSHAPE_NLP_COMPILE"
#: -O1: ~25 s for the 6 MB source of a 70-variable flat program, 4-12x faster than the VM; -O0 builds in ~9 s but
#: is only 2-3x faster; -O2 takes 190 s for the same source
FLAGS = ("-O1", *native.SAFE_MATH)
HOT_CALLS = 20  # solves of one program in a process before its library is built
CHECK_RTOL = 1e-9  # loaded library against the virtual machine, relative to the largest output


def _point(fn: ca.Function) -> list[np.ndarray]:
    """The fixed pseudo-random inputs of the fingerprint, one array (nnz_in,) per input of ``fn``."""
    rng = np.random.default_rng(20261126)
    return [rng.uniform(0.5, 1.5, fn.nnz_in(i)) for i in range(fn.n_in())]


def _outputs(fn: ca.Function, args: list[np.ndarray]) -> list[np.ndarray]:
    """``fn``'s outputs at ``args``, each flattened to its nonzeros."""
    return [np.asarray(ca.DM(out).nonzeros(), float) for out in fn.call(args)]


class NativeNLP:
    """The compiled versions of the named functions ``fns`` (name -> CasADi function), when built."""

    def __init__(self, fns: Mapping[str, ca.Function]) -> None:
        self.fns = dict(fns)
        self.points = {name: _point(fn) for name, fn in self.fns.items()}
        self.reference = {name: _outputs(fn, self.points[name]) for name, fn in self.fns.items()}
        digest = hashlib.sha256()
        for name, fn in self.fns.items():
            sizes = [fn.sparsity_in(i).dim() for i in range(fn.n_in())]
            sizes += [fn.sparsity_out(i).dim() for i in range(fn.n_out())]
            digest.update(f"{name}:{fn.name()}:{fn.n_instructions()}:{sizes}".encode())
            for i in range(fn.n_out()):
                digest.update(fn.sparsity_out(i).serialize().encode())
            for out in self.reference[name]:
                digest.update(out.tobytes())
        digest.update(" ".join([*FLAGS, native.version_tag()]).encode())
        self.key = f"nlp_{digest.hexdigest()[:24]}"
        self.calls = 0
        self.failed = False
        self.loaded: dict[str, ca.Function] | None = None

    def source(self) -> str:
        """CasADi's generated C of every function (made only when the library is built)."""
        gen = ca.CodeGenerator(self.key, {"with_header": False})
        for fn in self.fns.values():
            gen.add(fn)
        return str(gen.dump())

    def poll(self) -> dict[str, ca.Function] | None:
        """Count a solve; the compiled functions when their library is on disk (built here or elsewhere), after
        starting its build once the program is hot (:data:`HOT_CALLS`). The disk is looked at on the first solve and
        every :data:`HOT_CALLS` solves after, not on every one (a build another worker holds the lock for is then
        retried as rarely). None meanwhile, when turned off, or when the library failed."""
        self.calls += 1
        if self.loaded is not None or self.failed or not native.enabled(SWITCH):
            return self.loaded
        if self.calls % HOT_CALLS == 0:
            return self.get()
        if self.calls == 1 and (native.cache_dir("nlp") / f"{self.key}.so").exists():
            return self.get()
        return None

    def get(self, wait: bool = False) -> dict[str, ca.Function] | None:
        """The compiled functions, loaded and checked, when the library is on disk; else None after starting its
        build (``wait``: build it now)."""
        if self.loaded is not None or self.failed or not native.enabled(SWITCH):
            return self.loaded
        path = native.library(self.key, "nlp", self.source, FLAGS, wait=wait)
        if path is None:
            return None
        try:
            loaded = {name: ca.external(fn.name(), str(path)) for name, fn in self.fns.items()}
        except RuntimeError:
            loaded = None
        if loaded is None or not self._agrees(loaded):
            self.failed = True
            native.mark_failed(self.key)
            path.unlink(missing_ok=True)
            return None
        self.loaded = loaded
        return loaded

    def _agrees(self, loaded: Mapping[str, ca.Function]) -> bool:
        """Whether every compiled function gives the virtual machine's outputs at the fingerprint point."""
        for name, fn in loaded.items():
            for got, want in zip(_outputs(fn, self.points[name]), self.reference[name], strict=True):
                if got.shape != want.shape:
                    return False
                scale = max(1.0, float(np.nanmax(np.abs(want), initial=0.0)))
                same = (np.abs(got - want) <= CHECK_RTOL * scale) | (np.isnan(got) & np.isnan(want))
                if not np.all(same):
                    return False
        return True
