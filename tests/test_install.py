"""The installable app: the wheel built from this tree, installed into a fresh venv, is the whole app.

The ``wheel``-marked tests build the wheel (``pip wheel --no-deps --no-build-isolation``) from a copy
of the packaged files, install it with ``--no-deps`` into a fresh venv that sees this venv's
site-packages through a ``.pth`` file (the dependencies, without downloading them; the editable
install's finder is not activated there), and run its ``cbm-explorer`` and ``cbm-evaluate`` commands
from a folder outside the repository. The last test checks the declared dependencies against the
imports of the installed packages.
"""
from __future__ import annotations

import ast
import csv
import os
import re
import shutil
import signal
import subprocess
import sys
import sysconfig
import urllib.request
import venv
import zipfile
from dataclasses import dataclass
from importlib.metadata import packages_distributions
from pathlib import Path

import pytest

from support.processes import line_with

if sys.version_info >= (3, 11):
    import tomllib
else:
    import tomli as tomllib

REPO = Path(__file__).resolve().parents[1]
PACKAGES = ("app", "cbm", "loaders", "evaluation", "presets")
BUILD_FILES = ("pyproject.toml", "README.md", "LICENSE")
START_TIMEOUT = 600.0
"""The installed app compiles its kernels into an empty cache before it serves: on a busy 2-core
machine that took over 180 s once."""


@dataclass(frozen=True)
class Installed:
    wheel: Path
    bin: Path
    elsewhere: Path
    """An empty folder outside the repository and the venv: the commands' working directory."""
    env: dict[str, str]


def _build_wheel(root: Path) -> Path:
    source = _mkdir(root / "source")
    for name in BUILD_FILES:
        shutil.copy2(REPO / name, source / name)
    for package in PACKAGES:
        shutil.copytree(REPO / package, source / package, ignore=shutil.ignore_patterns("__pycache__"))
    subprocess.run([sys.executable, "-m", "pip", "wheel", "-q", "--no-deps", "--no-build-isolation", str(source),
                    "-w", str(root / "dist")], check=True, capture_output=True, timeout=300)
    return next((root / "dist").glob("cbm_explorer-*.whl"))


def _mkdir(path: Path) -> Path:
    path.mkdir(parents=True)
    return path


def _fresh_venv(root: Path, wheel: Path) -> Path:
    """A new venv holding only the wheel; this venv's site-packages appended to its path."""
    venv.create(root / "venv", with_pip=False)
    python = root / "venv" / "bin" / "python"
    subprocess.run([sys.executable, "-m", "pip", "--python", str(python), "install", "-q", "--no-deps", str(wheel)],
                   check=True, capture_output=True, timeout=300)
    site = subprocess.run([str(python), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                          check=True, capture_output=True, text=True).stdout.strip()
    Path(site, "test-venv-dependencies.pth").write_text(sysconfig.get_paths()["purelib"] + "\n")
    return python.parent


@pytest.fixture(scope="module")
def installed(tmp_path_factory: pytest.TempPathFactory) -> Installed:
    root = tmp_path_factory.mktemp("install")
    wheel = _build_wheel(root)
    env = {"PATH": "/usr/bin:/bin", "HOME": str(_mkdir(root / "home")),
           "CBM_EXPLORER_PRESETS": str(_mkdir(root / "presets"))}
    return Installed(wheel, _fresh_venv(root, wheel), _mkdir(root / "elsewhere"), env)


def _run(installed: Installed, *command: str, timeout: float = 300) -> subprocess.CompletedProcess:
    return subprocess.run([str(installed.bin / command[0]), *command[1:]], cwd=installed.elsewhere,
                          env=installed.env, capture_output=True, text=True, timeout=timeout)


@pytest.mark.wheel
def test_wheel_holds_the_presets_the_default_scene_and_the_licences(installed: Installed) -> None:
    names = set(zipfile.ZipFile(installed.wheel).namelist())
    presets = {f"presets/{p.name}" for p in (REPO / "presets").glob("*.toml")}
    scene = {f"loaders/{p.relative_to(REPO / 'loaders').as_posix()}"
             for p in (REPO / "loaders" / "data").rglob("*") if p.is_file()}
    assert "presets/default.toml" in presets and presets <= names
    assert "loaders/data/argoverse2/NOTICE" in scene and scene <= names
    dist_info = next(name.split("/")[0] for name in names if name.endswith(".dist-info/METADATA"))
    assert {f"{dist_info}/licenses/LICENSE", f"{dist_info}/licenses/loaders/data/argoverse2/NOTICE"} <= names


@pytest.mark.wheel
def test_the_venv_imports_the_installed_packages_and_finds_their_data(installed: Installed) -> None:
    code = ("import app, cbm, evaluation, loaders; from app.session.presets import discover; "
            "print(*(m.__file__ for m in (app, cbm, evaluation, loaders))); "
            "print(len(loaders.open('argoverse2')), sorted(discover()[0]))")
    done = _run(installed, "python", "-c", code)
    assert done.returncode == 0, done.stderr
    files, data = done.stdout.splitlines()
    venv_root = str(installed.bin.parent)
    assert all(f.startswith(venv_root) and "site-packages" in f for f in files.split())
    assert data.startswith("156 ") and "'default'" in data and "'paper-sind'" in data


@pytest.mark.wheel
def test_cbm_explorer_lists_the_shipped_presets_from_any_folder(installed: Installed) -> None:
    done = _run(installed, "cbm-explorer", "--list-presets")
    assert done.returncode == 0, done.stderr
    listed = {line.split()[0]: line.split()[1] for line in done.stdout.splitlines()}
    shipped = {p.stem for p in (REPO / "presets").glob("*.toml")}
    assert {"default", "teaching"} <= shipped
    assert {name: "shipped" for name in shipped} == listed


@pytest.mark.wheel
def test_cbm_explorer_serves_the_app_from_any_folder(installed: Installed) -> None:
    process = subprocess.Popen([str(installed.bin / "cbm-explorer"), "--port", "0"], cwd=installed.elsewhere,
                               env=installed.env, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    try:
        line = line_with(process, "open http://", START_TIMEOUT)
        assert "argoverse2/adcf7d18" in line and "156 frames" in line
        url = re.search(r"http://\S+", line).group(0)
        with urllib.request.urlopen(url, timeout=60) as response:
            assert response.status == 200 and "<html" in response.read().decode().lower()
        process.send_signal(signal.SIGINT)
        assert process.wait(timeout=60) == 0
    finally:
        if process.poll() is None:
            process.kill()
            process.wait()


@pytest.mark.wheel
def test_cbm_evaluate_helps_and_runs_a_tiny_evaluation_from_any_folder(installed: Installed) -> None:
    helped = _run(installed, "cbm-evaluate", "--help")
    assert helped.returncode == 0 and "--dataset" in helped.stdout and "--protocol" in helped.stdout
    done = _run(installed, "cbm-evaluate", "--dataset", "argoverse2", "--frames", "0", "--methods", "cbm,oracle",
                "--workers", "1", "--no-timing", "--out", "results")
    assert done.returncode == 0, done.stderr
    out = installed.elsewhere / "results"
    assert {"trials.csv", "summary.md"} <= set(os.listdir(out))
    with open(out / "trials.csv", newline="") as trials:
        assert {row["method"] for row in csv.DictReader(trials)} == {"cbm", "oracle"}


def _third_party_imports() -> dict[str, set[str]]:
    """Top-level modules imported by the installed packages, outside the standard library, each
    with the files that import it."""
    found: dict[str, set[str]] = {}
    for package in PACKAGES:
        for path in (REPO / package).rglob("*.py"):
            for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
                if isinstance(node, ast.Import):
                    names = [alias.name for alias in node.names]
                elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                    names = [node.module]
                else:
                    continue
                for name in names:
                    found.setdefault(name.partition(".")[0], set()).add(str(path.relative_to(REPO)))
    return {m: f for m, f in found.items() if m not in sys.stdlib_module_names and m not in {*PACKAGES, "__future__"}}


def _normalised(name: str) -> str:
    return re.sub(r"[-_.]+", "-", name).lower()


def _names(requirements: list[str]) -> set[str]:
    return {_normalised(re.match(r"[A-Za-z0-9_.-]+", r).group(0)) for r in requirements}


def _declared() -> set[str]:
    return _names(tomllib.loads((REPO / "pyproject.toml").read_text())["project"]["dependencies"])


def _optional() -> set[str]:
    """The optional extras a user installs for a feature (``.[ray]``), not the test tools."""
    extras = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]["optional-dependencies"]
    return set().union(*(_names(requirements) for name, requirements in extras.items() if name != "test"))


def test_every_third_party_import_is_a_declared_dependency_and_every_dependency_is_imported() -> None:
    distributions = packages_distributions()
    imported = {m: {_normalised(d) for d in distributions.get(m, [m])} for m in _third_party_imports()}
    declared = _declared()
    undeclared = {m: sorted(_third_party_imports()[m]) for m, dists in imported.items()
                  if not dists & (declared | _optional())}
    assert not undeclared, f"imported but not declared in pyproject.toml: {undeclared}"
    unused = declared - set().union(*imported.values())
    assert not unused, f"declared in pyproject.toml but imported by none of {PACKAGES}: {sorted(unused)}"
