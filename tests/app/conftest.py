"""Shared fixtures of the app tests: the shipped scene and a small synthetic one, loaded once; a
headless chromium for the browser tests."""
from __future__ import annotations

import pytest

import loaders
from app.session.explorer import Explorer


@pytest.fixture(scope="session")
def explorer() -> Explorer:
    return Explorer(loaders.open("argoverse2"))


@pytest.fixture(scope="session")
def small_explorer() -> Explorer:
    """A synthetic intersection of 60 objects over 50 frames: quick to run over every frame."""
    return Explorer(loaders.open("synthetic:60"))


@pytest.fixture(scope="module")
def browser():
    sync_api = pytest.importorskip("playwright.sync_api")
    from support.browser import launch

    yield from launch(sync_api)
