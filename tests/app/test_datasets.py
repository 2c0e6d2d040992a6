"""Open data from the page (issue 47, item 5): the datasets found under the folders named at start and
nothing outside them (links out and names not offered refused, before anything is read), one
explorer per dataset shared by the tabs, and a dataset opening on the first frame CBM can run on."""
from __future__ import annotations

import threading
from pathlib import Path

import pytest

import loaders
from app.cli import main, parse
from app.session import datasets
from app.session.datasets import Catalogue, DataError, data_roots, escape, found, settings_on, start_dataset
from app.session.explorer import Explorer
from app.session.settings import Settings
from app.session.start import FEWEST_SHARED, first_usable, runs_on, shared_objects, start_of
from support.recordings import intersection


@pytest.fixture
def data(tmp_path: Path) -> Path:
    """A data folder: a recording, a table of boxes, a folder of datasets, and links in and out."""
    root = tmp_path / "data"
    intersection(root / "crossing")
    intersection(root / "more" / "deeper")
    (root / "tables").mkdir()
    (root / "tables" / "boxes.csv").write_text("frame,x,y,yaw\n0,1,2,0\n")
    (root / "tables" / "notes.txt").write_text("not a dataset")
    intersection(tmp_path / "outside")
    (root / "outside_link").symlink_to(tmp_path / "outside")
    (root / "inside_link").symlink_to(root / "crossing")
    return root


def test_the_datasets_under_the_data_folders_are_found_and_no_link_out(data: Path) -> None:
    listed = found(data_roots([data]))
    assert [(d.name, d.kind) for d in listed] == [("data/crossing", "interaction"), ("data/more/deeper", "interaction"),
                                                 ("data/tables/boxes.csv", "table")]
    assert all(d.source.resolve().is_relative_to(data.resolve()) for d in listed)


def test_the_search_goes_so_deep_and_lists_so_many(data: Path) -> None:
    assert [d.name for d in found(data_roots([data]), depth=1)] == ["data/crossing", "data/tables/boxes.csv"]
    assert len(found(data_roots([data]), most=1)) == 1


def test_a_data_folder_that_is_not_one_is_named_in_one_line(tmp_path: Path) -> None:
    with pytest.raises(DataError, match=r"^--data .*nowhere: not a folder$"):
        data_roots([tmp_path / "nowhere"])


def test_a_dataset_with_a_link_out_is_not_opened_and_nothing_of_it_is_read(data: Path, tmp_path: Path,
                                                                           monkeypatch) -> None:
    catalogue = Catalogue(start_dataset("synthetic:30"), Explorer(loaders.open("synthetic:30")), data_roots([data]))
    (tmp_path / "secret.csv").write_text("not yours\n")
    (data / "crossing" / "pedestrian_tracks_000.csv").symlink_to(tmp_path / "secret.csv")
    opened = []
    monkeypatch.setattr(datasets.loaders, "open", lambda source: opened.append(source))
    assert escape(data / "crossing", catalogue.roots) == "pedestrian_tracks_000.csv links outside the data folders"
    with pytest.raises(DataError, match="data/crossing: not opened, pedestrian_tracks_000.csv links outside"):
        catalogue.explorer("data/crossing")
    assert opened == []


def test_only_the_names_offered_open(data: Path) -> None:
    catalogue = Catalogue(start_dataset("synthetic:30"), Explorer(loaders.open("synthetic:30")), data_roots([data]))
    assert catalogue.names == ("synthetic:30", "argoverse2 (shipped)", "data/crossing", "data/more/deeper",
                               "data/tables/boxes.csv")
    for name in ("../outside", str(data / "outside_link"), "data/outside_link", "/etc/passwd"):
        with pytest.raises(DataError, match="is not a dataset offered here"):
            catalogue.explorer(name)


def test_each_dataset_is_opened_once_and_shared(data: Path, monkeypatch) -> None:
    catalogue = Catalogue(start_dataset("synthetic:30"), Explorer(loaders.open("synthetic:30")), data_roots([data]))
    calls, original = [], loaders.open
    monkeypatch.setattr(datasets.loaders, "open", lambda source: calls.append(source) or original(source))
    opened: list[Explorer] = []
    threads = [threading.Thread(target=lambda: opened.append(catalogue.explorer("data/crossing"))) for _ in range(4)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join(60)
    assert len(calls) == 1 and len(opened) == 4 and all(e is opened[0] for e in opened)
    assert catalogue.explorer("synthetic:30") in catalogue.explorers and opened[0] in catalogue.explorers


def test_a_dataset_opens_on_the_first_frame_cbm_can_run_on_and_says_so(tmp_path: Path) -> None:
    """Issue 47: INTERACTION opened on a frame of two cars, each seeing nothing the other sees."""
    explorer = Explorer(loaders.open(intersection(tmp_path / "rec")))
    settings = Settings()
    assert shared_objects(explorer, settings, 0) == 0 and not runs_on(explorer, settings, 0)
    first = first_usable(explorer, settings, range(len(explorer)))
    assert first == 10 and shared_objects(explorer, settings, first) >= FEWEST_SHARED
    start, note = start_of(explorer, settings)
    assert start.frame == first
    assert note == (f"frame 0 has fewer than {FEWEST_SHARED} objects seen by both an ego and a CAV under the range "
                    f"protocol, too few for CBM to stand by a pose; frame {first}, the first with enough, is shown")


def test_a_dataset_no_frame_of_which_cbm_can_run_on_says_so(tmp_path: Path) -> None:
    explorer = Explorer(loaders.open(intersection(tmp_path / "rec", two_until=30)))
    start, note = start_of(explorer, Settings())
    assert start.frame == 0 and note == (f"no frame of this dataset has {FEWEST_SHARED} objects seen by both an ego "
                                         "and a CAV under the range protocol (at most 0): CBM abstains, whatever it "
                                         "finds; frame 0, the first with an ego and a CAV, is shown")


def test_a_tabs_settings_carry_to_another_dataset_where_it_offers_them() -> None:
    explorer = Explorer(loaders.open("synthetic:30"))
    mine = Settings(frame=40, cav="abc", method="icp")
    assert settings_on(mine, explorer, Settings()) == Settings(method="icp")
    dataset_poses = mine.with_scenario(localization="dataset")
    assert settings_on(dataset_poses, explorer, Settings(method="vips")) == Settings(method="vips")


def test_data_is_repeatable_and_a_bad_folder_exits_with_one_line(tmp_path: Path, capsys) -> None:
    assert parse(["--data", "a", "b", "--data", "c"]).data == ["a", "b", "c"]
    assert main(["--data", str(tmp_path / "nowhere"), "--port", "0"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].endswith(f"error: --data {tmp_path / 'nowhere'}: not a folder")
