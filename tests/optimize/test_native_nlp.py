"""Issue 14: the SQP's NLP functions compiled to C once per structure and machine (:mod:`ocp.optimize.native_nlp`,
:mod:`ocp.native`).

Oracles: CasADi's virtual machine evaluating the same graphs (the compiled functions must give its numbers), the
same SQP solve without the compiled functions (same iterations, same answer), and the files in a temporary
cache directory (what was built, loaded, refused or pruned).
"""

import fcntl
import json
import math
import os
import subprocess
import sys
import time
from pathlib import Path
from types import SimpleNamespace

import casadi as ca
import numpy as np
import pytest

from ocp import native
from ocp.optimize import flat, flat_solve, native_nlp, sqp
from ocp.optimize.mission import mission_from_mapping
from ocp.optimize.problem import problem_for

ROOT = Path(__file__).resolve().parents[2]
pytestmark = pytest.mark.skipif(native.compiler() is None, reason="no C compiler on the PATH")


@pytest.fixture()
def cache(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """A cache directory of the test's own, compiling allowed."""
    monkeypatch.setenv("THRUSTSHAPE_CACHE_DIR", str(tmp_path))
    monkeypatch.setenv(native_nlp.SWITCH, "1")
    return tmp_path / "nlp"


def _small_nlp(weight: float = 100.0) -> dict[str, ca.SX]:
    """A Rosenbrock valley with a disc and a linear row: 4 variables, 1 parameter, 2 rows."""
    x, p = ca.SX.sym("x", 4), ca.SX.sym("p")
    f = (x[0] - p) ** 2 + weight * (x[1] - x[0] ** 2) ** 2 + (x[2] - 0.5) ** 2 + ca.sin(x[3]) ** 2
    return {"x": x, "p": p, "f": f, "g": ca.vertcat(x[0] ** 2 + x[1] ** 2, x[2] + x[3])}


def _solver(nlp: dict[str, ca.SX]) -> sqp.Solver:
    return sqp.build("small", nlp, SimpleNamespace(until=math.inf))


def _solve(solver: sqp.Solver) -> dict:
    return solver(x0=np.array([-1.0, 1.0, 0.0, 0.3]), p=np.array([1.0]), lbx=np.full(4, -2.0), ubx=np.full(4, 2.0),
                  lbg=np.array([0.0, -1.0]), ubg=np.array([0.8, 1.0]))


def test_compiled_functions_give_the_virtual_machines_numbers_and_answer(cache: Path) -> None:
    """Every compiled function equals the VM's at random points (rtol 1e-12; the same IEEE arithmetic), and the
    SQP takes the same iterations to the same answer with either; the library lands in the cache."""
    solver = _solver(_small_nlp())
    vm_answer, vm_stats = _solve(solver), solver.stats()
    assert not solver.use_native()  # not hot yet, nothing on disk
    assert solver.use_native(wait=True)
    assert list(cache.glob("nlp_*.so")) == [cache / f"{solver.native.key}.so"]
    loaded = solver.native.get()
    assert loaded is not None
    rng = np.random.default_rng(3)
    for name, fn in solver.native.fns.items():
        for _ in range(5):
            args = [rng.uniform(-2.0, 2.0, fn.nnz_in(i)) for i in range(fn.n_in())]
            for got, want in zip(loaded[name].call(args), fn.call(args), strict=True):
                np.testing.assert_allclose(np.asarray(got), np.asarray(want), rtol=1e-12, atol=1e-300)
    answer = _solve(solver)
    assert solver.stats()["success"] and vm_stats["success"]
    assert solver.stats()["iter_count"] == vm_stats["iter_count"]
    np.testing.assert_allclose(answer["x"], vm_answer["x"], rtol=1e-12, atol=1e-14)


def test_the_fingerprint_names_the_graph(cache: Path) -> None:
    """The same graph built twice gets one key (a later process finds the library); another weight, another key."""
    keys = [_solver(_small_nlp(w)).native.key for w in (100.0, 100.0, 101.0)]
    assert keys[0] == keys[1] != keys[2]


def test_a_later_solver_loads_the_library_without_building(cache: Path) -> None:
    """A second solver of the same graph (a new worker, a later run) uses the library on its first solve."""
    assert _solver(_small_nlp()).use_native(wait=True)
    stamp = os.stat(next(cache.glob("nlp_*.so"))).st_mtime_ns
    fresh = _solver(_small_nlp())
    _solve(fresh)
    assert fresh.fns is not fresh.vm_fns
    assert os.stat(next(cache.glob("nlp_*.so"))).st_mtime_ns == stamp


def test_the_build_starts_only_once_the_program_is_hot(cache: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(native_nlp, "HOT_CALLS", 3)
    solver = _solver(_small_nlp(7.0))
    path = cache / f"{solver.native.key}.so"
    for _ in range(2):
        _solve(solver)
    assert not path.exists() and solver.native.key not in native._THREADS
    _solve(solver)  # the third: the build starts in the background
    assert path.exists() or solver.native.key in native._THREADS
    assert solver.use_native(wait=True) and path.exists()


def test_a_wrong_library_is_refused_removed_and_never_used(cache: Path) -> None:
    """A library whose functions do not give the VM's numbers (here: another graph's, copied under this key) is
    removed, and the solver keeps the virtual machine."""
    other = _solver(_small_nlp(3.0))
    assert other.use_native(wait=True)
    solver = _solver(_small_nlp(5.0))
    target = cache / f"{solver.native.key}.so"
    target.write_bytes((cache / f"{other.native.key}.so").read_bytes())
    assert not solver.use_native()
    assert not target.exists() and solver.native.failed
    assert _solve(solver)["x"] is not None and solver.fns is solver.vm_fns


def test_compiling_can_be_turned_off(cache: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv(native_nlp.SWITCH, "0")
    solver = _solver(_small_nlp(11.0))
    assert not solver.use_native(wait=True)
    assert not cache.exists() or not list(cache.glob("*.so"))


def test_a_failed_build_is_not_retried_and_the_cache_is_bounded(cache: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    assert native.library("bad_source", "nlp", lambda: "this is not C", native_nlp.FLAGS, wait=True) is None
    assert "bad_source" not in native._THREADS
    assert native.library("bad_source", "nlp", lambda: "int ok;", native_nlp.FLAGS, wait=True) is None
    monkeypatch.setattr(native, "MAX_LIBRARIES", 2)
    for k in range(4):
        def source(k: int = k) -> str:
            return f"int v{k} = {k};"

        assert native.library(f"lib{k}", "nlp", source, native_nlp.FLAGS, wait=True)
        os.utime(cache / f"lib{k}.so", (1e9 + k, 1e9 + k))  # distinct ages, oldest first
    assert sorted(p.name for p in cache.glob("*.so")) == ["lib2.so", "lib3.so"]


def test_the_flat_programs_compiled_functions_answer_as_the_virtual_machine(cache: Path,
                                                                           monkeypatch: pytest.MonkeyPatch) -> None:
    """The README's bounded reversal: the SQP with its compiled functions (a solver of the test's own, in the
    program's place) returns the same decision vector as with the VM (the same iterates, rounding aside)."""
    problem = problem_for(mission_from_mapping(json.loads((ROOT / "examples" / "reversal.json").read_text())))
    prog, _ = flat.program_for(flat_solve.structure_of(problem))
    data = flat_solve.flat_data(problem, prog)
    assert data is not None
    bounds = prog.g_bounds(1.0 - flat.MARGIN, 1.0 - flat.MARGIN)
    solver = sqp.build("flat_sqp", prog.nlp, prog.deadline, prog.solver)
    monkeypatch.setattr(prog, "sqp_solver", solver)
    solver.allow_native = False
    vm = flat.solve(prog, data.p, data.lbx, data.ubx, data.x0, bounds)
    assert solver.use_native(wait=True)
    solver.allow_native = True
    fast = flat.solve(prog, data.p, data.lbx, data.ubx, data.x0, bounds)
    assert fast.method == vm.method == "sqp" and fast.success and vm.success
    assert fast.iterations == vm.iterations
    assert fast.compiled and not vm.compiled  # what the answer's solver.compiled reports
    np.testing.assert_allclose(fast.x, vm.x, rtol=1e-9, atol=1e-12)


def test_one_build_at_a_time_and_a_busy_one_is_tried_again(cache: Path) -> None:
    """While another process holds the sub-folder's build lock, a build is not started (and not remembered as
    failed); once the lock is free, a later call builds the library."""
    cache.mkdir(parents=True)
    with open(cache / "builds.lock", "a") as held:
        fcntl.flock(held, fcntl.LOCK_EX)
        assert native.library("libx", "nlp", lambda: "int x;", native_nlp.FLAGS) is None
        for _ in range(100):  # the background thread finds the lock taken and gives up
            if "libx" not in native._THREADS:
                break
            time.sleep(0.05)
        assert "libx" not in native._THREADS and "libx" not in native._FAILED
        assert not (cache / "libx.so").exists()
    assert native.library("libx", "nlp", lambda: "int x;", native_nlp.FLAGS, wait=True) == cache / "libx.so"
    assert [p.name for p in cache.iterdir() if p.is_dir()] == []  # no temporary folder left


def test_a_build_outlives_the_worker_that_started_it(cache: Path) -> None:
    """A worker that starts a build and then dies (a pool shut down, a deadline kill) leaves no orphaned compiler
    and no temporary folder: the build process finishes, lands the library and cleans up."""
    script = (
        "import os, time\n"
        "from ocp import native\n"
        "body = '\\n'.join(f'  x = x * 1.0000001 + {i}.5 / (x + {i});' for i in range(4000))  # ~3 s of -O1\n"
        "native.library('slow', 'nlp', lambda: 'double f(double x) {\\n' + body + '\\n  return x;\\n}', "
        f"{native_nlp.FLAGS!r})\n"
        "folder = os.path.join(os.environ['THRUSTSHAPE_CACHE_DIR'], 'nlp')\n"
        "for _ in range(200):  # until the build process is started\n"
        "    if os.path.isdir(folder) and [p for p in os.scandir(folder) if p.is_dir()]:\n"
        "        break\n"
        "    time.sleep(0.05)\n"
        "time.sleep(0.3)\n"
        "os._exit(0)\n")
    subprocess.run([sys.executable, "-c", script], cwd=ROOT, check=True, timeout=60,
                   env={**os.environ, "PYTHONPATH": str(ROOT)})
    assert not (cache / "slow.so").exists()  # the worker is gone before its build ended
    deadline = time.monotonic() + 120.0
    while time.monotonic() < deadline and not (cache / "slow.so").exists():
        time.sleep(0.2)
    assert (cache / "slow.so").exists()
    time.sleep(0.5)
    assert [p.name for p in cache.iterdir() if p.is_dir()] == []
