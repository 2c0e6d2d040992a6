"""A dataset that cannot be read is one line naming it, status 2, in both commands (issue 27, rows
8-10): a device or FIFO given as the dataset (never opened, so never blocking), a folder, subfolder
or file the user may not read, a synthetic name whose count or seed is out of range."""
from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from tests.support.privileges import obeying_permissions

REPO = Path(__file__).resolve().parents[2]
FIXTURES = REPO / "tests" / "loaders" / "fixtures"
COMMANDS = {
    "evaluate.py": ["evaluate.py", "--workers", "1", "--methods", "icp", "--out"],
    "serve.py": ["serve.py", "--port", "0", "--preset"],
}
"""Each command up to its last option, whose value the test adds (a fresh --out, the default preset)."""


def fifo(tmp: Path) -> str:
    os.mkfifo(tmp / "boxes.csv")
    return str(tmp / "boxes.csv")


def closed_folder(tmp: Path) -> str:
    shutil.copytree(FIXTURES / "sind" / "Xian_412_m1", tmp / "sind")
    (tmp / "sind").chmod(0)
    return str(tmp / "sind")


def inside_a_closed_folder(tmp: Path) -> str:
    shutil.copytree(FIXTURES / "sind" / "Xian_412_m1", tmp / "closed" / "sind")
    (tmp / "closed").chmod(0)
    return str(tmp / "closed" / "sind")


def closed_subfolder(tmp: Path) -> str:
    shutil.copytree(FIXTURES / "opv2v" / "scenario", tmp / "scenario")
    (tmp / "scenario" / "641").chmod(0)
    return str(tmp / "scenario")


def closed_file(tmp: Path) -> str:
    shutil.copytree(FIXTURES / "sind" / "Xian_412_m1", tmp / "sind")
    (tmp / "sind" / "Ped_smoothed_tracks.csv").chmod(0)
    return str(tmp / "sind")


CASES = {
    "/dev/null": (lambda tmp: "/dev/null", "dataset path '/dev/null' is a character device, not a file or folder"),
    "a FIFO": (fifo, "boxes.csv' is a FIFO (named pipe), not a file or folder"),
    "an unreadable folder": (closed_folder, "/sind: cannot open the folder (Permission denied)"),
    "a dataset inside an unreadable folder": (
        inside_a_closed_folder, "{tmp}/closed/sind': {tmp}/closed: cannot open the folder (Permission denied)"),
    "an unreadable subfolder": (closed_subfolder, "/scenario/641: cannot open the folder (Permission denied)"),
    "an unreadable file": (closed_file, "/sind/Ped_smoothed_tracks.csv: cannot read the file"),
    "a negative seed": (lambda tmp: "synthetic:5:seed=-1",
                        "synthetic:5:seed=-1: seed must be a non-negative integer, got -1"),
    "too many objects": (lambda tmp: "synthetic:2001", "synthetic:2001: count must be from 0 to 2000, got 2001"),
}
NEED_PERMISSIONS = {"an unreadable folder", "a dataset inside an unreadable folder", "an unreadable subfolder",
                    "an unreadable file"}


@pytest.mark.parametrize("command", list(COMMANDS))
@pytest.mark.parametrize("case", list(CASES))
def test_a_dataset_that_cannot_be_read_is_one_line_naming_it(case: str, command: str, tmp_path: Path) -> None:
    make, message = CASES[case]
    dataset, message = make(tmp_path), message.format(tmp=tmp_path)
    last = str(tmp_path / "results") if command == "evaluate.py" else "default"
    preexec = obeying_permissions() if case in NEED_PERMISSIONS else None
    done = subprocess.run([sys.executable, *COMMANDS[command], last, "--dataset", dataset], cwd=REPO,
                          capture_output=True, text=True, timeout=300, preexec_fn=preexec,
                          env={**os.environ, "CBM_EXPLORER_PRESETS": str(tmp_path / "presets")})
    for path in tmp_path.rglob("*"):
        path.chmod(0o755)
    lines = done.stderr.strip().splitlines()
    assert done.returncode == 2, done.stderr
    assert len(lines) == 1 and "Traceback" not in done.stderr and message in lines[0], done.stderr
    assert lines[0].startswith(f"{command}: error: ") and not (tmp_path / "results").exists()
