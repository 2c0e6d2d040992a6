"""Shared fixtures of the app tests: the shipped scene, loaded once."""
from __future__ import annotations

import pytest

import loaders
from app.session import Explorer


@pytest.fixture(scope="session")
def explorer() -> Explorer:
    return Explorer(loaders.open("argoverse2"))
