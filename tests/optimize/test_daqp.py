"""The dense QP solver of the flat program's SQP (:mod:`ocp.optimize.daqp`, DAQP through ctypes) and the QP
Hessian it is given (:func:`ocp.optimize.sqp.convexified`).

Oracles: CasADi's own DAQP interface (another binding of the same solver, its structures laid out by CasADi's C++),
and the KKT conditions of the QP checked with numpy; for the Hessian, eigenvalues and the null space of the rows.
"""

import casadi as ca
import numpy as np

from ocp.optimize import daqp, sqp


def _qp(seed: int) -> tuple[np.ndarray, ...]:
    """A strictly convex QP of 12 variables, 40 two-sided rows (a few binding), box bounds and one equality row."""
    rng = np.random.default_rng(seed)
    n, m = 12, 40
    Q = rng.standard_normal((n, n))
    H = Q @ Q.T + 0.1 * np.eye(n)
    f = 3.0 * rng.standard_normal(n)
    A = rng.standard_normal((m, n))
    lower = np.concatenate([np.full(n, -1.0), np.full(m, -2.0)])
    upper = np.concatenate([np.full(n, 1.0), np.full(m, 2.0)])
    lower[n], upper[n] = 0.3, 0.3  # an equality row
    return H, f, A, lower, upper


def _base(lower: np.ndarray, upper: np.ndarray) -> np.ndarray:
    base = np.zeros(lower.size, np.int32)
    base[lower == upper] = daqp.EQUALITY
    return base


def test_daqp_matches_casadis_daqp_and_the_kkt_conditions():
    assert daqp.available()
    for seed in range(3):
        H, f, A, lower, upper = _qp(seed)
        n = f.size
        res = daqp.solve(H, f, A, lower, upper, _base(lower, upper))
        assert res.success
        qp = ca.conic("q", "daqp", {"h": ca.Sparsity.dense(n, n), "a": ca.Sparsity.dense(*A.shape)})
        ref = qp(h=H, g=f, a=A, lbx=lower[:n], ubx=upper[:n], lba=lower[n:], uba=upper[n:])
        np.testing.assert_allclose(res.x, ref["x"].full().ravel(), atol=1e-9)
        lam_ref = np.concatenate([ref["lam_x"].full().ravel(), ref["lam_a"].full().ravel()])
        np.testing.assert_allclose(res.lam, lam_ref, atol=1e-8)
        # stationarity and complementarity: H x + f + [I A]' lam = 0, lam < 0 only at a lower bound, > 0 at an upper
        rows = np.concatenate([res.x, A @ res.x])
        np.testing.assert_allclose(H @ res.x + f + res.lam[:n] + A.T @ res.lam[n:], 0.0, atol=1e-8)
        assert np.all(rows >= lower - 1e-9) and np.all(rows <= upper + 1e-9)
        assert np.all(np.abs(rows - lower)[res.lam < 0] < 1e-9) and np.all(np.abs(rows - upper)[res.lam > 0] < 1e-9)
        assert np.count_nonzero(res.lam[n + 1:]) >= 1  # some inequality row binds: the test is not trivial


def test_a_solve_from_its_own_working_set_takes_one_iteration_to_the_same_answer():
    """Hot start: the working set of a solved QP (:func:`daqp.working_set`) starts the same QP at its optimum."""
    H, f, A, lower, upper = _qp(4)
    base = _base(lower, upper)
    cold = daqp.solve(H, f, A, lower, upper, base)
    hot = daqp.solve(H, f, A, lower, upper, daqp.working_set(cold.lam, base))
    assert cold.success and hot.success and cold.iterations > 3
    assert hot.iterations <= 1
    np.testing.assert_allclose(hot.x, cold.x, atol=1e-10)
    np.testing.assert_allclose(hot.lam, cold.lam, atol=1e-10)


def test_convexified_keeps_the_hessian_on_the_rows_null_space_and_is_positive_definite():
    """An indefinite H whose restriction to the null space of rows R is positive definite: the QP Hessian is
    positive definite and equal to H on that null space (so the QP step is H's Newton step there); an H
    indefinite on the null space is shifted until positive definite."""
    rng = np.random.default_rng(0)
    n, k = 8, 3
    R = rng.standard_normal((k, n))
    Z = np.linalg.svd(R)[2][k:].T  # (n, n - k) orthonormal null space of R
    Y = np.linalg.svd(R)[2][:k].T
    H = Z @ np.diag(np.linspace(1.0, 3.0, n - k)) @ Z.T - 5.0 * Y @ Y.T  # negative across the rows
    assert np.min(np.linalg.eigvalsh(H)) < -1.0
    B = sqp.convexified(H, R)
    assert np.min(np.linalg.eigvalsh(B)) > 0.0
    np.testing.assert_allclose(Z.T @ B @ Z, Z.T @ H @ Z, atol=1e-12)
    # no rows: H itself is indefinite, so it is shifted by a multiple of the identity
    B0 = sqp.convexified(H, np.zeros((0, n)))
    assert np.min(np.linalg.eigvalsh(B0)) >= sqp.FLOOR * np.max(np.abs(H)) * 0.99
    shift = np.diag(B0 - H)
    np.testing.assert_allclose(B0 - H, np.diag(shift), atol=1e-15)
    assert np.all(shift > 0.0)


def test_screened_qp_is_the_full_qp():
    """Rows far from their bounds are left out of the QP and checked after it (:func:`sqp.screened`): on QPs
    whose unconstrained step breaks rows that start far from their bounds (so they are added in later rounds)
    the answer equals the full QP's, multipliers included (0 on the rows never solved with)."""
    for seed in range(4):
        H, f, A, lower, upper = _qp(seed)
        n = f.size
        lower[n + 1:], upper[n + 1:] = lower[n + 1:] - 0.5, upper[n + 1:] + 0.5  # most rows start > SCREEN away
        base = _base(lower, upper)
        full = daqp.solve(H, f, A, lower, upper, base)
        calls: list[int] = []  # each solve's row count

        def solve(*args, _calls=calls):
            _calls.append(args[2].shape[0])
            out = daqp.solve(*args)
            return out if out.success else None

        part = sqp.screened(solve, H, f, A, lower, upper, base, base)
        assert full.success and part is not None
        np.testing.assert_allclose(part.x, full.x, atol=1e-9)
        np.testing.assert_allclose(part.lam, full.lam, atol=1e-8)
        assert calls[0] < A.shape[0]  # the first solve had fewer rows
        if seed == 0:
            assert len(calls) > 1  # ... and rows were added


def test_a_changed_daqp_layout_is_refused(tmp_path):
    """The ctypes structures are checked against CasADi's DAQP headers: the shipped headers match, a header whose
    settings gained a field (or whose result reordered two) does not, and a missing header folder is refused."""
    import os
    import shutil

    include = os.path.join(os.path.dirname(ca.__file__), "include", "daqp")
    assert daqp._layout_matches(include)
    for name, edit in (("types.h", ("c_float abs_subopt;", "c_float abs_subopt;\n    c_float extra;")),
                       ("api.h", ("int exitflag;\n    int iter;", "int iter;\n    int exitflag;"))):
        copy = tmp_path / name.split(".")[0]
        shutil.copytree(include, copy)
        text = (copy / name).read_text()
        assert edit[0] in text
        (copy / name).write_text(text.replace(edit[0], edit[1]))
        assert not daqp._layout_matches(str(copy))
    assert not daqp._layout_matches(str(tmp_path / "absent"))
