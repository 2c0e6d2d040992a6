"""The dataset-calibration check (``evaluate.py --check-calibration``) on DAIR-V2X-C releases written
in their published layout: a shipped infrastructure transform 1.5 m off in one pair is flagged, the
correct pairs are not, by the oracle and by CBM alike."""
from __future__ import annotations

import csv
import subprocess
import sys
from pathlib import Path

import pytest

import loaders
from evaluation import calibration_check
from evaluation.calibration_check import Thresholds, check_sequence
from evaluation.cli import main
from support import releases

REPO = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def shifted(tmp_path_factory) -> Path:
    root = tmp_path_factory.mktemp("dair") / "cooperative-vehicle-infrastructure"
    return releases.dair_release(root, pairs=3, infra_error=(1.5, 0.0))


def test_a_shifted_pair_is_flagged_and_the_others_are_not(shifted):
    rows = check_sequence(loaders.open(shifted), [0, 1, 2])
    assert [(row.frame_id, row.ego, row.cav) for row in rows] == [
        ("000010", "vehicle", "infrastructure"), ("000011", "vehicle", "infrastructure"),
        ("000012", "vehicle", "infrastructure")]
    assert [row.flagged for row in rows] == [False, False, True]
    good, bad = rows[0], rows[2]
    assert good.judged_by == "oracle" and good.shared >= 3 and good.oracle_m < 1e-6 and good.cbm_m < 1e-6
    # the shift of the shipped transform, seen from the vehicle: 1.5 m, found by the labels alone
    assert bad.cbm_m == pytest.approx(1.5, abs=1e-6) and bad.cbm_deg == pytest.approx(0.0, abs=1e-6)
    assert bad.cbm_pairs >= 3


def test_thresholds_decide_what_is_flagged(shifted):
    rows = check_sequence(loaders.open(shifted), [2], Thresholds(metres=2.0, degrees=1.0))
    assert not rows[0].flagged


def test_datasets_without_per_agent_labels_are_refused():
    with pytest.raises(ValueError, match="keeps no per-agent labels"):
        check_sequence(loaders.open("synthetic:20"), [0])


def test_cli_writes_table_plot_and_flagged_frames(shifted, tmp_path, capsys):
    out = tmp_path / "check"
    assert main(["--dataset", str(shifted), "--check-calibration", "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert printed.startswith("1 of 3 frames checked disagrees with the dataset's transform by more than 1 m")
    assert "| 2 | 000012 | vehicle | infrastructure |" in printed
    with (out / "calibration_check.csv").open() as file:
        table = list(csv.DictReader(file))
    assert [row["flagged"] for row in table] == ["False", "False", "True"]
    assert (out / "calibration_check.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert (out / "calibration_flagged.md").read_text() == printed
    assert main(["--dataset", str(shifted), "--check-calibration", "0.5,0.5", "--out", str(out)]) == 0


@pytest.mark.parametrize("args, message", [
    (["--check-calibration", "1"], "--check-calibration: expected METRES,DEGREES such as 1,1, got '1'"),
    (["--check-calibration", "0,1"], "thresholds must be finite and positive"),
    (["--check-calibration", "--dataset", "synthetic:5"], "keeps no per-agent labels"),
])
def test_cli_bad_input_is_one_line_and_exit_2(args, message, tmp_path):
    done = subprocess.run([sys.executable, str(REPO / "evaluate.py"), *args, "--out", str(tmp_path / "o")],
                          capture_output=True, text=True, cwd=REPO)
    assert done.returncode == 2 and message in done.stderr
    assert "Traceback" not in done.stderr


def test_out_holding_other_files_is_refused(tmp_path):
    (tmp_path / "notes.txt").write_text("mine")
    with pytest.raises(ValueError, match="holds other files"):
        calibration_check.check_out_folder(tmp_path)
