"""evaluate.py with inputs that would grow without bound (issue 27): each is checked against the
dataset before it is expanded, so a run under a memory cap ends with one line naming the input."""
import resource
import subprocess
import sys
from pathlib import Path

import pytest

from evaluation.cli import CliError, parse_frames

REPO = Path(__file__).resolve().parents[2]
MEMORY_CAP = 1500 * 2**20
"""Bytes of address space: enough to start evaluate.py and refuse its input, far from enough to expand it."""


def run_capped(*args: str, cap: int = MEMORY_CAP, timeout: float = 300) -> subprocess.CompletedProcess:
    """``evaluate.py ARGS`` in a subprocess whose address space is capped at ``cap`` bytes."""
    def limit() -> None:
        resource.setrlimit(resource.RLIMIT_AS, (cap, cap))
    return subprocess.run([sys.executable, str(REPO / "evaluate.py"), *args], cwd=REPO, preexec_fn=limit,
                          capture_output=True, text=True, timeout=timeout)


@pytest.mark.parametrize(("frames", "first_outside"), [
    ("0:1000000000000", "50"), ("3,0:10000000:7", "56"), ("1" + "0" * 40, "1" + "0" * 40)])
def test_a_huge_frame_range_is_refused_before_it_is_expanded(tmp_path, frames: str, first_outside: str) -> None:
    done = run_capped("--dataset", "synthetic:5", "--frames", frames, "--out", str(tmp_path / "out"))
    assert done.returncode == 2, done.stderr
    assert done.stderr.strip().splitlines() == [
        f"evaluate.py: error: --frames: frame {first_outside} is out of range: the dataset has 50 frames (0 to 49)"]


def test_parse_frames_names_the_first_frame_out_of_range_without_expanding() -> None:
    assert parse_frames("0:10:3,4", 50) == [0, 3, 4, 6, 9]
    with pytest.raises(CliError, match="frame 52 is out of range"):
        parse_frames("3:10000000000000000000000:7", 50)
    with pytest.raises(CliError, match="frame 60 is out of range"):
        parse_frames("60:70,70", 50)
    with pytest.raises(CliError, match="selects no frame"):
        parse_frames("5:5", 50)
