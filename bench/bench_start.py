"""Start-up of the app as a person sees it: from launching ``serve.py`` to the first result in a page.

Launches ``serve.py`` on the default scene, opens headless chromium (Debian's, as the browser tests
do) as soon as the server prints its address, and times until the metrics panel shows the first
result. Run with an empty numba cache (a fresh install or a clean clone: CBM's kernels are
compiled at start, meanwhile the first frames run interpreted) and then with the cache that run
filled. Also prints the CBM time the first frame shows and the compile note beside it (the compile
is never part of CBM's time).

    python bench/bench_start.py [--runs 2]
"""
from __future__ import annotations

import argparse
import os
import re
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

from playwright.sync_api import sync_playwright  # noqa: E402

from support.browser import ARGS, CHROMIUM  # noqa: E402


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def first_result(browser, cache: Path) -> tuple[float, str, str, str]:
    """(seconds from launch to the first metrics, CBM time shown, compile note shown, seconds to
    the compiled result when the first one ran interpreted: the run leaves the cache filled)."""
    port = free_port()
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache)}
    started = time.perf_counter()
    server = subprocess.Popen([sys.executable, "serve.py", "--port", str(port)], cwd=ROOT, env=env, text=True,
                              stdout=subprocess.PIPE, stderr=subprocess.DEVNULL)
    try:
        next(line for line in server.stdout if line.startswith("CBM Explorer on"))
        page = browser.new_page(viewport={"width": 1280, "height": 720})
        page.goto(f"http://127.0.0.1:{port}")
        page.get_by_text("precision / recall").first.wait_for(timeout=300_000)
        seconds = time.perf_counter() - started
        text = page.locator("body").inner_text()
        compiled = "-"
        if "compiling (first start only)" in text:
            page.get_by_text(re.compile("CBM's kernels compiled in")).wait_for(timeout=600_000)
            compiled = f"{time.perf_counter() - started:.1f}"
        page.close()
    finally:
        server.terminate()
        server.wait(timeout=20)
    cbm_time = re.search(r"CBM time\s+([\d.]+ ms)", text)
    note = re.search(r"CBM's kernels compil(?:ed in [\d.]+ s|ing \(first start only\))", text)
    return seconds, cbm_time.group(1) if cbm_time else "?", note.group(0) if note else "-", compiled


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=2)
    args = parser.parse_args()
    print("| numba cache | first result after launch (s) | its CBM time | compile note | compiled result (s) |")
    print("|---|---:|---:|---|---:|")
    with sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=CHROMIUM, args=ARGS)
        for _ in range(args.runs):
            with tempfile.TemporaryDirectory() as cache:
                for state in ("empty (fresh install)", "filled by the run before"):
                    seconds, cbm_time, note, compiled = first_result(browser, Path(cache))
                    print(f"| {state} | {seconds:.1f} | {cbm_time} | {note} | {compiled} |", flush=True)
        browser.close()


if __name__ == "__main__":
    main()
