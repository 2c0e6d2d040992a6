"""The Steps tab: CBM's steps, one at a time, on the frame on screen (``app.walkthrough``)."""
from __future__ import annotations

from ..walkthrough.panel import WalkthroughPanel
from .registry import Panel

PANEL = Panel("Steps", 60, "CBM's steps one at a time on the frame on screen, each drawn in the scene",
              WalkthroughPanel)
"""Its title is short, so that the panel's six tabs fit on one row at its width (384 px)."""
