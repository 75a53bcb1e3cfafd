"""The Model check tab says what a log cannot show (headless Chromium, real server): a proving-ground rig with a
hidden voltage dead band logged under random steps between +-0.6 V_max (one voltage magnitude, where the dead band
is a gain on the command); the diagnosis misses it and the page says the log cannot show a dead band or a brush
drop, and why, beside the verdict, and lists a gain on the command as the rival of what it named; a thrust stand
swept forward only, that it cannot show an asymmetry."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from ocp.logs import write_log_csv
from tests.logfiles import Thruster, thruster_sweep, write_csv
from tests.page.test_page import diagnose_on_page
from tests.proving_ground.experiment import draw, run_command, voltage_steps
from tests.rig_log import rig_log
from tests.service.test_service_support import Server

pytestmark = pytest.mark.integration


def test_the_page_says_a_two_level_log_cannot_show_a_dead_band(page: Any, server: Server, tmp_path: Path) -> None:
    rig = draw(0, "voltage_deadband")
    t, v = voltage_steps(rig, 0, levels=(-1.0, 1.0))
    write_log_csv(rig_log(run_command(rig, t, v, 1)), tmp_path / "two-level.csv")
    diagnose_on_page(page, server, tmp_path / "two-level.csv", rig.nominal)
    blind = page.locator("#m-blind")
    assert blind.count() >= 1
    text = " ".join(blind.nth(k).inner_text() for k in range(blind.count()))
    assert "This log cannot show voltage_deadband, brush_drop" in text and "one voltage magnitude" in text
    assert text.endswith("Design the experiment to show them.")
    # the constants it named for the dead band are listed beside their rival, one gain on the command
    gain = page.locator("#m-ambiguous", has_text="command_gain")
    assert gain.count() == 1 and "a measured terminal voltage does" in gain.inner_text()


def test_the_page_says_a_forward_only_esc_sweep_cannot_show_an_asymmetry(page: Any, server: Server,
                                                                         tmp_path: Path) -> None:
    """An ESC thrust stand swept forward only (the upper half of the PWM range): no design is offered for it (a
    sweep is checked point by point), only what it cannot show."""
    th = Thruster(ratio=0.8)
    rows = thruster_sweep(th)
    forward = rows["PWM (µs)"] > 1525.0
    write_csv({k: v[forward] for k, v in rows.items()}, tmp_path / "forward.csv", title="Thruster at 16 V")
    diagnose_on_page(page, server, tmp_path / "forward.csv", th.params())
    text = page.inner_text("#m-blind")
    assert text == "This log cannot show drag_asymmetry, thrust_asymmetry: the log never reverses."


def test_the_page_notes_a_clipped_current(page: Any, server: Server, tmp_path: Path) -> None:
    """A clean proving-ground log with its current clipped at 45 % of its peak (``ocp/identify/clipping.py``): the
    page notes the clipped rows the diagnosis left out (a note, nothing hidden, no experiment to design)."""
    from tests.identify.test_clipped_current import _clipped_log
    from tests.proving_ground import make_case

    log, _ = _clipped_log(64)
    write_log_csv(log, tmp_path / "clipped.csv")
    diagnose_on_page(page, server, tmp_path / "clipped.csv", make_case(64).nominal)
    blind = page.locator("#m-blind")
    lines = [blind.nth(k).inner_text() for k in range(blind.count())]
    (note,) = [t for t in lines if "clipped" in t]
    assert note.startswith("Note: the current is clipped at") and "left out of every equation" in note
    assert "This log cannot show" not in note and not note.endswith("Design the experiment to show them.")
