"""Latency of the app as a person sees it: from an edit in a real browser to the page showing its
result.

Per dataset it starts the app's server on a free loopback port, opens one tab in headless chromium
(Debian's, under Playwright, with software WebGL as the browser tests use), waits for the first
result, then types into a control's number box: alternating sigma2 values in the Method tab (the
issue's measure), then successive frames (every node of the scene changes). Each edit is timed in
the page, from the box's input event to the moment the page shows the edit's result: the metrics
panel names the new sigma2 or frame (the panel is sent with the scene's nodes, in one batch), and
the 3D view's next draw after that has finished (a one-pixel read of the WebGL canvas, which waits
for the GPU, software or not); when nothing in the scene changed, the next painted frame.

"scene redrawn" counts the edits after which the 3D view drew before the page settled: the scene
changed, or one of the frames viser's client draws on its own (a heartbeat once a second, and a
quarter second of frames after every scene change) fell in the window. Those frames are part of
what a person waits for, so they are timed like any other.

The server's share of each edit is split out by timing the tab's worker: the recompute (trial,
method, metrics, diagnosis, drawing; CBM's own time apart) and the delivery (updating the scene's
nodes and the panels). What remains is the websocket and the browser (decoding, rebuilding the
three.js geometry, rendering). The CPU chromium's processes take per edit (``/proc``) shows how
much of the two cores the browser holds while the server computes: with software WebGL, its
renderer and GPU processes take about as much as CBM itself.

Needs the test extras (Playwright) and Debian's chromium, as ``make test`` installs them.

    python bench/bench_app.py [--datasets argoverse2 synthetic:300 synthetic:1000] [--edits 30]
"""
from __future__ import annotations

import argparse
import contextlib
import os
import statistics
import sys
import time
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT), str(ROOT / "tests")]

from playwright.sync_api import sync_playwright  # noqa: E402

import loaders  # noqa: E402
from app.server import ExplorerServer  # noqa: E402
from app.session.explorer import Explorer  # noqa: E402
from app.session.presets import discover  # noqa: E402
from app.session.settings import Settings  # noqa: E402
from support.browser import ARGS, CHROMIUM, label  # noqa: E402

SIGMA2 = (2.5, 3.0)
"""The sigma2 values the edits alternate between (the default preset's is 3.0)."""
PAUSE = 0.15
"""Seconds between a result and the next edit (viser's client throttles sends to one per 50 ms)."""

WATCH = """() => {
  const bench = window.__bench = {started: null, shown: null, done: null, expected: null, drew: false};
  const canvas = document.querySelector('canvas[data-engine]');
  const gl = canvas.getContext('webgl2') || canvas.getContext('webgl');
  for (const name of ['drawArrays', 'drawElements', 'drawArraysInstanced', 'drawElementsInstanced']) {
    const draw = gl[name].bind(gl);
    gl[name] = (...args) => { bench.drew = true; return draw(...args); };
  }
  const pixel = new Uint8Array(4);
  const metrics = () => [...document.querySelectorAll('table')]
    .find(t => t.textContent.includes('precision / recall'));
  const painted = (ticks) => requestAnimationFrame(() => setTimeout(() => {
    if (bench.drew) {
      gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, pixel);
      bench.done = performance.now();
      bench.redrawn = true;
    } else if (ticks >= 2) {
      bench.done = bench.firstPaint;
    } else {
      if (ticks === 0) bench.firstPaint = performance.now();
      painted(ticks + 1);
    }
  }, 0));
  document.addEventListener('input', () => {
    if (bench.started === null) bench.started = performance.now();
  }, true);
  new MutationObserver(() => {
    if (bench.started === null || bench.shown !== null) return;
    const table = metrics();
    if (!table || !table.parentElement.textContent.includes(bench.expected)) return;
    bench.shown = performance.now();
    bench.drew = false;
    painted(0);
  }).observe(document.body, {subtree: true, childList: true, characterData: true});
}"""
ARM = "expected => Object.assign(window.__bench, {started: null, shown: null, done: null, redrawn: false, expected})"


@dataclass
class Worker:
    """What the tab's worker spent per result (seconds), and the objects per agent it saw."""

    compute: list[float] = field(default_factory=list)
    deliver: list[float] = field(default_factory=list)
    cbm: list[float] = field(default_factory=list)
    objects: list[tuple[int, int]] = field(default_factory=list)


@contextlib.contextmanager
def timed_worker(session) -> Iterator[Worker]:
    """Within the block, time each recompute and delivery of the tab's worker."""
    spent, worker = Worker(), session.worker
    compute, deliver = worker._compute, worker._deliver

    def timed_compute(value):
        start = time.perf_counter()
        out = compute(value)
        spent.compute.append(time.perf_counter() - start)
        spent.cbm.append(out[0].result.timings.get("total", float("nan")))
        spent.objects.append((out[0].metrics.n_ego, out[0].metrics.n_cav))
        return out

    def timed_deliver(value, generation):
        start = time.perf_counter()
        deliver(value, generation)
        spent.deliver.append(time.perf_counter() - start)

    worker._compute, worker._deliver = timed_compute, timed_deliver
    try:
        yield spent
    finally:
        worker._compute, worker._deliver = compute, deliver


@dataclass
class Run:
    dataset: str
    edit: str
    times: list[float]
    redrawn: int
    """Edits whose result changed the 3D view (the others changed the panels only)."""
    worker: Worker
    browser_cpu: float
    """Seconds of CPU chromium's processes took per edit, on the cores the server computes on."""


def browser_cpu_seconds() -> float:
    """CPU seconds (user and system) chromium's processes under this one have taken so far."""
    tick, parents, spent = os.sysconf("SC_CLK_TCK"), {}, {}
    for pid in filter(str.isdigit, os.listdir("/proc")):
        with contextlib.suppress(OSError):
            with open(f"/proc/{pid}/stat") as f:
                fields = f.read().rsplit(")", 1)[1].split()
            with open(f"/proc/{pid}/cmdline", "rb") as f:
                chromium = b"chromium" in f.read().split(b"\0")[0]
            parents[int(pid)] = int(fields[1])
            spent[int(pid)] = (int(fields[11]) + int(fields[12])) / tick if chromium else 0.0
    mine, total = os.getpid(), 0.0
    for pid in parents:
        chain = pid
        while chain in parents and chain != mine:
            chain = parents[chain]
        if chain == mine:
            total += spent[pid]
    return total


def number_box(page, text: str):
    """The number box beside the slider labelled ``text`` (typing there moves the slider)."""
    control = label(page, text).get_attribute("for")
    row = page.locator(f'[id="{control}"]').locator("xpath=ancestor::div[contains(@class, 'mantine-Flex-root')][1]")
    return row.locator("input.mantine-NumberInput-input")


def timed_edits(page, box, values: list[str], markers: list[str]) -> tuple[list[float], int]:
    """Milliseconds from typing each of ``values`` into ``box`` to the page showing its result
    (the metrics naming its marker, the scene drawn), and how many of them redrew the scene."""
    page.evaluate(WATCH)
    times, redrawn = [], 0
    for value, marker in zip(values, markers):
        page.evaluate(ARM, marker)
        box.fill(value)
        page.wait_for_function("window.__bench.done !== null", timeout=120_000)
        times.append(page.evaluate("window.__bench.done - window.__bench.started"))
        redrawn += page.evaluate("window.__bench.redrawn")
        box.blur()
        time.sleep(PAUSE)
    return times, redrawn


def sigma2_edits(count: int) -> tuple[list[str], list[str]]:
    values = [SIGMA2[k % len(SIGMA2)] for k in range(count)]
    return [f"{v:g}" for v in values], [f"σ2 {v:.2f} m" for v in values]


def frame_edits(count: int, frames: int) -> tuple[list[str], list[str]]:
    values = [1 + k % (frames - 1) for k in range(count)]
    return [str(v) for v in values], [f"Frame {v} ·" for v in values]


def measure(dataset: str, edits: int, browser) -> list[Run]:
    """Serve ``dataset``, open a tab, time ``edits`` sigma2 edits then ``edits`` frame steps."""
    explorer = Explorer(loaders.open(dataset))
    presets, _ = discover()
    server = ExplorerServer(explorer, presets["default"].apply(Settings()), port=0)
    page = browser.new_page(viewport={"width": 1400, "height": 900})
    try:
        page.goto(server.url)
        page.get_by_text("precision / recall").first.wait_for(timeout=300_000)
        session = next(iter(server.sessions.values()))
        page.get_by_role("tab", name="Method").click()
        sigma2 = number_box(page, "σ2 distance (m)")
        timed_edits(page, sigma2, *sigma2_edits(2))
        runs = []
        for edit, box, (values, markers) in (("σ2", sigma2, sigma2_edits(edits)),
                                             ("frame", number_box(page, "frame"), frame_edits(edits, len(explorer)))):
            cpu = browser_cpu_seconds()
            with timed_worker(session) as spent:
                times, redrawn = timed_edits(page, box, values, markers)
            runs.append(Run(dataset, edit, times, redrawn, spent, (browser_cpu_seconds() - cpu) / len(times)))
        return runs
    finally:
        page.close()
        server.stop()


def table(runs: list[Run]) -> str:
    """The markdown table of the runs, then where the median edit's time goes."""
    lines = ["| dataset | edit | objects per agent (ego / CAV) | median ms | worst ms | n edits | scene redrawn |",
             "|---|---|---|---:|---:|---:|---:|"]
    for run in runs:
        ego, cav = (statistics.median(o[k] for o in run.worker.objects) for k in (0, 1))
        lines.append(f"| `{run.dataset}` | {run.edit} | {ego:.0f} / {cav:.0f} | {statistics.median(run.times):.1f} | "
                     f"{max(run.times):.1f} | {len(run.times)} | {run.redrawn} |")
    lines += ["", "Where the median goes (ms): CBM, the rest of the recompute (trial, metrics, diagnosis, drawing), "
              "the delivery (updating the nodes and panels), and the websocket plus the browser; then the CPU "
              "chromium's processes took per edit (on the same cores).", "",
              "| dataset | edit | total | CBM | rest of recompute | delivery | socket + browser | browser CPU |",
              "|---|---|---:|---:|---:|---:|---:|---:|"]
    for run in runs:
        total, w = statistics.median(run.times), run.worker
        cbm = 1000 * statistics.median(w.cbm)
        compute, deliver = 1000 * statistics.median(w.compute), 1000 * statistics.median(w.deliver)
        lines.append(f"| `{run.dataset}` | {run.edit} | {total:.1f} | {cbm:.1f} | {compute - cbm:.1f} | "
                     f"{deliver:.1f} | {total - compute - deliver:.1f} | {1000 * run.browser_cpu:.0f} |")
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--datasets", nargs="+", default=["argoverse2", "synthetic:300", "synthetic:1000"])
    parser.add_argument("--edits", type=int, default=30)
    args = parser.parse_args()
    if CHROMIUM is None:
        raise SystemExit("bench_app.py needs Debian's chromium (make test installs it)")
    with sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=CHROMIUM, args=ARGS)
        runs = [run for dataset in args.datasets for run in measure(dataset, args.edits, browser)]
        browser.close()
    print(table(runs))


if __name__ == "__main__":
    main()
