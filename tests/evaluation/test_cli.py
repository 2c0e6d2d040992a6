"""evaluate.py end to end: the files it writes, byte-identical tables, one-line errors with exit status 2."""
import importlib.util
import json
import subprocess
import sys
from pathlib import Path

import polars as pl
import pytest

import evaluation
from evaluation.presets import default_preset

REPO = Path(__file__).resolve().parents[2]
TINY = ["--dataset", "synthetic:40", "synthetic:40:seed=1", "--frames", "0:20:10", "--protocol", "sind",
        "--methods", "cbm,icp,vips",
        "--grid", "eta=0.4,0.8", "sigma_p=0,0.3", "sigma2=2,3", "--seed", "3"]


def load_evaluate():
    spec = importlib.util.spec_from_file_location("evaluate_cli", REPO / "evaluate.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return module


evaluate_cli = load_evaluate()


@pytest.fixture(scope="module")
def two_runs(tmp_path_factory):
    """The tiny run twice without timing: as a command with two workers, and in-process with one."""
    first, second = tmp_path_factory.mktemp("first"), tmp_path_factory.mktemp("second")
    command = [sys.executable, "evaluate.py", *TINY, "--no-timing", "--workers", "2", "--out", str(first)]
    done = subprocess.run(command, cwd=REPO, capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert evaluate_cli.main([*TINY, "--no-timing", "--workers", "1", "--out", str(second)]) == 0
    return first, second, done.stdout


def test_a_run_writes_the_table_the_summary_and_the_plots(two_runs):
    first, _, stdout = two_runs
    names = {"trials.parquet", "trials.csv", "summary.md", "precision_vs_eta.png", "rre_rte.png", "metrics.json",
             "success_curve.csv", "success_curve.png"}
    assert {p.name for p in first.iterdir()} == names
    assert stdout.startswith((first / "summary.md").read_text())
    assert "| precision (%) |" in stdout and "| cbm sigma2=2 | cbm sigma2=3 | icp | vips |" in stdout


def test_the_table_has_one_row_per_dataset_and_trial_with_every_parameter_and_metric(two_runs):
    table = pl.read_parquet(two_runs[0] / "trials.parquet")
    assert table.columns[:3] == ["dataset", "frame", "method"]
    for column in ("eta", "sigma_p", "sigma_theta", "loc_x", "loc_yaw", "seed", "sigma1", "sigma2", "top_k",
                   "precision", "recall", "ad", "rre", "rte", "success", "init_rte"):
        assert column in table.columns
    assert "runtime_s" not in table.columns
    assert table.height == 2 * 2 * 4 * (2 + 1 + 1)
    assert table["dataset"].unique(maintain_order=True).to_list() == ["synthetic:40", "synthetic:40:seed=1"]
    assert table.equals(pl.read_csv(two_runs[0] / "trials.csv", schema=table.schema))


def test_the_same_seed_gives_byte_identical_tables_and_summary(two_runs):
    first, second, _ = two_runs
    for name in ("trials.csv", "trials.parquet", "summary.md", "metrics.json", "success_curve.csv"):
        assert (first / name).read_bytes() == (second / name).read_bytes(), name


def test_with_timing_the_runtime_is_the_last_column(tmp_path):
    args = ["--dataset", "synthetic:30", "--frames", "0", "--methods", "icp", "--workers", "1", "--out", str(tmp_path)]
    assert evaluate_cli.main(args) == 0
    table = pl.read_csv(tmp_path / "trials.csv")
    assert table.columns[-1] == "runtime_s" and (table["runtime_s"] > 0).all()
    assert "median runtime (ms)" in (tmp_path / "summary.md").read_text()


def test_the_range_protocol_on_the_shipped_scene_names_its_agents(tmp_path):
    args = ["--frames", "0,100", "--protocol", "range", "--methods", "icp", "--grid", "localization=gaussian",
            "--workers", "1", "--out", str(tmp_path)]
    assert evaluate_cli.main(args) == 0
    table = pl.read_parquet(tmp_path / "trials.parquet")
    assert table["ego_id"].to_list() == ["ego", "ego"] and table["cav_id"].null_count() == 0


@pytest.mark.parametrize("args, message", [
    (["--grid", "eta=2"], "ScenarioParams.eta must be a number in [0, 1]"),
    (["--grid", "eta"], "'eta' is not NAME=V1,V2"),
    (["--grid", "wobble=1"], "unknown parameter 'wobble'"),
    (["--grid", "sigma2=2", "--methods", "icp"], "none of which is selected"),
    (["--grid", "consensus=maybe"], "consensus takes true or false"),
    (["--grid", "eta=0.2,0.2"], "eta repeats a value"),
    (["--frames", "0:999"], "out of range"),
    (["--frames", "a:b"], "--frames"),
    (["--methods", "cbm,sift"], "unknown 'sift'"),
    (["--protocol", "opv2v"], "use --protocol range"),
    (["--protocol", "teleport"], "invalid choice"),
    (["--dataset", "no/such/place"], "does not exist"),
    (["--workers", "0"], "--workers must be at least 1"),
    (["--dataset", "synthetic:40", "synthetic:40:seed=1", "--detections", "stage1_boxes.json"],
     "give exactly one --dataset"),
    (["--score-threshold", "1.5", "--detections", "stage1_boxes.json"],
     "--score-threshold must be a number from 0 to 1, got 1.5"),
    (["--score-threshold", "0.5"], "--score-threshold drops a detector's boxes by score: give --detections too"),
])
def test_bad_input_is_one_line_on_stderr_and_exit_status_2(args, message, capsys, tmp_path):
    with pytest.raises(SystemExit) as stop:
        evaluate_cli.main([*args, "--out", str(tmp_path / "out")])
    assert stop.value.code == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("evaluate.py: error:") and message in err
    assert not (tmp_path / "out").exists()


def test_the_pose_before_calibration_is_not_called_gnss_where_there_was_no_prior(tmp_path):
    """Under ``no-prior`` the pose before calibration is the identity, not a GNSS fix."""
    for condition, column in (("mild", "GNSS (init)"), ("no-prior", "init (no prior)")):
        out = tmp_path / condition
        assert evaluate_cli.main(["--dataset", "synthetic:20", "--frames", "0:1", "--no-timing", "--methods", "cbm",
                                  "--condition", condition, "--out", str(out)]) == 0
        assert f"| metric | cbm | {column} |" in (out / "summary.md").read_text()


def test_reference_methods_bound_the_default_table(tmp_path):
    """By default every method runs between the references: ``none`` (the GNSS error, which then
    needs no column of its own) and ``oracle`` (least squares on the true pairs)."""
    assert evaluate_cli.main(["--dataset", "synthetic:40", "--frames", "0:2", "--no-timing",
                              "--out", str(tmp_path)]) == 0
    summary = (tmp_path / "summary.md").read_text()
    assert ("| metric | none | cbm | cbm-no-consensus | cbm-no-prior | icp | ricp | vips | v2xregpp | freealign | "
            "oracle (least squares on the true pairs) |") in summary
    assert "GNSS (init) |" not in summary
    table = pl.read_csv(tmp_path / "trials.csv")
    oracle, none = table.filter(pl.col("method") == "oracle"), table.filter(pl.col("method") == "none")
    assert (oracle["precision"] == 1.0).all() and (oracle["recall"] == 1.0).all()
    assert (none["rte"] == none["init_rte"]).all() and (none["n_matched"] == 0).all()


def test_the_evaluation_is_an_importable_package_and_the_command_is_thin(two_runs):
    """``evaluation.run`` returns the same per-trial table the command writes (from the default
    preset, as the command starts); evaluate.py only hands over to ``evaluation.cli``."""
    preset = default_preset()
    table = evaluation.run(["synthetic:40", "synthetic:40:seed=1"], methods=("cbm", "icp", "vips"),
                           grid={"eta": (0.4, 0.8), "sigma_p": (0.0, 0.3), "sigma2": (2.0, 3.0)}, seed=3,
                           frames=lambda n: range(0, 20, 10), protocol="sind", scenario=preset.scenario,
                           params=preset.params)
    assert isinstance(table, pl.DataFrame) and "runtime_s" in table.columns
    written = pl.read_parquet(two_runs[0] / "trials.parquet")
    assert evaluation.without_timing(table).equals(written)
    assert len((REPO / "evaluate.py").read_text().splitlines()) <= 40


def test_a_detectors_boxes_replace_the_simulated_ones(tmp_path):
    fixtures = REPO / "tests" / "loaders" / "fixtures"
    common = ["--dataset", str(fixtures / "opv2v" / "scenario"), "--protocol", "opv2v", "--frames", "0:1",
              "--methods", "cbm", "--no-timing"]
    simulated, detected = tmp_path / "simulated", tmp_path / "detected"
    assert evaluate_cli.main([*common, "--out", str(simulated)]) == 0
    assert evaluate_cli.main([*common, "--detections", str(fixtures / "stage1" / "stage1_boxes.json"),
                              "--out", str(detected)]) == 0
    runs = [pl.read_csv(folder / "trials.csv") for folder in (simulated, detected)]
    assert len(runs[0]) == len(runs[1]) == 1
    assert runs[0].drop("dataset").row(0) != runs[1].drop("dataset").row(0)


def test_the_score_threshold_drops_a_detectors_low_scored_boxes(tmp_path):
    fixtures = REPO / "tests" / "loaders" / "fixtures"
    samples = json.loads((fixtures / "stage1" / "stage1_boxes.json").read_text())
    samples["13"]["pred_score_np_list"] = [[0.9, 0.3], [0.6, 0.2]]
    scored = tmp_path / "stage1_boxes.json"
    scored.write_text(json.dumps(samples))
    common = ["--dataset", str(fixtures / "opv2v" / "scenario"), "--protocol", "opv2v", "--frames", "0:1",
              "--methods", "cbm", "--no-timing", "--detections", str(scored)]
    runs = []
    for threshold in ("0", "0.5"):
        assert evaluate_cli.main([*common, "--score-threshold", threshold, "--out", str(tmp_path / threshold)]) == 0
        runs.append(pl.read_csv(tmp_path / threshold / "trials.csv"))
    assert runs[0]["min_score"].to_list() == [0.0] and runs[1]["min_score"].to_list() == [0.5]
    counts = [(run["n_ego"].item(), run["n_cav"].item()) for run in runs]
    assert counts[1][0] == counts[0][0] - 1 == 1 and counts[1][1] <= counts[0][1]    # the ego's 0.3 box dropped
