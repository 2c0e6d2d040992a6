"""Stored outputs of local matching's join on fixed seeds, street and dense layouts, so that a
faster join can be checked to count and list exactly the same (``test_join_reference.py``).

    python tests/cbm/join_reference.py    # rewrite data/join_reference.npz (only on purpose)

Stored per case: card(L_ij) of every anchor and the voting quadruples within sigma3 (as sorted keys
``member * Ne Nc + anchor``), each as its SHA-256 digest beside its size and sum (so that a failure
says how far off it is), which keeps the file small. The cases are the
synthetic intersection (street layout) and a car park (dense layout) under hard SIND noise, both
heading modes, default and wide thresholds.
"""
from __future__ import annotations

import hashlib
import sys
from collections.abc import Iterator
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
DATA = Path(__file__).resolve().parent / "data" / "join_reference.npz"
NOISE = dict(protocol="sind", eta=0.5, sigma_p=0.3, sigma_theta=3.0, flip_prob=0.5)
VARIANTS = {"align": dict(heading="align"), "fold": dict(heading="fold"),
            "wide": dict(heading="align", sigma1=25.0, sigma2=5.0, sigma3=2.0)}


def layouts(size: int) -> Iterator[tuple[str, np.ndarray, np.ndarray]]:
    """(layout name, world boxes, track ids) of a street and a dense scene giving about ``size``
    objects per agent under ``NOISE``."""
    import loaders
    from support.scenes import dense_scene

    n_world = int(round(2 * size / 1.5))
    frame = loaders.synthetic.generate(n_objects=n_world, n_frames=1, seed=size)[0]
    yield "street", frame.boxes(), frame.track_ids
    yield "dense", dense_scene(n_world, np.random.default_rng(size)), np.arange(n_world)


def cases() -> Iterator[tuple[str, np.ndarray, np.ndarray, np.ndarray, dict]]:
    """(name, ego boxes, CAV boxes, init, CBMParams keywords) of every stored case."""
    from evaluation.scenario import ScenarioParams, make_trial

    for size in (60, 200):
        for layout, boxes, ids in layouts(size):
            for seed in (0, 1):
                trial = make_trial(boxes, ids, ScenarioParams(**NOISE, seed=seed))
                for variant, keywords in VARIANTS.items():
                    yield (f"{layout}{size}-s{seed}-{variant}", trial.ego_boxes, trial.cav_boxes, trial.init,
                           keywords)


def outcome(ego: np.ndarray, cav: np.ndarray, init: np.ndarray, keywords: dict) -> dict[str, np.ndarray]:
    """What is stored of one join: digest, size and sum of the counts and of the sorted voting keys."""
    from cbm import CBMParams
    from cbm.pipeline import checked_inputs
    from cbm.sets import build_sets

    ego, cav, init, params = checked_inputs(ego, cav, init, CBMParams(**keywords))
    sets = build_sets(ego, cav, init, params)
    count = sets.candidates.count.astype(np.int64)
    n_pairs = len(count)
    votes = sets.voted_by
    keys = np.sort(np.repeat(np.arange(n_pairs, dtype=np.int64), np.diff(votes.start)) * n_pairs
                   + votes.member.astype(np.int64))
    return dict(counts=summary(count), votes=summary(keys))


def summary(values: np.ndarray) -> np.ndarray:
    """(size, sum, the SHA-256 digest of the int64 bytes as four int64 words) of ``values``."""
    digest = np.frombuffer(hashlib.sha256(np.ascontiguousarray(values, np.int64).tobytes()).digest(), np.int64)
    return np.concatenate([[len(values), int(values.sum())], digest])


def main() -> None:
    stored = {}
    for name, ego, cav, init, keywords in cases():
        for key, value in outcome(ego, cav, init, keywords).items():
            stored[f"{name}/{key}"] = value
    np.savez_compressed(DATA, **stored)
    print(f"{len(stored) // 2} cases written to {DATA.relative_to(ROOT)}")


if __name__ == "__main__":
    sys.path[:0] = [str(ROOT), str(ROOT / "tests")]
    main()
