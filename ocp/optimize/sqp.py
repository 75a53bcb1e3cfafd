"""The flat program's first solver: CasADi's ``sqpmethod`` with the sparse active-set QP solver qpOASES.

The flat NLP has tens of variables and hundreds of limit rows of which few are active. An active-set SQP with
the exact Hessian takes 3 to 6 iterations where IPOPT takes 6 to 27 (its interior point carries every row in
every linear solve): on the bench missions 2 to 3 times less time to the same optimum (objectives within 1e-4
relative; ``python bench/flat_split.py --sqp``). It is tried first from the same start (primal, and the duals of
a warm start); where it fails (no convergence in :data:`MAX_ITER` iterations, a QP that qpOASES cannot solve, an
indefinite Hessian) IPOPT solves the same NLP (:func:`ocp.optimize.flat.solve`).
"""

from __future__ import annotations

import contextlib
import io
from collections.abc import Iterator, Mapping

import casadi as ca

MAX_ITER = 50  # SQP iterations before IPOPT takes over (the bench missions need 3 to 6)
#: sqpmethod's options: the stopping tolerances on the primal and dual infeasibility (the objective is scaled to
#: 1 at the start, :func:`ocp.optimize.flat.objective_scaled`; IPOPT's ``tol`` is also 1e-7), quiet
OPTIONS: dict[str, object] = {
    "max_iter": MAX_ITER, "tol_pr": 1e-7, "tol_du": 1e-7, "error_on_fail": False,
    "print_time": False, "print_header": False, "print_iteration": False, "print_status": False,
    "qpsol": "qpoases", "qpsol_options": {"printLevel": "none", "sparse": True, "error_on_fail": False},
}


def build(name: str, nlp: Mapping[str, ca.SX], callback: object) -> ca.Function:
    """The SQP solver of ``nlp`` with the iteration ``callback`` (the program's deadline). qpOASES prints a
    banner when a solver is made (and its errors when a QP fails: call the solver inside :func:`quiet`); both are
    kept off the standard output, which carries a CLI's JSON answer."""
    with quiet():
        solver = ca.nlpsol(name, "sqpmethod", dict(nlp), {**OPTIONS, "iteration_callback": callback})  # type: ignore[dict-item]
    return solver


@contextlib.contextmanager
def quiet() -> Iterator[None]:
    """Nothing written to standard output inside the block reaches it: CasADi passes qpOASES's messages to
    Python's ``sys.stdout`` (replaced by a discarded buffer here; process-wide, so another thread's ``print`` in
    the meantime is lost too: the service logs to standard error)."""
    with contextlib.redirect_stdout(io.StringIO()):
        yield
