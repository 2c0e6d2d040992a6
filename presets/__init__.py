"""The presets shipped with CBM Explorer: named settings (method, CBM's thresholds, scenario, view) as
TOML files in this folder, carried by the wheel. ``app.session.presets`` reads them beside the user's
own (``$CBM_EXPLORER_PRESETS`` or ``~/.config/cbm-explorer/presets``); ``cbm-explorer --list-presets``
lists both. ``evaluation.presets`` reads their tables for the app and ``evaluate.py --preset``, and
``default.toml`` holds everyone's defaults.
"""
from pathlib import Path

SHIPPED_DIR = Path(__file__).resolve().parent
"""The folder of the shipped ``*.toml`` presets."""
