"""Stored results of ``cbm.match`` on fixed seeds, so that a faster implementation can be checked
to give the same pairs and transforms (``test_match_reference.py``).

    python tests/cbm/match_reference.py    # rewrite data/match_reference.npz (only on purpose)

The cases cover synthetic intersections of 20 to 300 objects under mild and hard SIND noise, a dense
layout (a car park: ``support.scenes.dense_scene``) of 60 and 150 objects under both, the shipped
Argoverse 2 scene under the range protocol, and parameter variants that switch every
branch of the matcher (heading modes, both consensus rules and none, the estimators, the
re-association, wide and narrow thresholds).
"""
from __future__ import annotations

import sys
from collections.abc import Iterator
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
DATA = Path(__file__).resolve().parent / "data" / "match_reference.npz"

VARIANTS = {
    "default": {},
    "released-code": dict(heading="fold", estimator="least_squares", refine=False),
    "paper-rule": dict(consensus_rule="paper", sigma3=3.0),
    "no-consensus": dict(consensus=False),
    "wide": dict(sigma1=25.0, sigma2=5.0, sigma3=2.0),
    "narrow": dict(sigma1=4.0, sigma2=1.0, sigma3=0.5, distance_limit=8.0),
}
MILD = dict(protocol="sind", eta=0.5, sigma_p=0.1, sigma_theta=1.0)
HARD = dict(protocol="sind", eta=0.5, sigma_p=0.3, sigma_theta=3.0)


def cases() -> Iterator[tuple[str, np.ndarray, np.ndarray, np.ndarray, str]]:
    """(name, ego boxes, CAV boxes, init, variant) of every stored case."""
    import loaders
    from evaluation.scenario import ScenarioParams, make_trial
    from evaluation.trials import build_trial

    for size, frames in ((20, 3), (60, 3), (150, 2), (300, 1)):
        scene = loaders.synthetic.generate(n_objects=int(round(2 * size / 1.5)), n_frames=frames, seed=size)
        for k in range(frames):
            boxes, ids = scene[k].boxes(), scene[k].track_ids
            for noise_name, noise in (("mild", MILD), ("hard", HARD)):
                trial = make_trial(boxes, ids, ScenarioParams(**noise, seed=k))
                for variant in VARIANTS:
                    if size == 300 and variant != "default":
                        continue
                    name = f"synthetic{size}-f{k}-{noise_name}-{variant}"
                    yield name, trial.ego_boxes, trial.cav_boxes, trial.init, variant
    yield from dense_cases()
    scene = loaders.open("argoverse2")
    for k in range(0, len(scene), 20):
        trial = build_trial(scene[k], ScenarioParams(protocol="range", sigma_p=0.3, sigma_theta=3.0), seed=k)
        for variant in VARIANTS:
            yield f"argoverse2-f{k}-range-{variant}", trial.ego_boxes, trial.cav_boxes, trial.init, variant


def dense_cases() -> Iterator[tuple[str, np.ndarray, np.ndarray, np.ndarray, str]]:
    """The dense layout's cases: two scenes, both noises, the defaults and the released code's variant."""
    from evaluation.scenario import ScenarioParams, make_trial
    from support.scenes import dense_scene

    for size in (60, 150):
        n_world = int(round(2 * size / 1.5))
        boxes = dense_scene(n_world, np.random.default_rng(size))
        for noise_name, noise in (("mild", MILD), ("hard", HARD)):
            trial = make_trial(boxes, np.arange(n_world), ScenarioParams(**noise, seed=size))
            for variant in ("default", "released-code"):
                yield f"dense{size}-{noise_name}-{variant}", trial.ego_boxes, trial.cav_boxes, trial.init, variant


def outcome(ego: np.ndarray, cav: np.ndarray, init: np.ndarray, variant: str) -> dict[str, np.ndarray]:
    """What is stored of one match: pairs, transform, CBM's own pairs and the selection's counts."""
    from cbm import CBMParams, match

    result = match(ego, cav, init, CBMParams(**VARIANTS[variant]))
    anchor = (-1, -1) if result.anchor is None else result.anchor
    counts = (result.candidate_count, result.consensus_count, result.runner_up_count, *anchor)
    return dict(pairs=np.asarray(result.pairs, dtype=np.int64), transform=result.transform,
                context_pairs=np.asarray(result.context_pairs, dtype=np.int64), counts=np.array(counts, dtype=np.int64))


def main() -> None:
    stored = {}
    for name, ego, cav, init, variant in cases():
        for key, value in outcome(ego, cav, init, variant).items():
            stored[f"{name}/{key}"] = value
    np.savez_compressed(DATA, **stored)
    print(f"{len(stored) // 4} cases written to {DATA.relative_to(ROOT)}")


if __name__ == "__main__":
    sys.path[:0] = [str(ROOT), str(ROOT / "tests")]
    main()
