"""Sweeps on Ray: the same rows as the process pool, progress as tasks finish, failures named, clear errors."""
import math
import statistics
import sys
import time

import numpy as np
import pytest

from evaluation.executors import ExecutorError, TaskError, check_reachable, ray_session, run_tasks
from evaluation.scenario import FrameInputs
from evaluation.sweep import Sweep, run
from support.scenes import street_scene

SWEEP = Sweep(methods=("cbm", "icp"), grid={"eta": (0.4, 0.8), "sigma2": (2.0, 3.0)}, seed=5)


def frames(n=3):
    return [FrameInputs(k, {"boxes": street_scene(25, np.random.default_rng(k)), "ids": np.arange(25)})
            for k in range(n)]


def without_runtime(rows):
    """The rows without their runtime, NaN as None (NaN is never equal to itself)."""
    return [{k: None if isinstance(v, float) and math.isnan(v) else v for k, v in row.items() if k != "runtime_s"}
            for row in rows]


@pytest.fixture(scope="module")
def local_ray():
    """One quiet local Ray instance with 2 CPUs for the module (each run reuses it)."""
    pytest.importorskip("ray")
    with ray_session("local", workers=2):
        yield


@pytest.mark.ray
def test_ray_gives_the_process_pools_rows_in_the_same_order(local_ray):
    seen = []
    on_ray = run(SWEEP, frames(), ray="local", progress=seen.append)
    in_pool = run(SWEEP, frames(), workers=2)
    assert without_runtime(on_ray) == without_runtime(in_pool)
    assert len(on_ray) == SWEEP.trial_count(3) and sum(seen) == len(on_ray) and len(seen) == 3 * 2


@pytest.mark.ray
def test_a_task_that_raises_is_named_not_dropped(local_ray):
    broken = [*frames(2), FrameInputs(7, {"boxes": np.zeros((4, 2)), "ids": np.arange(4)})]
    with pytest.raises(TaskError, match=r"task frame 7 \(eta=0\.[48]\) failed: ValueError: boxes must be"):
        run(SWEEP, broken, ray="local")
    with pytest.raises(TaskError, match=r"task \(\[\],\) failed: StatisticsError: mean requires"):
        run_tasks(statistics.mean, [([1.0, 2.0],), ([],)], ray="local")
    assert run_tasks(statistics.mean, [([1.0, 2.0],), ([4.0],)], ray="local") == [1.5, 4.0]


def test_the_process_pool_names_a_failing_task_too():
    broken = [FrameInputs(3, {"boxes": np.zeros((4, 2)), "ids": np.arange(4)})]
    with pytest.raises(TaskError, match=r"task frame 3 \(eta=0.8\) failed"):
        run(Sweep(methods=("cbm",), grid={"eta": (0.8,)}), broken, workers=2)


def test_without_ray_installed_the_error_says_how_to_install_it(monkeypatch):
    monkeypatch.setitem(sys.modules, "ray", None)
    with pytest.raises(ExecutorError, match=r"pip install \.\[ray\]"):
        run(SWEEP, frames(1), ray="local")


def test_an_unreachable_cluster_is_reported_without_hanging():
    start = time.perf_counter()
    with pytest.raises(ExecutorError, match="unreachable"):
        check_reachable("127.0.0.1:1", timeout=3.0)
    with pytest.raises(ExecutorError, match="HOST:PORT"):
        check_reachable("nowhere")
    assert time.perf_counter() - start < 30.0, "a check waited for the network instead of its timeout"


@pytest.mark.parametrize("ray,message", [("127.0.0.1:1", "the Ray cluster is unreachable"),
                                         ("nowhere", "expected local, auto or HOST:PORT")])
def test_evaluate_reports_a_bad_cluster_in_one_line_with_exit_status_2(ray, message, capsys, tmp_path):
    from evaluation.cli import main
    with pytest.raises(SystemExit) as stop:
        main(["--dataset", "synthetic:20", "--frames", "0:2", "--methods", "cbm", "--ray", ray,
              "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert stop.value.code == 2 and err.count("\n") == 1 and message in err
