"""Decompression bounds checked before decoding (ocp.logs.bounds): .mat and .xlsx, against what the files
really expand to (oracle: scipy's own reader and zipfile's inflated members)."""

from __future__ import annotations

import zipfile
from pathlib import Path

import numpy as np
import pytest
import scipy.io as sio

from ocp.errors import LogError
from ocp.logs import check_size, read_table
from ocp.logs.bounds import BYTES_PER_ROW


def _mat(path: Path, n: int, compress: bool) -> Path:
    sio.savemat(path, {"log": {"t": np.arange(n) * 1e-3, "rpm": np.zeros(n)}, "note": np.ones(3)},
                do_compression=compress)
    return path


@pytest.mark.parametrize("compress", [True, False])
def test_mat_budget_is_the_inflated_size(tmp_path: Path, compress: bool) -> None:
    """Two 20,000-sample columns take 320,000 bytes decoded: a budget of 600 rows (307,200 bytes) refuses the file,
    one of 700 rows (358,400 bytes) accepts it, and the accepted file still reads in full."""
    path = _mat(tmp_path / "log.mat", 20_000, compress)
    assert BYTES_PER_ROW[".mat"] * 600 < 2 * 8 * 20_000 < BYTES_PER_ROW[".mat"] * 700
    with pytest.raises(LogError) as err:
        check_size(path, max_rows=600)
    assert err.value.field == "log" and "MATLAB" in err.value.reason
    check_size(path, max_rows=700)
    assert read_table(path)["t"].size == 20_000


def test_a_mat_bomb_is_refused_without_inflating_it(tmp_path: Path) -> None:
    """16 MB of zeros compress to a few kB; a 1,000-row budget stops the count after about one 1 MiB chunk."""
    path = tmp_path / "bomb.mat"
    sio.savemat(path, {"t": np.zeros(1_000_000), "rpm": np.zeros(1_000_000)}, do_compression=True)
    assert path.stat().st_size < 100_000
    with pytest.raises(LogError, match="expands to more than"):
        check_size(path, max_rows=1_000)


def test_a_corrupt_compressed_mat_element_names_the_log(tmp_path: Path) -> None:
    path = _mat(tmp_path / "log.mat", 2_000, True)
    raw = bytearray(path.read_bytes())
    raw[140:180] = b"\xff" * 40  # inside the first compressed element's zlib stream
    path.write_bytes(bytes(raw))
    with pytest.raises(LogError) as err:
        check_size(path)
    assert err.value.field == "log" and "corrupt" in err.value.reason


def test_xlsx_budget_is_the_members_uncompressed_size(tmp_path: Path) -> None:
    """A zip whose one member inflates to 1 MB of XML: refused below 1 MB of budget, accepted above."""
    path = tmp_path / "book.xlsx"
    with zipfile.ZipFile(path, "w", compression=zipfile.ZIP_DEFLATED) as z:
        z.writestr("xl/worksheets/sheet1.xml", " " * 1_000_000)
    with zipfile.ZipFile(path) as z:  # the oracle: what the member really inflates to
        inflated = len(z.read("xl/worksheets/sheet1.xml"))
    assert path.stat().st_size < 10_000 and inflated == 1_000_000
    with pytest.raises(LogError, match="xlsx"):
        check_size(path, max_rows=inflated // BYTES_PER_ROW[".xlsx"] - 1)
    check_size(path, max_rows=inflated // BYTES_PER_ROW[".xlsx"] + 1)


def test_a_workbook_within_its_budget_reads(tmp_path: Path) -> None:
    openpyxl = pytest.importorskip("openpyxl")
    wb = openpyxl.Workbook()
    ws = wb.active
    ws.append(["Time (s)", "RPM", "Thrust (N)"])
    for k in range(200):
        ws.append([k * 0.01, 1000.0 + k, 0.1])
    path = tmp_path / "sweep.xlsx"
    wb.save(path)
    check_size(path, max_rows=1_000)
    assert len(next(iter(read_table(path).values()))) == 200


def test_uncompressed_formats_are_not_checked(tmp_path: Path) -> None:
    path = tmp_path / "log.csv"
    path.write_text("t,rpm\n" + "0,1\n" * 1_000)
    check_size(path, max_rows=1)  # a CSV's file size is its bound: nothing to refuse here
