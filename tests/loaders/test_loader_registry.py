"""Loaders are found, not listed (``loaders.dispatch.registered``): a module that says what it reads
joins ``loaders.open`` and its "expected ..." message by itself, with no edit anywhere else."""
from __future__ import annotations

import sys
from pathlib import Path

import pytest

import loaders
from loaders import dispatch

THROWAWAY = '''
from pathlib import Path

from loaders import synthetic

EXPECTED = "a throwaway scene (.throwaway)"


def recognises(path: Path) -> bool:
    return path.is_file() and path.suffix == ".throwaway"


def load(path):
    return synthetic.generate(n_objects=int(Path(path).read_text()), seed=3)
'''


@pytest.fixture
def throwaway(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """A loader module written to a folder that the ``loaders`` package is searched in too; gone after."""
    package = tmp_path / "package"
    package.mkdir()
    (package / "throwaway_scene.py").write_text(THROWAWAY)
    monkeypatch.setattr(loaders, "__path__", [*loaders.__path__, str(package)])
    yield tmp_path
    sys.modules.pop("loaders.throwaway_scene", None)


def test_a_new_loader_module_is_opened_and_named_without_an_edit_elsewhere(throwaway: Path) -> None:
    scene = throwaway / "scene.throwaway"
    scene.write_text("12")
    assert len(loaders.open(scene)[0].track_ids) == 12
    (throwaway / "notes.txt").write_text("hello")
    with pytest.raises(loaders.LoaderError, match=r"expected .*a throwaway scene \(\.throwaway\)"):
        loaders.open(throwaway / "notes.txt")


def test_the_message_lists_every_loader_and_the_broad_ones_come_last(tmp_path: Path) -> None:
    found = [module.__name__.removeprefix("loaders.") for module in dispatch.registered()]
    assert set(found) == {"argoverse2", "dair_v2x", "interaction", "opv2v", "sind", "table", "tumtraf_v2x",
                          "v2x_seq", "v2x_sim"}
    assert found[-3:] == ["dair_v2x", "opv2v", "table"], "V2X-Seq-SPD's data_info.json before DAIR-V2X's, tables last"
    (tmp_path / "notes.txt").write_text("hello")
    with pytest.raises(loaders.LoaderError) as raised:
        loaders.open(tmp_path / "notes.txt")
    message = str(raised.value)
    assert all(module.EXPECTED in message for module in dispatch.registered())
    assert message.endswith(", or a generic table (.csv / .parquet with a frame column)")
