"""Every writer of evaluate.py on a full disk: one line naming the folder, status 2, nothing new left
behind and the files there before untouched. The disk fills up while the plot is written, the last
file: the table and the markdown are complete by then and must not be left alone (issue 40, item 2)."""
from __future__ import annotations

from pathlib import Path

import matplotlib.figure
import pytest

import evaluation.cli
from support import releases

QUICK = ["--dataset", "synthetic:40", "--frames", "0:2", "--methods", "icp", "--workers", "1", "--no-timing"]


def disk_full(*args, **kwargs):
    raise OSError(28, "No space left on device")


def contents(folder: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in folder.iterdir()} if folder.exists() else {}


def refused_in_one_line(capsys, argv: list[str], folder: Path) -> None:
    with pytest.raises(SystemExit) as stop:
        evaluation.cli.main(argv)
    err = capsys.readouterr().err
    assert stop.value.code == 2 and err.count("\n") == 1, err
    assert "No space left on device" in err and str(folder) in err and "Traceback" not in err


@pytest.fixture
def calibration_release(tmp_path) -> Path:
    return releases.dair_release(tmp_path / "cooperative-vehicle-infrastructure")


def test_the_calibration_check_on_a_full_disk_leaves_no_table_and_no_markdown(calibration_release, tmp_path, capsys,
                                                                            monkeypatch):
    out = tmp_path / "check"
    monkeypatch.setattr(matplotlib.figure.Figure, "savefig", disk_full)
    refused_in_one_line(capsys, ["--dataset", str(calibration_release), "--check-calibration", "--out", str(out)],
                        out)
    assert not out.exists()


def test_the_calibration_check_on_a_full_disk_keeps_the_earlier_check(calibration_release, tmp_path, capsys,
                                                                     monkeypatch):
    out = tmp_path / "check"
    argv = ["--dataset", str(calibration_release), "--check-calibration", "--out", str(out)]
    assert evaluation.cli.main(argv) == 0
    before = contents(out)
    capsys.readouterr()
    monkeypatch.setattr(matplotlib.figure.Figure, "savefig", disk_full)
    refused_in_one_line(capsys, argv, out)
    assert contents(out) == before


def test_compare_on_a_full_disk_leaves_no_markdown(tmp_path, capsys, monkeypatch):
    a, b = tmp_path / "a", tmp_path / "b"
    for run in (a, b):
        assert evaluation.cli.main([*QUICK, "--out", str(run)]) == 0
    out = tmp_path / "comparison"
    capsys.readouterr()
    monkeypatch.setattr(matplotlib.figure.Figure, "savefig", disk_full)
    refused_in_one_line(capsys, ["compare", str(a), str(b), "--out", str(out)], out)
    assert not out.exists()
