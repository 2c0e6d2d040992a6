"""One range per scenario number, wherever a value enters (issue 40, item 1): the constructor every
entry goes through refuses values beyond it, naming the field; a preset file, ``--grid`` and the
app's sliders meet the same range. ``false_rate = 50`` (a preset that locked a tab) is refused."""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from app.panels.scenario import SLIDERS
from app.session.presets import discover
from evaluation.scenario import RANGES, ScenarioParams

REPO = Path(__file__).resolve().parents[2]


@pytest.mark.parametrize("name", list(RANGES))
def test_a_value_beyond_its_range_is_refused_naming_the_field(name: str) -> None:
    low, high = RANGES[name]
    ScenarioParams(**{name: high})
    with pytest.raises(ValueError, match=rf"ScenarioParams.{name} must be a number in \[{low:g}, {high:g}\]"):
        ScenarioParams(**{name: high * 1.01 + 0.01})


def test_the_sliders_span_the_ranges() -> None:
    for name, (_, low, high, _, _) in SLIDERS.items():
        assert (low, high) == (max(RANGES[name][0], 0.0), RANGES[name][1]), name


def test_a_preset_beyond_a_range_is_skipped_naming_its_file_and_field(tmp_path) -> None:
    (tmp_path / "fr50.toml").write_text("[scenario]\nfalse_rate = 50.0\n")
    presets, problems = discover(users=tmp_path)
    assert "fr50" not in presets
    assert any("fr50.toml" in p and "false_rate must be a number in [0, 2], got 50.0" in p for p in problems), problems


@pytest.mark.parametrize("given", [["--grid", "false_rate=50"], ["--preset", "PRESET"]])
def test_evaluate_refuses_a_value_beyond_its_range_in_one_line(tmp_path, given: list[str]) -> None:
    preset = tmp_path / "fr50.toml"
    preset.write_text("[scenario]\nfalse_rate = 50.0\n")
    argv = [str(preset) if arg == "PRESET" else arg for arg in given]
    done = subprocess.run([sys.executable, "evaluate.py", "--dataset", "synthetic:40", "--frames", "0:1", *argv,
                           "--out", str(tmp_path / "out")], cwd=REPO, capture_output=True, text=True, timeout=300)
    assert done.returncode == 2 and done.stderr.count("\n") == 1, done.stderr
    assert "false_rate must be a number in [0, 2], got 50.0" in done.stderr and not (tmp_path / "out").exists()


@pytest.mark.parametrize("params, field, value", [
    ("CBMParams", "sigma2", 10.5), ("CBMParams", "sigma1", 46.0), ("CBMParams", "distance_limit", 61.0),
    ("VIPSParams", "top_k", 1_000_000), ("VIPSParams", "candidate_radius", 1e5), ("ICPParams", "max_iterations", 10**6),
    ("V2XRegParams", "top_k", 101), ("FreeAlignParams", "max_boxes", 201),
])
def test_a_method_parameter_beyond_its_range_is_refused_naming_it(params: str, field: str, value: float) -> None:
    """VIPS with 1,000,000 candidates per object and a radius of 1e5 m ran out of memory and said
    "CBM cannot run on this frame"; now it is refused before it runs, naming the method's parameter."""
    import cbm.baselines
    import cbm.params

    cls = getattr(cbm.params, params, None) or getattr(cbm.baselines, params)
    with pytest.raises(ValueError, match=rf"{params}.{field} must be at most"):
        cls(**{field: value})


def test_cbm_without_a_distance_limit_stays_allowed_and_the_sliders_end_at_the_ranges() -> None:
    import math

    from app.panels.method import SLIDERS as METHOD_SLIDERS
    from cbm.params import MOST, CBMParams

    CBMParams(distance_limit=math.inf)
    for (key, name), (_, high, _) in METHOD_SLIDERS.items():
        assert key == "cbm" and high == MOST[name]


def test_evaluate_refuses_a_grid_beyond_a_method_range(tmp_path) -> None:
    done = subprocess.run([sys.executable, "evaluate.py", "--dataset", "synthetic:40", "--frames", "0:1", "--grid",
                           "sigma2=50", "--out", str(tmp_path / "out")], cwd=REPO, capture_output=True, text=True,
                          timeout=300)
    assert done.returncode == 2 and done.stderr.count("\n") == 1 and "sigma2 must be at most 10" in done.stderr
