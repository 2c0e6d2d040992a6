"""``evaluate.py compare`` on run folders it did not write (issue 27, row 7): every bad file or
``--out`` is one line naming the file and the field, exit status 2, never a traceback; two runs of
different datasets or protocols are compared with a warning."""
import json
import os
import subprocess
import sys
from pathlib import Path

import polars as pl
import pytest

from tests.support.privileges import obeying_permissions

REPO = Path(__file__).resolve().parents[2]
GOOD_CURVE = "rte_max_m,rre_max_deg,cbm\n0.5,0.5,0.25\n1.0,1.0,0.5\n"


def write_run(folder: Path, metrics: str | None = None, curve: str | bytes = GOOD_CURVE) -> Path:
    """A run folder with ``metrics.json`` (text as given, default a valid one) and ``success_curve.csv``."""
    folder.mkdir()
    (folder / "metrics.json").write_text(metrics or json.dumps({"cbm": {"precision": 0.9, "median_rte": None}}))
    path = folder / "success_curve.csv"
    path.write_bytes(curve) if isinstance(curve, bytes) else path.write_text(curve)
    return folder


def metrics_case(text: str):
    return lambda b: (b / "metrics.json").write_text(text)


def curve_case(content: str | bytes):
    def setup(b: Path) -> None:
        path = b / "success_curve.csv"
        path.write_bytes(content) if isinstance(content, bytes) else path.write_text(content)
    return setup


def fifo_curve(b: Path) -> None:
    (b / "success_curve.csv").unlink()
    os.mkfifo(b / "success_curve.csv")


CASES = {
    "text value": (metrics_case('{"cbm": {"precision": "high"}}'), "metrics.json: cbm.precision is the text 'high'"),
    "object value": (metrics_case('{"cbm": {"recall": {"a": 1}}}'), "metrics.json: cbm.recall is a JSON object"),
    "400-digit value": (metrics_case('{"cbm": {"precision": 1' + "0" * 399 + "}}"),
                        "metrics.json: cbm.precision is an integer of 400 digits"),
    "infinite value": (metrics_case('{"cbm": {"ad": Infinity}}'), "metrics.json: cbm.ad is inf, not a finite number"),
    "deep nesting": (metrics_case('{"cbm": ' + "[" * 100_000 + "]" * 100_000 + "}"),
                     "metrics.json: nested too deeply"),
    "binary curve": (curve_case(b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR" * 10), "success_curve.csv: binary content"),
    "empty curve": (curve_case(""), "success_curve.csv: not a readable CSV file"),
    "ragged curve": (curve_case("rte_max_m,rre_max_deg,cbm\n0.5,0.5,1.0,7,8\n"),
                     "success_curve.csv: not a readable CSV file"),
    "text in the curve": (curve_case("rte_max_m,rre_max_deg,cbm\n0.5,0.5,high\n"),
                          "success_curve.csv: column 'cbm' holds String values"),
    "curve without thresholds": (curve_case("cbm,icp\n0.5,0.5\n"),
                                 "success_curve.csv: the first columns are cbm, icp; expected rte_max_m"),
    "FIFO as the curve": (fifo_curve, "success_curve.csv: a FIFO (named pipe), not a regular file"),
    "unreadable curve": (lambda b: (b / "success_curve.csv").chmod(0), "success_curve.csv: cannot read it"),
    "--out under a file": (lambda b: (b.parent / "a-file").write_text("x"), "a-file is a file, so"),
    "read-only run B": (lambda b: b.chmod(0o555), "the default output folder (give --out FOLDER elsewhere)"),
    "unreadable run B": (lambda b: b.chmod(0), "/b: cannot open the folder (Permission denied)"),
}
NEED_PERMISSIONS = {"unreadable curve", "read-only run B", "unreadable run B"}


def compare(args: list[str], permissions: bool) -> subprocess.CompletedProcess:
    """``evaluate.py compare`` as a command; ``permissions``: the child obeys file modes even as root."""
    preexec = obeying_permissions() if permissions else None
    return subprocess.run([sys.executable, "evaluate.py", "compare", *args], cwd=REPO, capture_output=True,
                          text=True, timeout=300, preexec_fn=preexec)


@pytest.mark.parametrize("case", list(CASES))
def test_a_bad_run_file_or_out_is_one_line_naming_it_with_status_2(case, tmp_path):
    setup, message = CASES[case]
    a, b = write_run(tmp_path / "a"), write_run(tmp_path / "b")
    setup(b)
    out = ["--out", str(tmp_path / "a-file" / "cmp")] if case == "--out under a file" else []
    done = compare([str(a), str(b), *out], permissions=case in NEED_PERMISSIONS)
    b.chmod(0o755)
    assert done.returncode == 2, done.stderr
    assert done.stderr.count("\n") == 1 and "Traceback" not in done.stderr, done.stderr
    assert done.stderr.startswith("evaluate.py compare: error: ") and message in done.stderr, done.stderr
    assert done.stdout == "" and not (b / "compare_vs_a").exists()


def trials(folder: Path, dataset: str, protocol: str) -> None:
    pl.DataFrame({"dataset": [dataset], "frame": [0], "method": ["cbm"], "protocol": [protocol]}).write_parquet(
        folder / "trials.parquet")


def test_runs_of_different_datasets_or_protocols_are_compared_with_a_warning(tmp_path):
    a, b, c = write_run(tmp_path / "a"), write_run(tmp_path / "b"), write_run(tmp_path / "c")
    trials(a, "synthetic:30", "range")
    trials(b, "argoverse2", "sind")
    trials(c, "synthetic:30", "range")
    done = compare([str(a), str(b)], permissions=False)
    assert done.returncode == 0, done.stderr
    warnings = [line for line in done.stderr.splitlines() if "warning" in line]
    assert warnings == [
        f"evaluate.py compare: warning: the runs differ in dataset: synthetic:30 in {a}, argoverse2 in {b}",
        f"evaluate.py compare: warning: the runs differ in protocol: range in {a}, sind in {b}"]
    assert "**Warning:** the runs differ in dataset" in (b / "compare_vs_a" / "compare.md").read_text()
    same = compare([str(a), str(c)], permissions=False)
    assert same.returncode == 0 and "warning" not in same.stderr and "Warning" not in same.stdout
