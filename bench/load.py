"""The app under load: N browser tabs editing at once, every edit timed from input to the page
showing its result (issue 16, part 4).

It starts the app's server in this process on a free loopback port, opens ``--tabs`` tabs in one
headless chromium (Debian's, under Playwright, software WebGL as the browser tests use), waits for
each tab's first frame, then lets every tab edit continuously: type a sigma2 into the Method tab's
number box (alternating values), and as soon as that tab's page shows the result, type the next,
``--edits`` times per tab. An edit is timed in its page, from the box's input event to the first
painted frame after the metrics panel names the new sigma2. ``--jobs K`` first starts "run all
frames" in the first K tabs, so edits compete with long jobs (queued, one at a time on 2 cores).

Server tracebacks are counted from everything written to stderr (threads' uncaught exceptions,
logging, viser) while the bench runs. An edit whose result never shows within ``LOST_SECONDS`` is
counted as lost.

    python bench/load.py [--tabs 8] [--edits 20] [--jobs 1] [--dataset argoverse2]
"""
from __future__ import annotations

import argparse
import contextlib
import io
import statistics
import sys
import time
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT), str(ROOT / "tests")]

import loaders  # noqa: E402
from app.server import ExplorerServer  # noqa: E402
from app.session.explorer import Explorer  # noqa: E402
from app.session.presets import discover  # noqa: E402
from app.session.settings import Settings  # noqa: E402
from support.browser import ARGS, CHROMIUM, label  # noqa: E402

SIGMA2 = (2.5, 3.5, 2.0)
"""The sigma2 values each tab's edits cycle through: never twice in a row, none the default 3.0."""
LOST_SECONDS = 60.0
"""An edit not shown after this long is counted as lost and the tab moves on."""
SLOW_MS = 10_000.0
"""The issue's bound: no edit's result later than this."""

WATCH = """() => {
  const load = window.__load = {started: null, done: null, expected: null};
  const shows = () => [...document.querySelectorAll('table')]
    .some(t => t.textContent.includes('precision / recall') && t.parentElement.textContent.includes(load.expected));
  document.addEventListener('input', () => { if (load.started === null) load.started = performance.now(); }, true);
  new MutationObserver(() => {
    if (load.started === null || load.done !== null || load.expected === null || !shows()) return;
    load.done = -1;
    requestAnimationFrame(() => setTimeout(() => { load.done = performance.now(); }, 0));
  }).observe(document.body, {subtree: true, childList: true, characterData: true});
}"""
ARM = "expected => Object.assign(window.__load, {started: null, done: null, expected})"
READ = "() => window.__load.done > 0 ? window.__load.done - window.__load.started : null"


@dataclass
class Load:
    """Per-edit latencies (ms) of every tab, the edits lost, the server's tracebacks."""

    tabs: int
    times: list[float] = field(default_factory=list)
    lost: int = 0
    tracebacks: int = 0
    seconds: float = 0.0

    @property
    def slow(self) -> int:
        return sum(t > SLOW_MS for t in self.times) + self.lost

    def summary(self) -> str:
        times = sorted(self.times) or [float("nan")]
        p95 = times[min(len(times) - 1, int(0.95 * len(times)))]
        return (f"{self.tabs} tabs, {len(self.times) + self.lost} edits in {self.seconds:.0f} s: "
                f"median {statistics.median(times):.0f} ms, p95 {p95:.0f} ms, max {max(times):.0f} ms, "
                f"over 10 s {self.slow} (lost {self.lost}), server tracebacks {self.tracebacks}")


class CountingStderr(io.TextIOBase):
    """stderr that passes everything on and counts the tracebacks written to it."""

    def __init__(self, wrapped) -> None:
        self.wrapped, self.tracebacks = wrapped, 0

    def write(self, text: str) -> int:
        self.tracebacks += text.count("Traceback (most recent call last)")
        return self.wrapped.write(text)

    def flush(self) -> None:
        self.wrapped.flush()


@contextlib.contextmanager
def counted_stderr() -> Iterator[CountingStderr]:
    """Within the block, stderr (so logging and threads' uncaught exceptions too) is counted."""
    counting, original = CountingStderr(sys.stderr), sys.stderr
    sys.stderr = counting
    try:
        yield counting
    finally:
        sys.stderr = original


def number_box(page, text: str):
    """The number box beside the slider labelled ``text``."""
    control = label(page, text).get_attribute("for")
    row = page.locator(f'[id="{control}"]').locator("xpath=ancestor::div[contains(@class, 'mantine-Flex-root')][1]")
    return row.locator("input.mantine-NumberInput-input")


class Tab:
    """One page editing sigma2 over and over: ``edit`` types the next value, ``poll`` reads the
    latency once the page shows it (None until then)."""

    def __init__(self, browser, url: str, first: int) -> None:
        self.page = browser.new_page(viewport={"width": 1200, "height": 800})
        self.page.goto(url)
        self.count, self.started, self.first = 0, 0.0, first

    def ready(self, jobs: bool) -> None:
        self.page.get_by_text("precision / recall").first.wait_for(timeout=300_000)
        if jobs:
            self.page.get_by_role("tab", name="Explore").click()
            self.page.get_by_role("button", name="run all frames").click()
        self.page.get_by_role("tab", name="Method").click()
        self.box = number_box(self.page, "σ2 distance (m)")
        self.page.evaluate(WATCH)

    def edit(self) -> None:
        value = SIGMA2[(self.first + self.count) % len(SIGMA2)]
        self.page.evaluate(ARM, f"σ2 {value:.2f} m")
        self.box.fill(f"{value:g}")
        self.count, self.started = self.count + 1, time.monotonic()

    def poll(self) -> float | None:
        return self.page.evaluate(READ)

    def overdue(self) -> bool:
        return time.monotonic() - self.started > LOST_SECONDS


def drive(tabs: list[Tab], edits: int, load: Load) -> None:
    """Every tab edits as soon as its previous edit shows, until each made ``edits``."""
    for tab in tabs:
        tab.edit()
    active = list(tabs)
    while active:
        for tab in list(active):
            shown = tab.poll()
            if shown is None and not tab.overdue():
                continue
            if shown is None:
                load.lost += 1
            else:
                load.times.append(shown)
            if tab.count < edits:
                tab.edit()
            else:
                active.remove(tab)
        time.sleep(0.02)


def run_load(server: ExplorerServer, browser, tabs: int, edits: int, jobs: int = 0) -> Load:
    """``tabs`` tabs on ``server`` each making ``edits`` sigma2 edits at once; the first ``jobs``
    tabs first start a run over every frame."""
    load = Load(tabs)
    with counted_stderr() as stderr:
        opened = [Tab(browser, server.url, k) for k in range(tabs)]
        try:
            for k, tab in enumerate(opened):
                tab.ready(k < jobs)
            start = time.monotonic()
            drive(opened, edits, load)
            load.seconds = time.monotonic() - start
        finally:
            for tab in opened:
                tab.page.close()
        load.tracebacks = stderr.tracebacks
    return load


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--tabs", type=int, default=8)
    parser.add_argument("--edits", type=int, default=20, help="edits per tab")
    parser.add_argument("--jobs", type=int, default=0, help="tabs that first start 'run all frames'")
    parser.add_argument("--dataset", default="argoverse2")
    args = parser.parse_args()
    if CHROMIUM is None:
        raise SystemExit("load.py needs Debian's chromium (make test installs it)")
    from playwright.sync_api import sync_playwright

    presets, _ = discover()
    server = ExplorerServer(Explorer(loaders.open(args.dataset)), presets["default"].apply(Settings()), port=0)
    try:
        with sync_playwright() as playwright:
            browser = playwright.chromium.launch(executable_path=CHROMIUM, args=ARGS)
            load = run_load(server, browser, args.tabs, args.edits, args.jobs)
            browser.close()
    finally:
        server.stop()
    print(f"`{args.dataset}`, {args.jobs} long job(s): {load.summary()}")


if __name__ == "__main__":
    main()
