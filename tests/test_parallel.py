"""Independent pieces in threads (:mod:`ocp.parallel`): results in the items' order, a bounded number ahead, errors
raised at their item's turn, BLAS held to one thread, and the ripple's period search (the pieces it runs in threads)
giving the same diagnosis to the last bit however many threads run it."""

from __future__ import annotations

import importlib
import threading
import time

import numpy as np
import pytest
from pydantic import ValidationError
from threadpoolctl import threadpool_info

from ocp.errors import ParameterError
from ocp.identify import check, diagnose, fit
from ocp.logs import log_from_arrays
from ocp.logs.timebase import uniform
from ocp.model.params import MotorParams
from ocp.model.plant import DCMotorPlant
from ocp.parallel import MAX_THREADS, one_blas_thread, ordered, threads
from service.settings import Settings
from tests.proving_ground import make_case


@pytest.mark.parametrize("workers", [1, 2, 3])
def test_ordered_yields_in_the_items_order_and_starts_few_ahead(workers: int) -> None:
    started: list[int] = []
    lock = threading.Lock()
    consumed = 0
    ahead = 0

    def piece(i: int) -> int:
        nonlocal ahead
        with lock:
            started.append(i)
            ahead = max(ahead, len(started) - consumed)
        time.sleep(0.002 * ((7 * i) % 5))  # (unequal pieces: later ones finish first)
        return i * i

    out = []
    for r in ordered(piece, range(40), workers):
        out.append(r)
        consumed += 1
    assert out == [i * i for i in range(40)]
    assert sorted(started) == list(range(40))
    assert ahead <= workers + 1  # results waiting to be consumed stay few


def test_an_error_is_raised_at_its_items_turn() -> None:
    def piece(i: int) -> int:
        if i == 5:
            raise ArithmeticError("piece 5")
        return i

    got = []
    with pytest.raises(ArithmeticError, match="piece 5"):
        for r in ordered(piece, range(20), 2):
            got.append(r)
    assert got == [0, 1, 2, 3, 4]


def test_threads_reads_the_environment_at_each_call(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv("THRUSTSHAPE_THREADS", raising=False)
    assert 1 <= threads() <= MAX_THREADS
    monkeypatch.setenv("THRUSTSHAPE_THREADS", "3")
    assert threads() == 3
    for bad in ("0", "-2", "two", "1.5", "²"):
        monkeypatch.setenv("THRUSTSHAPE_THREADS", bad)
        with pytest.raises(ParameterError) as err:
            threads()
        assert err.value.field == "THRUSTSHAPE_THREADS" and repr(bad) in err.value.reason


@pytest.mark.parametrize("entry", ["diagnose", "check", "fit"])
def test_a_bad_thread_setting_stops_the_model_check_before_any_work(entry: str,
                                                                    monkeypatch: pytest.MonkeyPatch) -> None:
    """Each entry point whose work runs pieces in threads (:func:`ocp.parallel.own_threads`) names the setting before
    its first step (``dynamic(log)``, made to fail here if it is reached)."""
    def started(_: object) -> bool:
        raise AssertionError(f"{entry} started before the thread setting was checked")

    monkeypatch.setattr(importlib.import_module(f"ocp.identify.{entry}"), "dynamic", started)
    monkeypatch.setenv("THRUSTSHAPE_THREADS", "many")
    log = log_from_arrays(np.arange(200) * 1e-3, np.ones(200), np.ones(200), np.ones(200), omega=np.ones(200))
    plant = DCMotorPlant(MotorParams(**make_case(1182).nominal))
    calls = {"diagnose": lambda: diagnose(plant, log), "check": lambda: check(plant, log),
             "fit": lambda: fit(plant, log, ["coulomb_friction"])}
    with pytest.raises(ParameterError, match="THRUSTSHAPE_THREADS"):
        calls[entry]()


def test_the_server_refuses_to_start_with_a_bad_thread_setting(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("THRUSTSHAPE_THREADS", "0")
    with pytest.raises(ValidationError, match="threads"):
        Settings()
    monkeypatch.setenv("THRUSTSHAPE_THREADS", "3")
    assert Settings().threads == 3


def _blas_threads() -> list[int]:
    return [int(d["num_threads"]) for d in threadpool_info() if d["user_api"] == "blas"]


def test_one_blas_thread_holds_blas_to_one_and_restores_it() -> None:
    before = _blas_threads()
    assert before  # (NumPy's BLAS is loaded)
    with one_blas_thread():
        assert _blas_threads() == [1] * len(before)
    assert _blas_threads() == before


def test_the_diagnosis_is_the_same_to_the_last_bit_with_one_thread_or_three(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """Proving-ground tuning draw 1182 (a tachometer log, no angle column: each of the 64 counts' phases tracked
    along the integrated angle, the period search's heaviest pieces)."""
    case = make_case(1182)
    assert "theta" not in case.columns
    t, c, _ = uniform(case.columns["t"], {k: v for k, v in case.columns.items() if k != "t"}, resample=True)
    log = log_from_arrays(t, c["voltage"], c["current"], c["thrust"], omega=c["omega"])
    plant = DCMotorPlant(MotorParams(**case.nominal))
    results = []
    for n in ("1", "3"):
        monkeypatch.setenv("THRUSTSHAPE_THREADS", n)
        results.append(diagnose(plant, log).to_dict())
    assert results[0]["verdict"] == ["cogging"]
    assert results[0] == results[1]
    spectrum = np.asarray(results[0]["angle_periodic"]["shares"])
    assert spectrum.shape == (64,) and int(np.argmax(spectrum)) + 1 == results[0]["angle_periodic"]["periods"]
