"""Issue 50, item 8: a disk that fills while the run's table is written gives the command's one line
about the disk, not polars' "File out of specification"; the older run stays whole."""
from __future__ import annotations

import errno
import subprocess
from pathlib import Path

import polars as pl
import pytest

import evaluation.cli

QUICK = ["--dataset", "synthetic:40", "--frames", "0:2", "--methods", "icp", "--workers", "1"]


@pytest.fixture
def full_disk(tmp_path: Path):
    """A 64 KB tmpfs filled to its last byte (skipped where a tmpfs cannot be mounted)."""
    disk = tmp_path / "disk"
    disk.mkdir()
    mounted = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=64k", "tmpfs", str(disk)], capture_output=True,
                             text=True)
    if mounted.returncode != 0:
        pytest.skip(f"cannot mount a tmpfs here: {mounted.stderr.strip()}")
    try:
        with (disk / "filler").open("wb", buffering=0) as filler:
            with pytest.raises(OSError):
                while True:
                    filler.write(b"\0" * 1024)
        yield disk
    finally:
        subprocess.run(["umount", "-l", str(disk)], check=False)


def test_a_full_disk_while_the_table_is_written_is_the_commands_one_line(full_disk: Path, capsys) -> None:
    out = full_disk / "results"
    assert evaluation.cli.main([*QUICK, "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err == (f"evaluate.py: error: cannot write the run to {out} (No space left on device); "
                   "its earlier files are untouched\n"), err
    assert sorted(p.name for p in full_disk.iterdir()) == ["filler"]


def test_the_table_writer_reports_a_full_device_as_os_error() -> None:
    from evaluation.outputs import write_table

    with pytest.raises(OSError) as raised:
        write_table(pl.DataFrame({"a": list(range(1000))}), Path("/dev/full"), Path("/dev/full"))
    assert raised.value.errno == errno.ENOSPC
