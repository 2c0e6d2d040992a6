"""serve.py's command line: a wrong option or an unreadable dataset gives one line and a non-zero exit."""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from support import releases

REPO = Path(__file__).resolve().parents[2]


def _serve(*args: str, tmp_path: Path) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "serve.py", *args], cwd=REPO, capture_output=True, text=True, timeout=60,
                          env={"CBM_EXPLORER_PRESETS": str(tmp_path), "PATH": "/usr/bin:/bin"})


@pytest.mark.parametrize("args, words", [
    (("--no-such-option",), "unrecognized arguments"),
    (("--port", "eighty"), "invalid int value"),
    (("--dataset", "no/such/folder"), "does not exist"),
    (("--preset", "no-such-preset"), "not found"),
    (("--dataset", "tests/loaders/fixtures/opv2v/scenario", "--detections", "no/such/stage1_boxes.json"),
     "stage1_boxes.json"),
])
def test_bad_input_is_one_line_and_a_nonzero_exit(args: tuple[str, ...], words: str, tmp_path: Path) -> None:
    done = _serve(*args, tmp_path=tmp_path)
    assert done.returncode != 0
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and words in lines[0] and "Traceback" not in done.stderr


def test_unreadable_dataset_file(tmp_path: Path) -> None:
    bad = tmp_path / "scene.csv"
    bad.write_text("this is not,a table\n1,2,3\n")
    done = _serve("--dataset", str(bad), tmp_path=tmp_path)
    assert done.returncode != 0 and len(done.stderr.strip().splitlines()) == 1 and "Traceback" not in done.stderr


def test_a_loader_warning_is_one_line(tmp_path: Path) -> None:
    """A DAIR-V2X subset without world calibration: the loader's note on the console is one line,
    not Python's ``UserWarning`` with a file name and a source line."""
    root = releases.dair_release(tmp_path / "cooperative-vehicle-infrastructure", world_calib=False)
    done = _serve("--dataset", str(root), "--preset", "no-such-preset", tmp_path=tmp_path)
    lines = done.stderr.strip().splitlines()
    assert done.returncode != 0 and len(lines) == 2, done.stderr
    assert lines[0].startswith("serve.py: warning: 3 of 3 pair(s) ship no world calibration")
    assert "UserWarning" not in done.stderr and "dispatch.py" not in done.stderr
