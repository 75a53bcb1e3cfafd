"""``ocp.__all__`` is the curated public API: every name resolves to the object of the module that defines it,
the documented entry points are in it, and ``import ocp`` stays light (the CLI's ``--help`` imports it)."""

from __future__ import annotations

import importlib
import json
import subprocess
import sys
from pathlib import Path

import ocp

ROOT = Path(__file__).resolve().parents[1]


def test_every_public_name_resolves_to_its_defining_module() -> None:
    assert ocp.__all__ == sorted(set(ocp.__all__))
    for name in ocp.__all__:
        value = getattr(ocp, name)
        module = importlib.import_module(ocp._EXPORTS[name])
        assert value is getattr(module, ocp._ALIASES.get(name, name)), name
        assert getattr(value, "__module__", module.__name__).startswith("ocp"), name


def test_the_pipeline_entry_points_are_public() -> None:
    assert {"load_params", "Mission", "load_mission", "optimize_reference", "OptimizeResult", "Source", "Status",
            "SolverStats", "Verification", "Crossing", "simulate_open_loop", "diagnose", "compare", "analytic_fallback",
            "PlantKind", "jsonable"} <= set(ocp.__all__)


def test_no_public_name_shadows_a_subpackage() -> None:
    packages = {p.name for p in (ROOT / "ocp").iterdir() if (p / "__init__.py").is_file()}
    assert packages and not packages & set(ocp.__all__)


def test_an_unknown_name_is_an_attribute_error() -> None:
    try:
        ocp.no_such_name  # noqa: B018
    except AttributeError as exc:
        assert "no_such_name" in str(exc)
    else:
        raise AssertionError("ocp.no_such_name resolved")


def test_importing_ocp_loads_nothing_heavy() -> None:
    code = "import sys, ocp; print([m for m in ('numpy', 'casadi', 'scipy', 'pydantic') if m in sys.modules])"
    run = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, check=True)
    assert json.loads(run.stdout.replace("'", '"')) == []
