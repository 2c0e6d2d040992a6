"""Shared paths for the loader tests: the fixtures beside this file, the repository's shipped
data, and ``<repo root>/../shared/data`` (optional; tests that need it skip without it)."""
from __future__ import annotations

import shutil
from pathlib import Path

import pytest

FIXTURES = Path(__file__).resolve().parent / "fixtures"
REPO = Path(__file__).resolve().parents[2]
SHIPPED_LOG = REPO / "loaders" / "data" / "argoverse2" / "adcf7d18-0510-35b0-a2fa-b4cea13a6d76"
SHARED_DATA = REPO.parent / "shared" / "data"


@pytest.fixture
def fixtures() -> Path:
    return FIXTURES


@pytest.fixture
def shipped_log() -> Path:
    return SHIPPED_LOG


@pytest.fixture
def shared_data() -> Path:
    if not SHARED_DATA.is_dir():
        pytest.skip("../shared/data is not beside the repository")
    return SHARED_DATA


@pytest.fixture
def copy_fixture(tmp_path):
    """Copy a fixture file or folder (relative to fixtures/) into a temporary folder."""
    def copy(relative: str) -> Path:
        source = FIXTURES / relative
        target = tmp_path / source.name
        if source.is_dir():
            shutil.copytree(source, target)
        else:
            shutil.copy(source, target)
        return target
    return copy
