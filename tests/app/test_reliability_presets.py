"""Presets cannot hurt the app (issue 16, part 2): any bad file is skipped with its reason, size
and depth are limited, files are read once per change, and distinct names never share a file."""
from __future__ import annotations

import os
import time
from pathlib import Path

import pytest

from app.session import presets as module
from app.session.presets import MAX_NAME, PresetError, discover, read, save_preset, skipped_markdown
from app.session.settings import Settings
from evaluation import presets as reader
from evaluation.presets import nesting_depth

BAD_FILES = {
    "deep.toml": b"x = " + b"[" * 5000 + b"]" * 5000,
    "deepinline.toml": b"x = " + b"{a = " * 400 + b"1" + b"}" * 400,
    "latin1.toml": b'description = "caf\xe9"\n',
    "syntax.toml": b"[cbm\nsigma2 = 3",
    "wrongtype.toml": b"description = 3\n",
    "tablewrong.toml": b"cbm = 5\n",
    "nametype.toml": b"name = [1]\n",
    "huge.toml": b"# " + b"a" * (reader.MAX_BYTES + 10) + b"\n",
}


def test_every_kind_of_bad_file_is_skipped_with_its_reason(tmp_path: Path) -> None:
    for name, data in BAD_FILES.items():
        (tmp_path / name).write_bytes(data)
    (tmp_path / "folder.toml").mkdir()
    (tmp_path / "good.toml").write_text("[cbm]\nsigma2 = 2\n")
    presets, problems = discover(users=tmp_path)
    assert "good" in presets
    skipped = {p.split(":")[0] for p in problems}
    assert skipped == set(BAD_FILES) | {"folder.toml"}
    text = "\n".join(problems)
    assert "nested deeper than" in text and "larger than 256 KB" in text and "UnicodeDecodeError" in text
    assert "folder.toml: a folder, not a regular file; not read" in text
    markdown = skipped_markdown(problems)
    assert markdown.startswith("**Preset files skipped:**") and markdown.count("\n- ") == len(problems)
    assert skipped_markdown([]) == ""


def test_recursion_inside_the_parser_is_caught_too(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(reader, "MAX_DEPTH", 10**6)
    path = tmp_path / "deep.toml"
    path.write_bytes(BAD_FILES["deep.toml"])
    with pytest.raises(PresetError, match="RecursionError"):
        read(path, shipped=False)


def test_nesting_depth_ignores_brackets_in_strings_and_comments() -> None:
    assert nesting_depth('[cbm]\nsigma2 = 2 # [[[[\nname = "[[[["\nx = [[1], [2]]\n') == 2
    assert nesting_depth("'''\n[[[\n'''") == 0


def test_files_are_read_once_until_they_change(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    path = tmp_path / "mine.toml"
    path.write_text("[cbm]\nsigma2 = 2\n")
    reads: list[Path] = []
    original = module.read
    monkeypatch.setattr(module, "read", lambda p, shipped: reads.append(p) or original(p, shipped))
    discover(users=tmp_path)
    discover(users=tmp_path)
    assert reads.count(path) == 1
    path.write_text("[cbm]\nsigma2 = 3.5\n")
    os.utime(path, ns=(time.time_ns() + 10**9, time.time_ns() + 10**9))
    presets, _ = discover(users=tmp_path)
    assert reads.count(path) == 2 and presets["mine"].apply(Settings()).cbm.sigma2 == 3.5


def test_distinct_names_never_share_a_file(tmp_path: Path) -> None:
    first = save_preset("../x", Settings(), users=tmp_path)
    with pytest.raises(PresetError, match=r"which holds the preset '\.\./x'"):
        save_preset("..\\x", Settings(), users=tmp_path)
    assert first == tmp_path / "x.toml" and read(first, shipped=False).saved_as == "../x"
    assert save_preset(" ../X ", Settings().with_params("cbm", sigma2=5.0), users=tmp_path) == first, \
        "the same name again (case and spaces aside) replaces its own preset"
    assert read(first, shipped=False).apply(Settings()).cbm.sigma2 == 5.0
    (tmp_path / "hand.toml").write_text("[cbm]\nsigma2 = 2\n")
    save_preset("hand", Settings(), users=tmp_path)
    with pytest.raises(PresetError, match="hand.toml"):
        save_preset("Hand!", Settings(), users=tmp_path)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["hand.toml", "x.toml"], "no temporary file is left"


def test_a_long_name_gets_a_clear_message(tmp_path: Path) -> None:
    with pytest.raises(PresetError, match=f"at most {MAX_NAME} characters; this one has 300"):
        save_preset("a" * 300, Settings(), users=tmp_path)
    assert save_preset("b" * MAX_NAME, Settings(), users=tmp_path).name == "b" * MAX_NAME + ".toml"


def test_names_in_any_script_keep_their_letters_and_never_collide(tmp_path: Path) -> None:
    files = {"配置": "配置.toml", "配置 2": "配置-2.toml", "ünï": "ünï.toml", "हिन्दी": "हिन्दी.toml"}
    for name, file in files.items():
        assert save_preset(name, Settings(), users=tmp_path).name == file
    presets, problems = discover(users=tmp_path)
    assert problems == [] and {n: presets[Path(f).stem].saved_as for n, f in files.items()} == {n: n for n in files}
    assert save_preset("ÜNÏ", Settings(), users=tmp_path).name == "ünï.toml", "the same name in other case replaces it"
    with pytest.raises(PresetError, match="'配置!' would be saved as 配置.toml, which holds the preset '配置'"):
        save_preset("配置!", Settings(), users=tmp_path)
    longest = "配" * MAX_NAME
    path = save_preset(longest, Settings(), users=tmp_path)
    assert len(path.name.encode("utf-8")) <= 255 and read(path, shipped=False).saved_as == longest
    assert save_preset(longest, Settings(), users=tmp_path) == path
