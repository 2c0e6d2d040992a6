"""Named parameter sets as TOML: the shipped ones in ``presets/``, the user's in a folder of theirs.

A preset file holds an optional ``description``, an optional ``name`` (the name it was saved under)
and the tables of ``settings.to_preset`` (``method``, ``[scenario]``, ``[cbm]``, ``[view]``, ...
with angles in degrees); it is named by its file stem. Keys it leaves out take the app's defaults.
The user folder is ``$CBM_EXPLORER_PRESETS`` or ``~/.config/cbm-explorer/presets``.

Reading cannot hurt the app: a file ``evaluation.presets.read_toml`` refuses (too large, nested too
deep, not UTF-8, not TOML, not a regular file), or one whose reading raises anything at all, is
skipped with the reason. Files are read once and kept while their modification time and size stay
the same.
"""
from __future__ import annotations

import dataclasses
import hashlib
import os
import tempfile
import threading
import unicodedata
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import tomli_w

from evaluation.presets import PresetError, read_toml
from presets import SHIPPED_DIR

from .markup import plain
from .settings import Settings, from_preset, to_preset

ENV_VAR = "CBM_EXPLORER_PRESETS"
MAX_NAME = 80
"""Longest preset name, in characters."""


@dataclass(frozen=True)
class Preset:
    name: str
    description: str
    path: Path
    shipped: bool
    tables: dict[str, Any]
    """The file's content without ``description`` and ``name``."""
    saved_as: str = ""
    """The name the user saved it under (the file stem for a file written by hand)."""

    def apply(self, current: Settings) -> Settings:
        """This preset over the app's defaults, keeping ``current``'s frame, CAV and view (the
        preset's ``[view]`` keys, if any, replace the view's)."""
        return from_preset(self.tables, Settings(frame=current.frame, cav=current.cav, view=current.view))


def in_use(presets: dict[str, Preset], settings: Settings) -> str | None:
    """The first preset ``settings`` compute as (loading it would change no result: the frame, the
    CAVs and the view aside); None when none does."""
    kept = {"frame": settings.frame, "cav": settings.cav, "cavs": settings.cavs, "view": settings.view}
    return next((name for name, preset in presets.items()
                 if dataclasses.replace(preset.apply(settings), **kept) == settings), None)


def user_dir() -> Path:
    """Where the user's presets are saved."""
    return Path(os.environ.get(ENV_VAR) or Path.home() / ".config" / "cbm-explorer" / "presets")


def read(path: Path, shipped: bool) -> Preset:
    """Read and check one preset file; ``PresetError`` names the file and what is wrong, whatever
    went wrong (size, depth, encoding, syntax, unknown keys, wrong types, recursion, I/O)."""
    try:
        data = read_toml(path, path.name)
        description, saved_as = data.pop("description", ""), data.pop("name", path.stem)
        if not isinstance(description, str) or not isinstance(saved_as, str):
            raise PresetError(f"{path.name}: description and name must be text")
        from_preset(data)
    except PresetError:
        raise
    except (KeyError, TypeError, ValueError) as error:
        raise PresetError(f"{path.name}: {error.args[0] if error.args else error}") from None
    except Exception as error:  # any other failure to read one file skips that file only
        raise PresetError(f"{path.name}: {type(error).__name__}: {error}") from None
    return Preset(path.stem, description, path, shipped, data, saved_as)


_read_cache: dict[Path, tuple[tuple[int, int], Preset | PresetError]] = {}
_cache_lock = threading.Lock()


def read_cached(path: Path, shipped: bool) -> Preset:
    """``read``, remembered while the file's modification time and size stay the same."""
    stat = path.stat()
    stamp = (stat.st_mtime_ns, stat.st_size)
    with _cache_lock:
        known = _read_cache.get(path)
    if known is None or known[0] != stamp:
        try:
            result: Preset | PresetError = read(path, shipped)
        except PresetError as error:
            result = error
        known = (stamp, result)
        with _cache_lock:
            _read_cache[path] = known
    if isinstance(known[1], PresetError):
        raise known[1]
    return known[1]


def _forget_missing(present: set[Path]) -> None:
    with _cache_lock:
        for path in [p for p in _read_cache if p not in present]:
            del _read_cache[path]


def discover(shipped_dir: Path = SHIPPED_DIR, users: Path | None = None) -> tuple[dict[str, Preset], list[str]]:
    """Every readable preset by name (shipped first, then the user's; a user file may not take a
    shipped name) and one message per file that was skipped."""
    presets: dict[str, Preset] = {}
    problems: list[str] = []
    seen: set[Path] = set()
    for folder, shipped in ((shipped_dir, True), (users or user_dir(), False)):
        for path in _listing(folder, problems):
            seen.add(path)
            try:
                preset = read_cached(path, shipped)
            except (PresetError, OSError) as error:
                problems.append(str(error) if isinstance(error, PresetError) else f"{path.name}: {error}")
                continue
            if preset.name in presets:
                problems.append(f"{path.name}: the name {preset.name!r} is taken by a shipped preset; skipped")
                continue
            presets[preset.name] = preset
    _forget_missing(seen)
    return presets, problems


def _listing(folder: Path, problems: list[str]) -> list[Path]:
    """The ``*.toml`` files of the presets folder ``folder`` (none when it does not exist); a folder
    that cannot be listed, or is not a folder, is reported in ``problems`` rather than taken as empty."""
    try:
        if not folder.exists():
            return []
        if not folder.is_dir():
            problems.append(f"{folder}: the presets folder is not a folder; its presets are not offered")
            return []
        with os.scandir(folder) as entries:
            return sorted(Path(entry.path) for entry in entries if entry.name.endswith(".toml"))
    except OSError as error:
        problems.append(f"{folder}: the presets folder cannot be listed ({error.strerror or error}); "
                        "its presets are not offered")
        return []


def skipped_markdown(problems: list[str]) -> str:
    """The Presets tab's list of skipped files and why ("" when none was)."""
    if not problems:
        return ""
    return "**Preset files skipped:**\n\n" + "\n".join(f"- {plain(p[:300])}" for p in problems)


MAX_STEM_BYTES = 200
"""Longest file stem, in UTF-8 bytes (file systems allow 255 bytes per name; 80 characters of a
non-Latin script can take 320)."""


def slug(name: str) -> str:
    """The file stem of a preset name: in any script, case folded, with each run of characters that
    are not letters, marks or digits (spaces, punctuation, path separators) made one hyphen; one
    longer than ``MAX_STEM_BYTES`` is cut at a character and ends with a digest of the whole name."""
    folded = unicodedata.normalize("NFC", name).casefold()
    kept = "".join(c if unicodedata.category(c)[0] in "LMN" else " " for c in folded)
    stem = "-".join(kept.split())
    if len(stem.encode("utf-8")) <= MAX_STEM_BYTES:
        return stem
    digest = hashlib.sha256(folded.encode("utf-8")).hexdigest()[:10]
    cut = stem.encode("utf-8")[:MAX_STEM_BYTES - len(digest) - 1].decode("utf-8", errors="ignore")
    return f"{cut.rstrip('-')}-{digest}"


def _same_name(a: str, b: str) -> bool:
    return all_words(a) == all_words(b)


def all_words(name: str) -> str:
    """``name`` compared for sameness: Unicode-normalised, case folded, spaces collapsed."""
    return " ".join(unicodedata.normalize("NFC", name).split()).casefold()


def checked_stem(name: str, folder: Path, shipped_dir: Path = SHIPPED_DIR) -> str:
    """The file stem ``name`` saves under; ``PresetError`` for an empty or over-long name, a shipped
    preset's name, or a name that differs from the one already saved in that file (``../x`` and
    ``..\\x`` are refused rather than overwrite each other)."""
    if len(name) > MAX_NAME:
        raise PresetError(f"a preset name may have at most {MAX_NAME} characters; this one has {len(name)}")
    stem = slug(name)
    if not stem:
        raise PresetError("a preset needs a name with at least one letter or digit")
    if (shipped_dir / f"{stem}.toml").exists():
        raise PresetError(f"{stem!r} is a shipped preset and cannot be overwritten; choose another name")
    target = folder / f"{stem}.toml"
    if target.exists():
        try:
            existing = read(target, shipped=False).saved_as
        except PresetError:
            existing = stem
        if not _same_name(existing, name):
            raise PresetError(f"{name!r} would be saved as {stem}.toml, which holds the preset {existing!r}; "
                              f"choose another name, or save as {existing!r} to replace it")
    return stem


def save_preset(name: str, settings: Settings, shipped_dir: Path = SHIPPED_DIR, users: Path | None = None) -> Path:
    """Write ``settings`` as the user preset ``name``, atomically (temporary file + rename in the
    same folder); refuses what ``checked_stem`` refuses."""
    folder = users or user_dir()
    stem = checked_stem(name, folder, shipped_dir)
    folder.mkdir(parents=True, exist_ok=True)
    text = tomli_w.dumps({"description": f"Saved from CBM Explorer as {name!r}.", "name": name,
                          **to_preset(settings)})
    handle, temporary = tempfile.mkstemp(dir=folder, prefix=f".{stem}.", suffix=".tmp")
    try:
        with os.fdopen(handle, "w", encoding="utf-8") as out:
            out.write(text)
        os.replace(temporary, folder / f"{stem}.toml")
    except BaseException:
        Path(temporary).unlink(missing_ok=True)
        raise
    return folder / f"{stem}.toml"
