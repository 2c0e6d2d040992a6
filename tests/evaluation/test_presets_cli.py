"""The command line and the app agree: evaluate.py's defaults are the app's (the shipped default
preset), ``--preset`` reads the files the app saves and exports, and the same settings give the
same numbers on the same frame."""
from __future__ import annotations

import dataclasses
from pathlib import Path

import polars as pl
import pytest

import loaders
from app.session.explorer import Explorer
from app.session.export import preset_toml
from app.session.presets import save_preset
from app.session.settings import Settings
from evaluation.cli import main
from evaluation.presets import PresetError, default_preset, find_preset, read_preset_file
from evaluation.sweep import SCENARIO_FIELDS

QUICK = ["--dataset", "synthetic:40", "--frames", "0:20:10", "--workers", "1", "--no-timing"]


def _run(tmp_path: Path, name: str, *args: str) -> pl.DataFrame:
    out = tmp_path / name
    assert main([*QUICK, *args, "--out", str(out)]) == 0
    return pl.read_csv(out / "trials.csv")


def _scenario_row(table: pl.DataFrame) -> dict:
    return table.select(*SCENARIO_FIELDS).row(0, named=True)


def test_the_defaults_are_the_apps_default_preset(tmp_path: Path) -> None:
    app = Settings()
    table = _run(tmp_path, "defaults", "--methods", "cbm,icp")
    assert _scenario_row(table) == dataclasses.asdict(app.scenario)
    assert app.scenario.sigma_p == 0.2 and app.scenario.protocol == "range"
    cbm = table.filter(pl.col("method") == "cbm").row(0, named=True)
    assert all(cbm[name] == value for name, value in dataclasses.asdict(app.cbm).items())
    assert _run(tmp_path, "named", "--methods", "cbm,icp", "--preset", "default").equals(table)


def test_the_app_and_the_command_line_give_the_same_numbers_on_a_frame(tmp_path: Path) -> None:
    out = tmp_path / "argoverse2"
    assert main(["--dataset", "argoverse2", "--frames", "0,40", "--methods", "cbm", "--workers", "1",
                 "--no-timing", "--out", str(out)]) == 0
    table = pl.read_csv(out / "trials.csv")
    explorer = Explorer(loaders.open("argoverse2"))
    for row in table.iter_rows(named=True):
        outcome = explorer.compute(dataclasses.replace(Settings(), frame=row["frame"]))
        assert str(outcome.cav_id) == row["cav_id"]
        assert (outcome.metrics.n_matched, outcome.metrics.n_correct) == (row["n_matched"], row["n_correct"])
        assert outcome.metrics.rte == pytest.approx(row["rte"], abs=1e-9)


def test_a_preset_the_app_exports_runs_as_the_app_ran_it(tmp_path: Path) -> None:
    settings = dataclasses.replace(Settings(), method="icp").with_scenario(protocol="sind", eta=0.7, sigma_p=0.4)
    settings = settings.with_params("cbm", sigma2=2.5, refine=False).with_params("icp", max_iterations=7)
    settings = settings.with_view(ghosts=True, layout="side by side")
    exported = tmp_path / "cbm-explorer-preset.toml"
    exported.write_bytes(preset_toml(settings, "synthetic:40"))
    table = _run(tmp_path, "exported", "--methods", "cbm,icp", "--preset", str(exported))
    assert _scenario_row(table) == dataclasses.asdict(settings.scenario)
    cbm = table.filter(pl.col("method") == "cbm").row(0, named=True)
    assert cbm["sigma2"] == 2.5 and cbm["refine"] is False and cbm["sigma1"] == settings.cbm.sigma1
    assert table.filter(pl.col("method") == "icp")["max_iterations"].to_list() == [7, 7]


def test_a_saved_preset_and_a_shipped_one_by_name(tmp_path: Path) -> None:
    saved = save_preset("My tuning", Settings().with_params("cbm", sigma3=2.0), users=tmp_path / "mine")
    assert read_preset_file(saved).params["cbm"].sigma3 == 2.0
    sind = find_preset("paper-sind")
    assert sind.scenario.protocol == "sind" and sind.scenario.sigma_p == 0.3 and not sind.params["cbm"].refine
    table = _run(tmp_path, "sind", "--methods", "cbm", "--preset", "paper-sind")
    assert table["protocol"].unique().to_list() == ["sind"] and table["refine"].unique().to_list() == [False]


def test_protocol_seed_and_grid_change_the_preset(tmp_path: Path) -> None:
    table = _run(tmp_path, "changed", "--methods", "cbm", "--preset", "paper-sind", "--protocol", "range",
                 "--seed", "4", "--grid", "sigma_p=0.1")
    row = _scenario_row(table)
    assert (row["protocol"], row["seed"], row["sigma_p"], row["sigma_theta"]) == ("range", 4, 0.1, 3.0)


def test_keys_a_preset_leaves_out_are_the_default_presets(tmp_path: Path) -> None:
    partial = tmp_path / "partial.toml"
    partial.write_text("[cbm]\nsigma2 = 2\n")
    read = read_preset_file(partial)
    assert read.params["cbm"].sigma2 == 2.0 and read.scenario == default_preset().scenario


@pytest.mark.parametrize(("content", "expected"), [
    ("[cbm]\nsigma_2 = 3.0\n", "sigma_2"),
    ('[scenario]\neta = "half"\n', "eta must be float"),
    ("[scenario\neta = 0.5\n", "not a TOML preset"),
    ("[teleport]\nx = 1\n", "unknown table [teleport]"),
])
def test_a_bad_preset_is_a_one_line_error_naming_the_file(tmp_path: Path, capsys: pytest.CaptureFixture,
                                                          content: str, expected: str) -> None:
    bad = tmp_path / "bad.toml"
    bad.write_text(content)
    with pytest.raises(SystemExit) as stop:
        main([*QUICK, "--preset", str(bad), "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err.strip()
    assert stop.value.code == 2 and "\n" not in err and "--preset" in err and "bad.toml" in err and expected in err
    assert not (tmp_path / "out").exists()


def test_an_unknown_preset_name_lists_the_shipped_ones(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    with pytest.raises(SystemExit) as stop:
        main([*QUICK, "--preset", "no-such-preset", "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert stop.value.code == 2 and "no-such-preset" in err and "paper-sind" in err
    with pytest.raises(PresetError, match="not a regular file"):
        read_preset_file(tmp_path)


def test_a_preset_saved_with_a_byte_order_mark_is_read(tmp_path: Path) -> None:
    """Some editors (Notepad) save UTF-8 with a byte order mark; before, such a preset was refused as
    "Invalid statement (at line 1, column 1)" (issue 40, item 7)."""
    path = tmp_path / "bom.toml"
    path.write_bytes("\ufeff[scenario]\nsigma_p = 0.4\n".encode())
    assert read_preset_file(path).scenario.sigma_p == 0.4
