"""What a scenario edit costs under CBM over time at a frame deep in the sequence, as a tab computes it.

CBM over time answers frame k from the frames before it, so an edit that changes every frame's trial
(a detection-noise level here: a new value each edit, none of them computed before) recomputes
frames 0..k before frame k shows. Per checkout, on the shipped scene under the ``drift-heavy``
preset, the tab's ``Explorer`` computes frame ``--frame`` once, then ``--edits`` edits, each timed
from the edit to its outcome (``Explorer.compute``: every frame before in order, the frame's trial,
its metrics) and to its drawing (``app.scene.drawing.draw``, what the tab sends). Then a step to the
next frame (the frames before are kept) and the calibrator's own share: its steps alone over the
same trials, built beforehand, the floor of any exact recompute. With ``--browser``, the same edits
typed into the Scenario tab of a tab open in headless chromium, each timed from the typing to the
tab having sent the frame computed under it (its scene, panels and key numbers, in one batch), and to
the page showing per-frame CBM's answer on it, marked, while the frames before are computed.
Each checkout runs in a process of its own, the checkouts alternating round by round on the same
machine (a loaded machine shifts both alike); the table gives the medians over the rounds and their
ratio (the first checkout's over the last's).

    python bench/bench_over_time.py [--roots . ../before] [--rounds 3] [--edits 5] [--frame 150] [--browser]
"""
from __future__ import annotations

import argparse
import dataclasses
import json
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve()
PACKAGES = ("cbm", "loaders", "evaluation", "app")


def typed_edits(frame: int, edits: int) -> dict[str, float]:
    """Milliseconds from typing each new σp into a tab's Scenario tab to the tab having sent its
    frame ``frame`` computed under it (CBM over time, ``drift-heavy``)."""
    from playwright.sync_api import sync_playwright

    import loaders
    from app.server import ExplorerServer
    from app.session.explorer import Explorer
    from app.session.presets import discover
    from app.session.settings import Settings
    from support.browser import ARGS, CHROMIUM, label, wait_until

    settings = dataclasses.replace(discover()[0]["drift-heavy"].apply(Settings()), frame=frame)
    server = ExplorerServer(Explorer(loaders.open("argoverse2")), settings, port=0)
    spent, previewed = [], []
    with sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=CHROMIUM, args=ARGS)
        page = browser.new_page(viewport={"width": 1400, "height": 900})
        page.goto(server.url)
        wait_until(lambda: server.sessions and next(iter(server.sessions.values())).last is not None, 300)
        tab = next(iter(server.sessions.values()))
        control = label(page, "position noise σp (m)").get_attribute("for")
        box = page.locator(f'[id="{control}"]').locator(
            "xpath=ancestor::div[contains(@class, 'mantine-Flex-root')][1]").locator("input.mantine-NumberInput-input")
        preview = page.get_by_text("shown while CBM over time computes the frames before it")
        for k in range(edits):
            value = round(settings.scenario.sigma_p + 0.01 * (k + 1), 2)
            started = time.perf_counter()
            box.fill(f"{value:g}")
            preview.first.wait_for(timeout=120_000)
            previewed.append(1000 * (time.perf_counter() - started))
            wait_until(lambda v=value: tab.last.settings.scenario.sigma_p == v and not tab.worker.superseded, 120)
            spent.append(1000 * (time.perf_counter() - started))
            wait_until(lambda: tab.worker.wait_idle(0.01), 120)
        browser.close()
    server.stop()
    return {f"σp typed at frame {frame} -> per-frame CBM shown, marked (browser)": statistics.median(previewed),
            f"σp typed at frame {frame} -> frame sent (browser)": statistics.median(spent)}


def one_round(frame: int, edits: int) -> dict[str, float]:
    """Every measure once, in this process (its checkout first on ``sys.path``), in milliseconds."""
    import loaders
    from app.scene.drawing import draw
    from app.session.explorer import Explorer
    from app.session.presets import discover
    from app.session.settings import Settings
    from cbm.warmup import warm_up
    from evaluation.sweep import calibrator_for

    warm_up()
    explorer = Explorer(loaders.open("argoverse2"))
    settings = dataclasses.replace(discover()[0]["drift-heavy"].apply(Settings()), frame=frame)
    explorer.compute(settings)
    outcome_ms, drawing_ms = [], []
    for k in range(edits):
        edited = settings.with_scenario(sigma_p=round(settings.scenario.sigma_p + 0.01 * (k + 1), 2))
        started = time.perf_counter()
        outcome = explorer.compute(edited)
        outcome_ms.append(1000 * (time.perf_counter() - started))
        draw(outcome, explorer.map_segments, explorer.sequence[outcome.frame_index])
        drawing_ms.append(1000 * (time.perf_counter() - started))
    started = time.perf_counter()
    explorer.compute(dataclasses.replace(edited, frame=frame + 1))
    step_ms = 1000 * (time.perf_counter() - started)
    trials = [explorer.trial_inputs(edited, j) for j in range(frame + 1)]
    built = [(inputs, inputs.build(edited.scenario, edited.scenario.seed)) for inputs in trials]
    calibrator = calibrator_for(edited.method, edited.params, edited.tracking)
    started = time.perf_counter()
    for j, (inputs, trial) in enumerate(built):
        calibrator.step(trial.ego_boxes, trial.cav_boxes, trial.init, float(explorer.sequence.timestamps[j]),
                        agent=inputs.trial.get("cav_id"))
    floor_ms = 1000 * (time.perf_counter() - started)
    _check_checkout()
    return {f"scenario edit at frame {frame}: outcome": statistics.median(outcome_ms),
            f"scenario edit at frame {frame}: outcome + drawing": statistics.median(drawing_ms),
            f"step to frame {frame + 1}": step_ms,
            f"calibrator steps alone, frames 0-{frame} (floor)": floor_ms}


def _check_checkout() -> None:
    """Stop when a package came from another checkout than the round's."""
    mixed = [name for name, module in list(sys.modules.items())
             if name.split(".")[0] in PACKAGES and getattr(module, "__file__", None)
             and Path.cwd() not in Path(module.__file__).resolve().parents]
    if mixed:
        raise SystemExit(f"bench_over_time: {mixed[0]} was imported from another checkout than {Path.cwd()}")


def run_round(root: Path, args: argparse.Namespace) -> dict[str, float]:
    """One round measured in a process whose packages are ``root``'s."""
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(root), str(root / "tests")]))
    command = [sys.executable, str(HERE), "--one", "--frame", str(args.frame), "--edits", str(args.edits),
               *(["--browser"] if args.browser else [])]
    out = subprocess.run(command, cwd=root, env=env, capture_output=True, text=True)
    if out.returncode != 0:
        last = (out.stderr.strip().splitlines() or [f"exit status {out.returncode}"])[-1]
        raise SystemExit(f"bench_over_time: the round in {root} failed: {last}")
    return json.loads(out.stdout.strip().splitlines()[-1])


def table(roots: list[Path], rounds: list[list[dict[str, float]]]) -> str:
    """Medians over the rounds (ms) per measure and checkout, and the first checkout's / the last's."""
    lines = [f"| measure | {' | '.join(f'{root.name} ms' for root in roots)} | ratio |",
             "|---|" + "---:|" * (len(roots) + 1)]
    for measure in rounds[0][0]:
        medians = [statistics.median(r[measure] for r in per_root) for per_root in rounds]
        lines.append(f"| {measure} | {' | '.join(f'{m:.0f}' for m in medians)} | {medians[0] / medians[-1]:.2f} |")
    return "\n".join(lines)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--roots", nargs="+", type=Path, default=[HERE.parents[1]],
                        help="checkouts to compare (the first is 'ours', the ratio is ours / the last)")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--edits", type=int, default=5)
    parser.add_argument("--frame", type=int, default=150)
    parser.add_argument("--browser", action="store_true", help="also type the edits in a browser tab")
    parser.add_argument("--one", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.one:
        if sys.path[0] == str(HERE.parent):
            del sys.path[0]
        measured = one_round(args.frame, args.edits)
        if args.browser:
            measured.update(typed_edits(args.frame, args.edits))
        print(json.dumps(measured))
        return 0
    roots = [root.resolve() for root in args.roots]
    for root in roots:
        if not (root / "cbm" / "pipeline.py").is_file():
            parser.error(f"--roots: {root} is not a checkout of this project (no cbm/pipeline.py)")
    rounds: list[list[dict[str, float]]] = [[] for _ in roots]
    for _ in range(args.rounds):
        for k, root in enumerate(roots):
            rounds[k].append(run_round(root, args))
    print(table(roots, rounds))
    return 0


if __name__ == "__main__":
    sys.exit(main())
