"""Named parameter sets as TOML: the shipped ones in ``app/presets/``, the user's in a folder of theirs.

A preset file holds an optional ``description`` and the tables of ``settings.to_preset``
(``method``, ``[scenario]``, ``[cbm]``, ``[view]``, ... with angles in degrees); it is named by its
file stem. Keys it leaves out take the app's defaults. The user folder is
``$CBM_EXPLORER_PRESETS`` or ``~/.config/cbm-explorer/presets``.
"""
from __future__ import annotations

import os
import re
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import tomli_w

from .settings import Settings, from_preset, to_preset

if sys.version_info >= (3, 11):
    import tomllib
else:
    import tomli as tomllib

SHIPPED_DIR = Path(__file__).resolve().parents[1] / "presets"
ENV_VAR = "CBM_EXPLORER_PRESETS"


class PresetError(ValueError):
    """A preset that cannot be read or saved; the message names the file and the field."""


@dataclass(frozen=True)
class Preset:
    name: str
    description: str
    path: Path
    shipped: bool
    tables: dict[str, Any]
    """The file's content without ``description``."""

    def apply(self, current: Settings) -> Settings:
        """This preset over the app's defaults, keeping ``current``'s frame, CAV and view (the
        preset's ``[view]`` keys, if any, replace the view's)."""
        return from_preset(self.tables, Settings(frame=current.frame, cav=current.cav, view=current.view))


def user_dir() -> Path:
    """Where the user's presets are saved."""
    return Path(os.environ.get(ENV_VAR) or Path.home() / ".config" / "cbm-explorer" / "presets")


def read(path: Path, shipped: bool) -> Preset:
    """Read and check one preset file; ``PresetError`` names the file and what is wrong."""
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError) as error:
        raise PresetError(f"{path.name}: {error}") from None
    description = data.pop("description", "")
    if not isinstance(description, str):
        raise PresetError(f"{path.name}: description must be text")
    try:
        from_preset(data)
    except (KeyError, TypeError, ValueError) as error:
        raise PresetError(f"{path.name}: {error.args[0] if error.args else error}") from None
    return Preset(path.stem, description, path, shipped, data)


def discover(shipped_dir: Path = SHIPPED_DIR, users: Path | None = None) -> tuple[dict[str, Preset], list[str]]:
    """Every readable preset by name (shipped first, then the user's; a user file may not take a
    shipped name) and one message per file that was skipped."""
    presets: dict[str, Preset] = {}
    problems: list[str] = []
    for folder, shipped in ((shipped_dir, True), (users or user_dir(), False)):
        for path in sorted(folder.glob("*.toml")) if folder.is_dir() else []:
            try:
                preset = read(path, shipped)
            except PresetError as error:
                problems.append(str(error))
                continue
            if preset.name in presets:
                problems.append(f"{path.name}: the name {preset.name!r} is taken by a shipped preset; skipped")
                continue
            presets[preset.name] = preset
    return presets, problems


def slug(name: str) -> str:
    """The file stem of a preset name."""
    return re.sub(r"[^a-z0-9]+", "-", name.lower()).strip("-")


def save_preset(name: str, settings: Settings, shipped_dir: Path = SHIPPED_DIR, users: Path | None = None) -> Path:
    """Write ``settings`` as the user preset ``name``, atomically (temporary file + rename in the
    same folder); refuses an empty name and the name of a shipped preset."""
    stem = slug(name)
    if not stem:
        raise PresetError("a preset needs a name with at least one letter or digit")
    if (shipped_dir / f"{stem}.toml").exists():
        raise PresetError(f"{stem!r} is a shipped preset and cannot be overwritten; choose another name")
    folder = users or user_dir()
    folder.mkdir(parents=True, exist_ok=True)
    text = tomli_w.dumps({"description": f"Saved from CBM Explorer as {name!r}.", **to_preset(settings)})
    handle, temporary = tempfile.mkstemp(dir=folder, prefix=f".{stem}.", suffix=".tmp")
    try:
        with os.fdopen(handle, "w", encoding="utf-8") as out:
            out.write(text)
        os.replace(temporary, folder / f"{stem}.toml")
    except BaseException:
        Path(temporary).unlink(missing_ok=True)
        raise
    return folder / f"{stem}.toml"
