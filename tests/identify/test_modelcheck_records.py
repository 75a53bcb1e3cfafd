"""``bench/modelcheck.py`` on recorded runs: ``--records`` re-tabulates ``--json`` files (merged by seed) without
diagnosing, ``--compare`` lists seed by seed what a change fixed and broke -- how a change to the identifier is judged
(README, Model check). Hand-made records; the module is loaded from its file (``bench`` is no package)."""

from __future__ import annotations

import argparse
import importlib.util
import json
from pathlib import Path
from types import ModuleType
from typing import Any

import pytest

BENCH = Path(__file__).resolve().parents[2] / "bench" / "modelcheck.py"


def _bench() -> ModuleType:
    spec = importlib.util.spec_from_file_location("modelcheck_bench", BENCH)
    assert spec is not None and spec.loader is not None
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def _rec(seed: int, expected: list[str], verdict: list[str]) -> dict[str, Any]:
    return {"seed": seed, "kind": "one" if expected else "clean", "expected": expected, "verdict": verdict,
            "error": None, "ambiguous": False, "rate": 1000.0, "n": 3000, "speed": "encoder", "excitations": ["prbs"],
            "true_lag": 1.0, "alignment": 1.0, "constant_error": {}, "t_generate": 0.1, "t_diagnose": 0.5}


OLD = [_rec(1, ["stribeck"], []), _rec(2, ["cogging"], ["cogging"]), _rec(3, [], []), _rec(4, ["B"], ["R"]),
       _rec(5, ["R"], ["R"])]
NEW = [_rec(1, ["stribeck"], ["stribeck"]), _rec(2, ["cogging"], []), _rec(3, [], ["param:L"]),
       _rec(4, ["B"], ["J"]), _rec(6, ["k"], ["k"])]


def test_compare_lists_what_a_change_fixed_and_broke() -> None:
    out = _bench().compare(OLD, NEW).splitlines()
    tags = {int(line.split()[1]): line.split()[0] for line in out[:-1]}
    assert tags == {1: "FIXED", 2: "BROKE", 3: "BROKE", 4: "CHANGED"}  # 5 unchanged; 6 in one run only
    assert out[-1] == "4 logs: exactly right 2 -> 1, false alarms on clean logs 0 -> 1"


def test_records_are_tabulated_merged_by_seed(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    a, b = tmp_path / "a.json", tmp_path / "b.json"
    a.write_text(json.dumps(OLD[:3]), encoding="utf-8")
    b.write_text(json.dumps([*OLD[3:], *NEW[4:]]), encoding="utf-8")
    assert _bench().main(["--records", str(a), str(b), "--misses"]) == 0
    out = capsys.readouterr().out
    assert "logs: 6   verdicts exactly right: 4/6 (66.7 %)" in out
    assert "seed    1 one" in out and "seed    4 one" in out and "seed    2" not in out


def test_the_alignment_error_is_tabulated_by_armature_and_filter() -> None:
    """The alignment block: found minus drawn lag on the logs without a delay whose lag was measured, grouped by the
    armature's L/R [samples] and the current filter; records written before those fields were recorded are left out,
    and a table of only such records has no alignment block."""
    def rec(seed: int, armature: float, filt: float, found: float, measured: bool = True,
            expected: tuple[str, ...] = ()) -> dict[str, Any]:
        return {**_rec(seed, list(expected), []), "true_lag": 1.0, "alignment": found, "align_measured": measured,
                "armature": armature, "current_filter": filt}

    rows = [rec(1, 0.2, 0.0, 1.1), rec(2, 0.3, 0.4, 0.2), rec(3, 3.0, 0.0, 2.2), rec(4, 3.0, 0.0, 0.0, False),
            rec(5, 3.0, 0.0, 9.0, expected=("input_delay",)), _rec(6, [], [])]
    lines = _bench().alignment_table(rows)
    assert "on the 3 of 4 logs without a delay whose lag was measured" in lines[1]
    table = {line[:24].strip(): line[24:].split() for line in lines[3:]}
    assert table["L/R 0-0.5 samples"] == ["2", "0.45", "-0.35", "1", "0"]  # errors +0.1 and -0.8
    assert table["L/R 2-7 samples"] == ["1", "1.20", "+1.20", "1", "1"]
    assert "L/R 0.5-2 samples" not in table
    assert table["no current filter"][0] == "2" and table["current filter"][0] == "1"
    assert table["all"] == ["3", "0.80", "+0.17", "2", "1"]
    assert _bench().alignment_table([_rec(7, [], [])]) == []
    assert "alignment (found - drawn lag" in _bench().table(rows)


def test_the_cache_is_keyed_by_the_generator(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A cached log is read back only by the proving ground that wrote it: the cache's subfolder is the digest of
    the generator's modules (not of its tests)."""
    mod = _bench()
    src = BENCH.parents[1] / "tests" / "proving_ground"
    copy = tmp_path / "tests" / "proving_ground"
    copy.mkdir(parents=True)
    for f in src.glob("*.py"):
        (copy / f.name).write_bytes(f.read_bytes())
    monkeypatch.setattr(mod, "ROOT", tmp_path)
    first = mod.generator_stamp()
    (copy / "test_more.py").write_text("x = 1\n")
    assert mod.generator_stamp() == first
    (copy / "physics.py").write_text((copy / "physics.py").read_text() + "\n# changed\n")
    assert mod.generator_stamp() != first


def test_a_forced_kind_is_its_own_draw_in_the_cache(tmp_path: Path) -> None:
    """``--kind``: seed ``s`` of a forced kind is ``make_case(s, kind)``, not the seed's own draw, and is cached apart
    from it (a cache written by a run without ``--kind`` must not answer one with it)."""
    import numpy as np

    from tests.proving_ground import make_case

    mod, seed = _bench(), 3046
    own, forced = mod.load_case(seed, str(tmp_path)), mod.load_case(seed, str(tmp_path), kind="constant")
    assert forced.kind == "constant" and own.kind != "constant"
    again = mod.load_case(seed, str(tmp_path), kind="constant")  # (read back from the cache)
    assert np.array_equal(again.columns["current"], make_case(seed, "constant").columns["current"])
    assert sorted(p.name for p in tmp_path.glob("*/*.pkl")) == [f"case-{seed}.pkl", f"constant-case-{seed}.pkl"]


def test_noise_free_records_the_same_run_without_noise() -> None:
    """``--noise-free``: the case's rig replayed under its logged commands and recorded by its logger without noise,
    quantisation or jitter. Oracle: the proving ground's own noiseless channels (``logged``) of that replay; and
    the original log differs from it by the logger's stated noise levels (the same run, its noise removed)."""
    import numpy as np

    from tests.proving_ground import make_case
    from tests.proving_ground.logger import logged, noise_levels

    case = make_case(10152)
    quiet = _bench().noise_free(case)
    assert quiet.expected == case.expected and np.array_equal(quiet.columns["voltage"], case.columns["voltage"])
    ref = logged(case.logger, _bench_replay(case))
    got = np.vstack([quiet.columns["omega"], quiet.columns["current"], quiet.columns["thrust"]])
    err = np.max(np.abs(got[:, 2:] - ref[:, 2:]), axis=1)
    assert np.all(err <= 1e-6 * np.max(np.abs(ref), axis=1)), err
    noisy = np.vstack([case.columns["omega"], case.columns["current"], case.columns["thrust"]])
    ratio = np.sqrt(np.mean((noisy - got) ** 2, axis=1)) / noise_levels(case.logger)
    assert np.all((ratio > 0.7) & (ratio < 1.3))  # (the stated levels, within sampling and rounding)


def test_no_angle_drops_only_the_encoder_angle() -> None:
    """``--no-angle``: an encoder log as a logger that exports only its differenced speed writes it. Oracle: the
    same arrays as with the angle, the angle left out; the speed stays the backward difference of that angle."""
    import numpy as np

    from tests.proving_ground import make_case

    case = next(c for c in map(make_case, range(10150, 10170)) if c.logger.speed == "encoder")
    full, bare = _bench().case_log(case), _bench().case_log(case, angle=False)
    assert full.theta is not None and bare.theta is None
    for ch in ("t", "voltage", "current", "omega", "thrust"):
        assert np.array_equal(getattr(full, ch), getattr(bare, ch))
    d, col = case.logger.diff_span, case.columns  # (as logged, before a jittery clock is resampled)
    diff = (col["theta"][d:] - col["theta"][:-d]) / (d * case.logger.dt)  # (the firmware divides by its period)
    assert np.allclose(col["omega"][d:], diff, rtol=1e-6, atol=1e-9)


def _bench_replay(case: Any) -> Any:
    from tests.proving_ground.cases import _replay

    return _replay(case.truth, case.columns["voltage"], case.logger, case.meta["tau_m"])


def test_audited_records_are_tabulated_with_the_absorbed_labels_optional(tmp_path: Path,
                                                                         capsys: pytest.CaptureFixture[str]) -> None:
    """Records carrying the audit (``--audit``: ``required``, the labels that show beyond calibration) are tabulated
    twice: on the labels as drawn, then with the others optional -- a verdict is right when it holds the required
    labels and nothing it was not drawn with; an optional label named is a true positive, one not named no miss."""
    rows = [{**_rec(1, ["brush_drop"], []), "required": []},  # optional, not named: right
            {**_rec(2, ["param:L", "stribeck"], ["stribeck"]), "required": ["stribeck"]},  # right
            {**_rec(3, ["param:k"], ["param:k"]), "required": []},  # optional, named: right either way
            {**_rec(4, ["cogging"], []), "required": ["cogging"]},  # a miss either way
            {**_rec(5, ["B"], ["B", "cogging"]), "required": []},  # a label never drawn: wrong either way
            {**_rec(6, [], []), "required": []}]
    path = tmp_path / "a.json"
    path.write_text(json.dumps(rows), encoding="utf-8")
    assert _bench().main(["--records", str(path)]) == 0
    drawn, audited = capsys.readouterr().out.split("with the labels calibration absorbs optional")
    assert "verdicts exactly right: 2/6 (33.3 %)" in drawn
    assert audited.startswith(" (4 of 6: 1:brush_drop, 2:param:L, 3:param:k, 5:B):")
    assert "verdicts exactly right: 4/6 (66.7 %)" in audited and "clean logs: 1   false alarms: 0" in audited
    rows_ = audited.split("recall")[1].split("\n\n")[0].splitlines()[1:]
    matrix = {line.split()[0]: line.split()[1:4] for line in rows_}
    assert "brush_drop" not in matrix and "param:L" not in matrix  # (optional, not named: no count anywhere)
    assert matrix["param:k"] == ["1", "0", "0"] and matrix["cogging"] == ["0", "1", "1"]


def test_the_audit_of_a_drawn_case_is_kept_in_the_cache(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """``--audit`` on proving-ground seed 3 (a wake lag and a 0.27 V brush drop under a two-level PRBS of 4.83 V: the
    drop is ``R`` and ``k`` scaled by 1 / (1 - 0.27 / 4.83), 5.9 %, within the tolerance): the brush drop is optional,
    the wake lag required; the audit is written under the cache and read back from there."""
    from tests.proving_ground import calibration

    mod = _bench()
    rec = _rec(3, ["brush_drop", "thrust_lag"], ["thrust_lag"])
    out = mod.audited(rec, str(tmp_path))
    assert max(out["footprints"]["brush_drop"]) < 0.1 and max(out["footprints"]["thrust_lag"]) > 10.0
    assert out["required"] == ["thrust_lag"] and mod.right(out, optional=True) and not mod.right(out)

    def fail(case: Any) -> None:
        raise AssertionError("audited again")

    monkeypatch.setattr(calibration, "audit", fail)
    assert mod.audited(rec, str(tmp_path))["footprints"] == out["footprints"]


def test_a_run_takes_the_seeds_asked_for_or_a_range() -> None:
    """``--seeds`` names the logs (a class of them, judged before and after a change), each once, in order; without
    it ``--n`` logs from ``--first``."""
    bench = _bench()
    args = argparse.Namespace(seeds=[9204, 6003, 9204], n=200, first=0)
    assert bench.seeds(args) == [6003, 9204]
    assert bench.seeds(argparse.Namespace(seeds=None, n=3, first=13000)) == [13000, 13001, 13002]


def test_the_noise_levels_read_are_tabulated_by_clock() -> None:
    """The noise block: per channel the median of the levels read over the logger's own and the share within 10 %,
    regular clocks and jittered ones apart; records without ``noise_ratio`` (older, or noise-free) are left out, and a
    table of only such records has no noise block."""
    def rec(seed: int, jitter: float, omega: float, current: float, thrust: float) -> dict[str, Any]:
        return {**_rec(seed, [], []), "jitter": jitter,
                "noise_ratio": {"omega": omega, "current": current, "thrust": thrust}}

    rows = [rec(1, 0.0, 1.0, 1.05, 0.5), rec(2, 0.0, 2.0, 1.2, 1.0), rec(3, 0.01, 0.7, 0.95, 1.08),
            {**_rec(4, [], []), "jitter": 0.0, "noise_ratio": None}, _rec(5, [], [])]
    lines = _bench().noise_table(rows)
    assert lines[1].startswith("noise levels read / the logger's own")
    table = {line[:24].strip(): line[24:].split() for line in lines[3:]}
    assert table["regular clock"] == ["2", "1.50", "50", "%", "1.12", "50", "%", "0.75", "50", "%"]
    assert table["jittered, resampled"] == ["1", "0.70", "0", "%", "0.95", "100", "%", "1.08", "100", "%"]
    assert _bench().noise_table([_rec(6, [], [])]) == []
    assert "noise levels read" in _bench().table(rows)


def test_a_record_holds_the_noise_levels_read_against_the_loggers_own() -> None:
    """A diagnosed record (``one``) holds its clock's jitter, the ambiguity pairs and the noise levels read over the
    logger's own; on a regular clock the load cell's level is read within 10 % (oracle: the proving ground's
    ``noise_levels``, its white noise and ADC step; 13 of 13 regular logs among seeds 0..29)."""
    r = _bench().one(5)
    assert r["jitter"] == 0.0 and isinstance(r["pairs"], list)
    assert set(r["noise_ratio"]) == {"omega", "current", "thrust"}
    assert r["noise_ratio"]["thrust"] == pytest.approx(1.0, rel=0.1)


@pytest.mark.xfail(strict=True, reason="known: a jittered clock is resampled onto a grid of its first stamp and the "
                   "median step, which drifts off the rows (half a sample over 6,000 rows of 1 % jitter) and averages "
                   "neighbouring samples; the load cell's level is read 38 % low here (29 % of jittered logs among "
                   "seeds 0..29 within 10 %; docs/model-check-history.md, session 76)")
def test_a_jittered_clocks_noise_levels_are_read_as_a_regular_ones() -> None:
    """Seed 4 (5,998 rows at 1 % time-stamp jitter): the load cell's noise level read within 10 % of the logger's, as
    on a regular clock (the test above)."""
    r = _bench().one(4)
    assert r["jitter"] > 0.0
    assert r["noise_ratio"]["thrust"] == pytest.approx(1.0, rel=0.1)
