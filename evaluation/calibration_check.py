"""Check a dataset's own calibration against its own labels (``evaluate.py --check-calibration``).

A cooperative release ships, per frame, each agent's labels in its own sensor frame and the
transform between the agents (DAIR-V2X-C: ``virtuallidar_to_world``, ``novatel_to_world`` ... or
``lidar_i2v``; the OPV2V family: each CAV's ``lidar_pose``). Nothing independent says the transform
is right. But the labels are: the same object labelled by both agents puts a constraint on it. Per
frame and CAV this module

1. takes each agent's labels in its own frame (``Frame.agent_view`` mapped back with the dataset's
   pose of that agent: exactly the boxes of the label files),
2. estimates the CAV -> ego transform from them twice, with no noise added: the **oracle** fits the
   centres of the objects both label under one track id (CBM's robust SE(2) fit, eq. 15), and
   **CBM** matches the two label sets by context alone, starting from the dataset's transform,
3. compares each estimate with the dataset's transform ``T_dataset = ego_pose⁻¹ ∘ cav_pose``: the
   disagreement is the RTE (metres) and RRE (degrees) between them,
4. flags the frame when the disagreement exceeds the thresholds (default 1 m / 1°), judged on the
   oracle when at least :data:`MIN_PAIRS` objects share an id, else on CBM when it matched at least
   as many; with fewer the frame is reported but not judged.

A flagged frame means the labels of the two agents do not line up under the shipped transform: the
transform, or one agent's labels, or the association of ids, is off by that much in that frame. It
does not prove the transform is the wrong one (labels can be shifted too, and DAIR-V2X's ids are
themselves derived by the loader within 2 m under the transform being checked), nor does an
unflagged frame prove it right (a constant shift of both label sets is invisible).
"""
from __future__ import annotations

import csv
from dataclasses import asdict, dataclass, fields
from pathlib import Path

import numpy as np

from cbm import CBMParams, match, robust_fit, se2
from loaders import Frame, Sequence
from loaders.errors import unreadable

from .agents import agent_ids, choose_ego
from .metrics import rre, rte

MIN_PAIRS = 3
"""Objects both agents must share before an estimate judges a frame."""
FIT_FLOOR = 0.05
"""Metres: the label noise the robust fit assumes at least (labels are not detections)."""
CHECK_FILES = ("calibration_check.csv", "calibration_check.png", "calibration_flagged.md")


@dataclass(frozen=True)
class Thresholds:
    metres: float = 1.0
    degrees: float = 1.0


DEFAULT_THRESHOLDS = Thresholds()


@dataclass(frozen=True)
class FrameCheck:
    """One frame and CAV: the dataset's transform against the two estimates."""

    frame: int
    frame_id: str
    ego: str
    cav: str
    shared: int
    """Objects both agents label under one track id (the oracle's pairs)."""
    oracle_m: float
    oracle_deg: float
    cbm_pairs: int
    cbm_m: float
    cbm_deg: float
    judged_by: str
    """``oracle``, ``cbm`` or ``none`` (too few shared objects to judge)."""
    flagged: bool


def check_frame(frame: Frame, cav: str, ego: str, thresholds: Thresholds) -> FrameCheck:
    """The check of one frame for the agent pair ``ego``, ``cav`` (both with ``Frame.agent_view``)."""
    ego_ids, ego_boxes = own_labels(frame, ego)
    cav_ids, cav_boxes = own_labels(frame, cav)
    dataset = se2.inverse(frame.agent_pose(ego)) @ frame.agent_pose(cav)
    oracle, shared = oracle_transform(ego_ids, ego_boxes, cav_ids, cav_boxes)
    result = match(ego_boxes, cav_boxes, init=dataset, params=CBMParams()) if len(ego_boxes) and len(cav_boxes) \
        else None
    cbm_pairs = 0 if result is None else len(result.pairs)
    oracle_m, oracle_deg = disagreement(oracle, dataset)
    cbm_m, cbm_deg = disagreement(None if result is None else result.transform, dataset)
    judged_by = "oracle" if shared >= MIN_PAIRS else "cbm" if cbm_pairs >= MIN_PAIRS else "none"
    worst = {"oracle": (oracle_m, oracle_deg), "cbm": (cbm_m, cbm_deg), "none": (0.0, 0.0)}[judged_by]
    flagged = worst[0] > thresholds.metres or worst[1] > thresholds.degrees
    return FrameCheck(frame.index, str(frame.frame_id), ego, cav, shared, oracle_m, oracle_deg, cbm_pairs,
                      cbm_m, cbm_deg, judged_by, bool(flagged))


def own_labels(frame: Frame, agent: str) -> tuple[np.ndarray, np.ndarray]:
    """The agent's labels (track ids, boxes) in its own frame: its world view mapped back with the
    dataset's pose of it."""
    view = frame.agent_view(agent)
    if view is None:
        raise ValueError(f"{frame.sequence.name} frame {frame.index}: agent {agent!r} has no labels of its own")
    ids, world = view
    return ids, se2.apply_boxes(se2.inverse(frame.agent_pose(agent)), world)


def oracle_transform(ego_ids: np.ndarray, ego_boxes: np.ndarray, cav_ids: np.ndarray,
                     cav_boxes: np.ndarray) -> tuple[np.ndarray | None, int]:
    """The CAV -> ego transform fitted to the objects both label under one id (None below 2)."""
    shared, ego_at, cav_at = np.intersect1d(ego_ids, cav_ids, return_indices=True)
    if len(shared) < 2:
        return None, len(shared)
    fit = robust_fit(cav_boxes[cav_at, :2], ego_boxes[ego_at, :2], FIT_FLOOR)
    return fit.transform, len(shared)


def disagreement(estimate: np.ndarray | None, dataset: np.ndarray) -> tuple[float, float]:
    """RTE (m) and RRE (deg) between an estimate and the dataset's transform; NaN without an estimate."""
    if estimate is None:
        return float("nan"), float("nan")
    return float(rte(estimate, dataset)), float(rre(estimate, dataset))


def check_sequence(sequence: Sequence, frames: list[int],
                   thresholds: Thresholds = DEFAULT_THRESHOLDS) -> list[FrameCheck]:
    """Every frame of ``frames`` and every agent with labels of its own besides the frame's ego."""
    if not sequence.agent_views:
        raise ValueError(f"{sequence.name}: the dataset keeps no per-agent labels (DAIR-V2X-C and the OPV2V "
                         "family do), so there is no calibration of its own to check")
    rows = []
    for index in frames:
        frame = sequence[index]
        ego = choose_ego(frame)
        if ego is None or frame.agent_view(ego) is None:
            continue
        for cav in agent_ids(frame):
            if cav != ego and frame.agent_view(cav) is not None:
                rows.append(check_frame(frame, str(cav), ego, thresholds))
    return rows


def write_table(rows: list[FrameCheck], path: Path) -> None:
    names = [f.name for f in fields(FrameCheck)]
    with path.open("w", newline="") as file:
        writer = csv.DictWriter(file, fieldnames=names)
        writer.writeheader()
        for row in rows:
            writer.writerow({k: (f"{v:.4f}" if isinstance(v, float) else v) for k, v in asdict(row).items()})


def flagged_markdown(rows: list[FrameCheck], thresholds: Thresholds) -> str:
    """The flagged frames as a markdown table (what the CLI prints and writes)."""
    flagged = [row for row in rows if row.flagged]
    judged = sum(row.judged_by != "none" for row in rows)
    checked = f"{judged} frame{'s' * (judged != 1)} checked"
    unchecked = f"{len(rows) - judged} had fewer than {MIN_PAIRS} shared objects to check"
    limits = f"more than {thresholds.metres:g} m / {thresholds.degrees:g} deg"
    if flagged:
        verb = "disagrees" if len(flagged) == 1 else "disagree"
        head = f"{len(flagged)} of {checked} {verb} with the dataset's transform by {limits} ({unchecked})\n"
    else:
        head = f"No frame disagrees with the dataset's transform by {limits} ({checked}; {unchecked})\n"
    if not flagged:
        return head
    lines = ["", "| frame | frame id | ego | CAV | judged by | shared | oracle m | oracle deg | CBM m | CBM deg |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    lines += [f"| {r.frame} | {r.frame_id} | {r.ego} | {r.cav} | {r.judged_by} | {r.shared} | {r.oracle_m:.2f} | "
              f"{r.oracle_deg:.2f} | {r.cbm_m:.2f} | {r.cbm_deg:.2f} |" for r in flagged]
    return head + "\n".join(lines) + "\n"


def plot(rows: list[FrameCheck], thresholds: Thresholds):
    """Disagreement per frame (translation above, rotation below), thresholds dashed, flagged in red."""
    from .plots import plt

    figure, (top, bottom) = plt.subplots(2, 1, figsize=(9, 5.5), sharex=True)
    frames = np.array([row.frame for row in rows])
    flagged = np.array([row.flagged for row in rows], dtype=bool)
    for axis, keys, limit, unit in ((top, ("oracle_m", "cbm_m"), thresholds.metres, "m"),
                                    (bottom, ("oracle_deg", "cbm_deg"), thresholds.degrees, "deg")):
        for key, marker in zip(keys, ("o", "x")):
            values = np.array([getattr(row, key) for row in rows], float)
            axis.plot(frames, values, marker, ms=4, label=key.split("_")[0])
            if flagged.any():
                axis.plot(frames[flagged], values[flagged], marker, ms=7, color="#d55e00")
        axis.axhline(limit, ls="--", color="grey")
        axis.set_ylabel(f"disagreement ({unit})")
        axis.legend(loc="upper right")
    bottom.set_xlabel("frame")
    top.set_title("Dataset transform vs. its own labels (flagged in red)")
    figure.tight_layout()
    return figure


def parse_thresholds(text: str) -> Thresholds:
    """``"M,DEG"`` (e.g. ``"1,1"``) as :class:`Thresholds`; ``ValueError`` naming the flag otherwise."""
    parts = text.split(",")
    try:
        metres, degrees = (float(part) for part in parts)
    except ValueError:
        raise ValueError(f"--check-calibration: expected METRES,DEGREES such as 1,1, got {text!r}") from None
    if not (metres > 0 and degrees > 0 and np.isfinite([metres, degrees]).all()):
        raise ValueError(f"--check-calibration: thresholds must be finite and positive, got {text!r}")
    return Thresholds(metres, degrees)


def check_out_folder(out: Path) -> None:
    """``ValueError`` unless ``out`` is new, empty or holds only a previous check's files, in a place
    this process can write; a folder on the way that cannot be opened is named."""
    from .outputs import check_writable

    out = out.resolve()
    try:
        if out.exists() and not out.is_dir():
            raise ValueError(f"--out: {out} exists and is not a folder")
        foreign = sorted(p.name for p in out.iterdir() if p.name not in CHECK_FILES) if out.is_dir() else []
        if foreign:
            raise ValueError(f"--out: {out} holds other files ({', '.join(foreign[:3])}); name a new or empty folder")
        check_writable(out, out)
    except OSError as error:
        raise ValueError(f"--out: {unreadable(error, out)}") from None


def write_check(rows: list[FrameCheck], thresholds: Thresholds, out: Path) -> str:
    """Write the table, the plot and the flagged frames into ``out``, all three or none
    (``evaluation.outputs.write_together``); return the flagged frames' markdown."""
    from .outputs import write_together
    from .plots import plt

    text = flagged_markdown(rows, thresholds)
    figure = plot(rows, thresholds)
    try:
        write_together(out, {"calibration_check.csv": lambda tmp: write_table(rows, tmp),
                             "calibration_flagged.md": lambda tmp: tmp.write_text(text),
                             "calibration_check.png": lambda tmp: figure.savefig(tmp, dpi=110, format="png")})
    finally:
        plt.close(figure)
    return text
