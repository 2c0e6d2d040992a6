"""Presets: the shipped ones load, malformed files are reported and skipped, saving is atomic and
never overwrites a shipped preset."""
from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest

from app.session.presets import SHIPPED_DIR, PresetError, discover, in_use, read, save_preset
from app.session.settings import Settings, from_preset, to_preset
from evaluation.conditions import condition
from evaluation.scenario import ScenarioParams

CONDITION_PRESETS = ("heavy-noise", "prior-error", "clutter", "drift-heavy", "drift-sparse", "occluded", "latency")
"""The shipped presets of the hard named conditions (``evaluation.conditions``), one click in the app."""


def test_shipped_presets_load_and_cover_the_required_cases(tmp_path: Path) -> None:
    presets, problems = discover(users=tmp_path)
    assert problems == []
    assert {"default", "paper-sind", "paper-opv2v", "released-code", "stress", "teaching", "heavy-noise",
            "prior-error", "clutter"} <= set(presets)
    settings = {name: p.apply(Settings()) for name, p in presets.items()}
    assert settings["paper-sind"].scenario.protocol == "sind"
    assert settings["paper-opv2v"].scenario.localization == "gaussian"
    assert settings["released-code"].cbm.heading == "fold"
    assert settings["stress"].scenario.sigma_p > settings["teaching"].scenario.sigma_p
    assert all(p.shipped and p.description for p in presets.values())


@pytest.mark.parametrize("name", CONDITION_PRESETS)
def test_a_condition_preset_is_the_named_conditions_scenario(tmp_path: Path, name: str) -> None:
    presets, _ = discover(users=tmp_path)
    assert presets[name].apply(Settings()).scenario == condition(name)
    elsewhere = Settings(scenario=ScenarioParams(sigma_p=1.5, miss_rate=0.9))
    assert presets[name].apply(elsewhere).scenario == condition(name)


def test_malformed_files_are_reported_with_file_and_field(tmp_path: Path) -> None:
    (tmp_path / "broken.toml").write_text("[cbm\nsigma2 = 3")
    (tmp_path / "typo.toml").write_text("[cbm]\nsigma_2 = 3.0\n")
    (tmp_path / "wrongtype.toml").write_text('[scenario]\neta = "half"\n')
    (tmp_path / "outofrange.toml").write_text("[scenario]\neta = 2.0\n")
    (tmp_path / "good.toml").write_text("[cbm]\nsigma2 = 2\n")
    presets, problems = discover(users=tmp_path)
    assert "good" in presets and presets["good"].apply(Settings()).cbm.sigma2 == 2.0
    text = "\n".join(problems)
    assert len(problems) == 4
    assert "broken.toml" in text and "typo.toml" in text and "sigma_2" in text
    assert "wrongtype.toml" in text and "eta" in text and "outofrange.toml" in text


def test_save_round_trips_atomically_and_refuses_shipped_names(tmp_path: Path) -> None:
    settings = Settings().with_params("cbm", sigma2=4.5)
    settings = dataclasses.replace(settings, scenario=dataclasses.replace(settings.scenario, sigma_p=0.7))
    path = save_preset("My Tuning #1", settings, users=tmp_path)
    assert path == tmp_path / "my-tuning-1.toml"
    assert [p.name for p in tmp_path.iterdir()] == ["my-tuning-1.toml"], "no temporary file is left behind"
    loaded = read(path, shipped=False).apply(Settings())
    assert loaded.cbm.sigma2 == 4.5 and loaded.scenario.sigma_p == 0.7
    before = (SHIPPED_DIR / "default.toml").read_text()
    with pytest.raises(PresetError, match="shipped"):
        save_preset("Default", settings, users=tmp_path)
    with pytest.raises(PresetError):
        save_preset("  !!  ", settings, users=tmp_path)
    assert (SHIPPED_DIR / "default.toml").read_text() == before


def test_user_preset_cannot_shadow_a_shipped_one(tmp_path: Path) -> None:
    (tmp_path / "default.toml").write_text("[cbm]\nsigma2 = 9.0\n")
    presets, problems = discover(users=tmp_path)
    assert presets["default"].shipped and any("default.toml" in p for p in problems)


def test_preset_form_round_trips() -> None:
    settings = dataclasses.replace(Settings(), method="icp").with_params("cbm", sigma1=12.0)
    again = from_preset(to_preset(settings))
    assert again.method == "icp" and again.cbm.sigma1 == 12.0 and again.scenario == settings.scenario


def test_environment_variable_sets_the_user_folder(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("CBM_EXPLORER_PRESETS", str(tmp_path))
    save_preset("mine", Settings())
    assert (tmp_path / "mine.toml").exists() and "mine" in discover()[0]


def test_the_preset_in_use_is_the_one_the_settings_compute_as(tmp_path: Path) -> None:
    presets, _ = discover(users=tmp_path)
    start = Settings()
    assert in_use(presets, start) == "default"
    moved = dataclasses.replace(start, frame=7, cavs=2, view=dataclasses.replace(start.view, ghosts=True))
    assert in_use(presets, moved) == "default", "the frame, the CAVs and the view are no part of a preset"
    assert in_use(presets, presets["clutter"].apply(start)) == "clutter"
    assert in_use(presets, start.with_params("cbm", sigma2=2.5)) is None
