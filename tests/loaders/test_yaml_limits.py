"""Issue 50, item 3: a small YAML file that stands for a huge value (nested aliases) is refused
before it is built, and no error message quotes more than a line of a value."""
from __future__ import annotations

import shutil
import time
from pathlib import Path

import pytest
import yaml

import loaders
from loaders.errors import SHOWN_CHARS, shown
from loaders.structured import MAX_EXPANDED_VALUES, read_yaml

FIXTURES = Path(__file__).parent / "fixtures"


def _laughs(levels: int) -> str:
    """``levels`` nested anchors of ten aliases each: 10**levels values in a few hundred bytes."""
    lines = ["a0: &a0 [x, x, x, x, x, x, x, x, x, x]"]
    lines += [f"a{k}: &a{k} [{', '.join([f'*a{k - 1}'] * 10)}]" for k in range(1, levels)]
    return "\n".join(lines) + "\n"


def _with_location(folder: Path, location: str) -> Path:
    """The OPV2V fixture scenario with CAV 641's first vehicle at ``location`` (YAML text)."""
    scenario = folder / "scenario"
    shutil.copytree(FIXTURES / "opv2v" / "scenario", scenario)
    path = scenario / "641" / "000068.yaml"
    path.write_text(path.read_text().replace("location: [15, 22, 0]", f"location: {location}"))
    return scenario


@pytest.mark.parametrize("levels", [9, 10])
def test_nested_aliases_as_a_location_are_one_short_line(tmp_path: Path, levels: int) -> None:
    scenario = _with_location(tmp_path, "")
    path = scenario / "641" / "000068.yaml"
    path.write_text(_laughs(levels) + path.read_text().replace("location: ", f"location: *a{levels - 1}"))
    assert len(path.read_bytes()) < 2048
    started = time.perf_counter()
    with pytest.raises(loaders.LoaderError) as raised:
        loaders.open(str(scenario))
    message = str(raised.value)
    assert f"aliases expand to more than {MAX_EXPANDED_VALUES:,} values" in message and len(message) < 400, message
    assert "000068.yaml" in message
    print(f"refused in {time.perf_counter() - started:.3f} s")


def test_an_alias_that_holds_itself_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "loop.yaml"
    path.write_text("a: &a [1, *a]\n")
    with pytest.raises(loaders.LoaderError, match="an alias refers to a value that holds it"):
        read_yaml(path)


def test_aliases_as_yaml_dump_writes_them_are_read(tmp_path: Path) -> None:
    shared = [10.0, 20.0, 1.9, 0.0, 90.0, 0.0]
    path = tmp_path / "shared.yaml"
    path.write_text(yaml.dump({"lidar_pose": shared, "true_ego_pos": shared}))
    assert "&id001" in path.read_text()
    assert read_yaml(path) == {"lidar_pose": shared, "true_ego_pos": shared}


def test_a_huge_value_where_a_number_belongs_is_quoted_in_one_short_line(tmp_path: Path) -> None:
    scenario = _with_location(tmp_path, "[" + ", ".join(["[" + ", ".join(["abc"] * 2000) + "]"] * 50) + "]")
    with pytest.raises(loaders.LoaderError) as raised:
        loaders.open(str(scenario))
    message = str(raised.value)
    assert "location[0]: expected a number, got [" in message and len(message) < 400, message


@pytest.mark.parametrize("value", [list(range(10**6)), "x" * 10**6, {"k": [[[[[1]]]]]}, b"\0" * 10**6, 10**300])
def test_a_quoted_value_is_at_most_one_short_line(value: object) -> None:
    assert len(shown(value)) <= SHOWN_CHARS
