"""evaluate.py's paths inside a folder the user may not open (issue 27, the pattern of row 9): a
``--preset`` file, ``--out`` of a run, of a calibration check and of ``compare`` are one line naming
the folder, status 2 (each was a ``PermissionError`` traceback from ``Path.exists``)."""
import json
import subprocess
import sys
from pathlib import Path

import pytest

from tests.support.privileges import obeying_permissions

REPO = Path(__file__).resolve().parents[2]
CASES = {
    "--preset": ["--preset", "{closed}/mine.toml", "--out", "{tmp}/results"],
    "--out": ["--dataset", "synthetic:5", "--out", "{closed}/results"],
    "--check-calibration --out": ["--dataset", "synthetic:5", "--check-calibration", "--out", "{closed}/check"],
    "compare --out": ["compare", "{tmp}/run", "{tmp}/run", "--out", "{closed}/cmp"],
}


@pytest.mark.parametrize("case", list(CASES))
def test_a_path_in_a_folder_that_cannot_be_opened_is_one_line_naming_it(case: str, tmp_path: Path) -> None:
    preexec = obeying_permissions()
    closed = tmp_path / "closed"
    closed.mkdir()
    (closed / "mine.toml").write_text("[cbm]\nsigma2 = 2\n")
    (tmp_path / "run").mkdir()
    (tmp_path / "run" / "metrics.json").write_text(json.dumps({"cbm": {"precision": 1.0}}))
    closed.chmod(0)
    args = [a.format(closed=closed, tmp=tmp_path) for a in CASES[case]]
    done = subprocess.run([sys.executable, "evaluate.py", *args], cwd=REPO, capture_output=True, text=True,
                          timeout=300, preexec_fn=preexec)
    closed.chmod(0o755)
    assert done.returncode == 2 and done.stderr.count("\n") == 1 and "Traceback" not in done.stderr, done.stderr
    assert done.stderr.endswith(f": {closed}: cannot open the folder (Permission denied)\n"), done.stderr
    assert sorted(p.name for p in closed.iterdir()) == ["mine.toml"]
