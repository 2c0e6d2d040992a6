"""evaluate.py with inputs that would grow without bound (issue 27): each is checked against the
dataset before it is expanded, so a run under a memory cap ends with one line naming the input."""
import json
import os
import resource
import subprocess
import sys
from pathlib import Path

import pytest

import evaluation
import loaders
from evaluation.bounds import GRAPH_WARNING_CAVS, bounded_workers, cost_warnings
from evaluation.cli import CliError, main, parse_frames
from evaluation.trials import frame_cav_inputs

REPO = Path(__file__).resolve().parents[2]
MEMORY_CAP = 2500 * 2**20
"""Bytes of address space: enough for a small run of evaluate.py (OpenBLAS at one thread: its
per-thread buffers alone take most of 1.5 GB), far from enough to expand a huge input."""


def run_capped(*args: str, cap: int = MEMORY_CAP, timeout: float = 300) -> subprocess.CompletedProcess:
    """``evaluate.py ARGS`` in a subprocess whose address space is capped at ``cap`` bytes."""
    def limit() -> None:
        resource.setrlimit(resource.RLIMIT_AS, (cap, cap))
    environment = {**os.environ, "OPENBLAS_NUM_THREADS": "1"}
    return subprocess.run([sys.executable, str(REPO / "evaluate.py"), *args], cwd=REPO, preexec_fn=limit,
                          env=environment, capture_output=True, text=True, timeout=timeout)


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


PEDESTRIANS = ["frame,track_id,category,x,y,length,width,yaw",
               *(f"{f},p{k},pedestrian,{3 * k},{k},0.5,0.5,0" for f in (0, 1) for k in range(3))]
"""Two frames of three pedestrians: no two vehicles, so the sind protocol deals them to abstract agents."""


def test_a_huge_agents_count_is_bounded_by_the_frame_and_warned_about(tmp_path) -> None:
    dataset = tmp_path / "pedestrians.csv"
    dataset.write_text("\n".join(PEDESTRIANS) + "\n")
    done = run_capped("--dataset", str(dataset), "--protocol", "sind", "--agents", "100000", "--methods", "icp",
                      "--workers", "1", "--no-timing", "--out", str(tmp_path / "out"))
    assert done.returncode == 0, done.stderr[-2000:]
    assert ("evaluate.py: warning: --agents 100000: the chosen frames have at most 4 agents (the ego and 3 CAV(s)), "
            "so a frame gives at most 3 trial(s) per method") in done.stderr.splitlines()
    rows = (tmp_path / "out" / "trials.csv").read_text().strip().splitlines()
    assert len(rows) == 1 + 2 * 3


def test_a_frame_of_k_cavs_holds_k_references_to_its_cohort_not_k_squared() -> None:
    sequence = loaders.open("synthetic:300")
    inputs = frame_cav_inputs(sequence[0], "range", agents=1000)
    assert len(inputs) > 200
    assert len({id(item.cohort) for item in inputs}) == 1
    first = inputs[0]
    assert [peer.stream for peer in first.peers] == list(range(1, len(inputs)))


def test_cbm_graph_on_many_cavs_warns_of_its_quadratic_cost() -> None:
    planned = evaluation.plan(["synthetic:30"], methods=("cbm", "cbm-graph"), agents=50, frames=lambda n: [0])
    most = planned.most_cavs
    assert most >= GRAPH_WARNING_CAVS
    assert cost_warnings(planned, 50)[-1] == (
        f"--agents 50: cbm-graph matches every CAV of the frame for each CAV's trial: up to {most * most} CBM runs "
        f"per frame and scenario point ({most} for cbm); this may take hours")
    few = evaluation.plan(["synthetic:30"], methods=("cbm", "cbm-graph"), agents=3, frames=lambda n: [0])
    assert cost_warnings(few, 3) == []


FIXTURES = REPO / "tests" / "loaders" / "fixtures"


def big_detections(path: Path, samples: int = 2600, boxes: int = 300) -> Path:
    """The fixture's stage1_boxes.json with ``samples`` more samples of ``boxes`` boxes each, for egos
    far from the scenario (about 130 MB; json.loads would make over 4 GB of it)."""
    fixture = (FIXTURES / "stage1" / "stage1_boxes.json").read_text().strip()
    corners = json.dumps([[[float(k % 97), float(k % 89), -1.75]] * 8 for k in range(boxes)])
    with path.open("w") as file:
        file.write(fixture[:-1].rstrip())
        for k in range(samples):
            file.write(f', "{1000 + k}": {{"cav_id_list": ["641"], "lidar_pose_clean_np": '
                       f'[[{900 + k}.0, 20.0, 1.9, 0, 90, 0]], "pred_corner3d_np_list": [{corners}]}}')
        file.write("}\n")
    return path


def test_a_detections_file_of_130_mb_is_streamed_within_the_memory_cap(tmp_path) -> None:
    detections = big_detections(tmp_path / "stage1_boxes.json")
    assert detections.stat().st_size > 120e6
    scenario = str(FIXTURES / "opv2v" / "scenario")
    done = run_capped("--dataset", scenario, "--detections", str(detections), "--protocol", "opv2v", "--methods",
                      "icp", "--workers", "1", "--no-timing", "--out", str(tmp_path / "out"))
    assert done.returncode == 0, done.stderr[-2000:]
    assert (tmp_path / "out" / "trials.csv").read_text().count("\n") == 1 + 2
    probe = ("import sys, tracemalloc, loaders; tracemalloc.start(); "
             "loaders.open(sys.argv[1], detections=sys.argv[2]); print(tracemalloc.get_traced_memory()[1])")
    peak = int(subprocess.run([sys.executable, "-c", probe, scenario, str(detections)], capture_output=True,
                              text=True, check=True, timeout=600).stdout)
    assert peak < 200 * 2**20, f"loading the detections held {peak / 2**20:.0f} MB at its peak (json.loads: over 1 GB)"


def test_more_workers_than_cpus_are_bounded_with_a_warning(tmp_path, capsys) -> None:
    cpus = len(os.sched_getaffinity(0))
    assert bounded_workers(cpus, None) == (cpus, None)
    assert bounded_workers(10_000, "auto") == (10_000, None)
    assert bounded_workers(10_000, "local")[0] == cpus
    assert main(["--dataset", "synthetic:20", "--frames", "0:2", "--methods", "icp", "--workers", "10000",
                 "--out", str(tmp_path / "out")]) == 0
    assert (f"evaluate.py: warning: --workers 10000: this machine has {cpus} CPU(s) for this process; using {cpus} "
            "(more workers would share them and each take its own memory)") in capsys.readouterr().err.splitlines()


def test_a_grid_of_too_many_points_is_refused_before_it_is_expanded(tmp_path) -> None:
    thousand, ninety = (",".join(str(k) for k in range(1, n + 1)) for n in (1000, 90))
    done = run_capped("--dataset", "synthetic:5", "--frames", "0", "--methods", "cbm", "--grid", f"sigma2={thousand}",
                      f"sigma1={ninety}", f"sigma3={thousand}", "--out", str(tmp_path / "out"))
    assert done.returncode == 2, done.stderr[-2000:]
    assert done.stderr.strip().splitlines() == [
        "evaluate.py: error: --grid: 90,000,000 points (1000 sigma2 x 90 sigma1 x 1000 sigma3); "
        "at most 100,000 in one run"]
