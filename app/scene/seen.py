"""What each agent saw, drawn and said (``app.session.seen`` computes it): the ego's and the CAV's
sight as a translucent fill in each one's colour with its edge (the shadows behind the boxes are
the holes in it), and for a late message a line from where the CAV saw each moving object to where
it is now, the one that moved most labelled, and the message's age in the metrics and the caption.

The ego's sight is drawn in the ego's frame, the CAV's in its own frame placed as its boxes are (at
``init`` before calibration, at the estimate after), so the CAV's boxes lie in its sight as drawn;
the motion lines are facts of the world, drawn at the truth like the ghosts."""
from __future__ import annotations

import numpy as np

from cbm import se2

from ..session.explorer import Outcome
from ..session.names import role_of
from ..session.seen import Late
from . import planes
from .geometry import segments
from .layouts import Panel
from .pairs import Labels

ROLES = ("ego", "cav")
SIGHT_OPACITY = 0.12
"""The fills' opacity: the map and the boxes show through, two overlapping sights look darker."""
Fan = tuple[np.ndarray, np.ndarray, np.ndarray]
"""(vertices (V, 3) float32, faces (F, 3) uint32, edge segments (E, 2, 3) float32) of one agent's sight."""


def sight_node(role: str, kind: str = "sight") -> str:
    """The scene node of an agent's sight fill (``ego_sight``) or edge (``cav_sight_edge``)."""
    return f"{role}_{kind}"


def sight_fans(outcome: Outcome, panels: list[Panel]) -> dict[str, Fan]:
    """Each agent's sight in every copy of the scene, as a triangle fan around the agent and the
    outline's edge (empty arrays when the view does not ask for it or the protocol decides no sight)."""
    found = outcome.sights() if outcome.settings.view.sight else None
    fans = {role: [] for role in ROLES}
    for panel in panels if found else []:
        shift = se2.make(panel.offset[0], panel.offset[1], 0.0)
        placed = {"ego": shift, "cav": shift @ outcome.placements[panel.placement]}
        for level, role in enumerate(ROLES, 1):
            fans[role].append(fan(se2.apply_points(placed[role], found[role].outline),
                                  se2.translation_of(placed[role]), level * planes.SIGHT))
    return {role: _joined(parts) for role, parts in fans.items()}


def fan(outline: np.ndarray, centre: np.ndarray, z: float) -> Fan:
    """The triangle fan from ``centre`` over the closed ``outline`` (R, 2), and the outline's edge, at height ``z``."""
    rays = len(outline)
    vertices = np.zeros((rays + 1, 3), np.float32)
    vertices[0, :2], vertices[1:, :2], vertices[:, 2] = centre, outline, z
    ring = np.arange(rays, dtype=np.uint32)
    faces = np.stack([np.zeros(rays, np.uint32), 1 + ring, 1 + (ring + 1) % rays], axis=1)
    return vertices, faces, segments(outline, np.roll(outline, -1, axis=0), z)


def _joined(parts: list[Fan]) -> Fan:
    """Several fans as one mesh and one set of segments."""
    if not parts:
        return np.zeros((0, 3), np.float32), np.zeros((0, 3), np.uint32), np.zeros((0, 2, 3), np.float32)
    offsets = np.cumsum([0] + [len(v) for v, _, _ in parts[:-1]])
    return (np.concatenate([v for v, _, _ in parts]),
            np.concatenate([f + np.uint32(o) for (_, f, _), o in zip(parts, offsets)]),
            np.concatenate([s for _, _, s in parts]))


def motion(outcome: Outcome, panels: list[Panel]) -> tuple[np.ndarray, Labels]:
    """For a late message: a segment from where the CAV saw each moving object to where it is now, in
    every copy of the scene, and a label on the object that moved most ("moved 1.4 m while the message
    travelled"); nothing when the message is not late or nothing moved."""
    late = outcome.late()
    if late is None or not late.moving.any():
        return np.zeros((0, 2, 3), np.float32), {}
    most = int(np.argmax(late.moved))
    text = f"moved {late.moved[most]:.1f} m while the message travelled"
    lines, labels = [], {}
    for panel in panels:
        lines.append(segments(late.captured[late.moving] + panel.offset, late.now[late.moving] + panel.offset,
                              planes.MARKS))
        labels[f"moved_{panel.placement}"] = (text, (*(late.now[most] + panel.offset), planes.LABELS))
    return np.concatenate(lines), labels


def gap_words(outcome: Outcome) -> str | None:
    """The dataset's own gap between the two agents' captures in words ("CAV captured 40 ms before the
    ego"); None where the dataset keeps one time per frame or the two are the same."""
    gap = outcome.capture_gap_s
    if gap is None or round(1000 * gap) == 0:
        return None
    return f"{role_of('CAV', outcome.cav_id)} captured {abs(1000 * gap):.0f} ms {'before' if gap > 0 else 'after'} " \
           "the ego"


def late_rows(outcome: Outcome) -> list[str]:
    """The metrics table's rows of a late message: the agents' capture times, the message's age and
    how far the CAV's objects moved meanwhile; the rows of the agents' sight under line of sight."""
    rows = [f"| {name} | {words} |" for name, words in sight_words(outcome)]
    gap = gap_words(outcome)
    if gap:
        later = "; counted as no delay" if outcome.capture_gap_s < 0 else ""
        rows.append(f"| capture times | {gap} (the dataset's timestamps{later}) |")
    late = outcome.late()
    if late is not None and (late.age_s > 0 or outcome.settings.scenario.delayed):
        rows.append(f"| message age | {1000 * late.age_s:.0f} ms{_cut_short(outcome, late)} |")
        rows.append(f"| moved while the message travelled | {moved_words(late)} |")
    return rows


def _cut_short(outcome: Outcome, late: Late) -> str:
    """Why the message is younger than the scenario's delay allows: the sequence has no frame that old."""
    scenario = outcome.settings.scenario
    if 1000 * late.age_s + 0.5 >= scenario.delay_ms - scenario.jitter_ms:
        return ""
    return " (as old as the frames before this one allow)"


def moved_words(late: Late) -> str:
    """How far the CAV's objects moved while its message travelled, in words."""
    if not late.moving.any():
        return f"none of the {len(late.ids)} objects the CAV sees moved"
    return f"up to {late.moved.max():.1f} m ({late.moving.sum()} of the {len(late.ids)} objects the CAV sees moved)"


def sight_words(outcome: Outcome) -> list[tuple[str, str]]:
    """What decides each agent's sight under line of sight, when the dataset says what an agent saw
    (its sight is then the range alone); nothing otherwise."""
    scenario = outcome.settings.scenario
    if not (scenario.sight and scenario.protocol == "range" and outcome.inputs is not None):
        return []
    said = outcome.inputs.trial.get("visibility") or {}
    return [("line of sight", " · ".join(f"{_role(outcome, role)}: {_decides(role, said)}" for role in ROLES))]


def _decides(role: str, said: dict) -> str:
    return "what the dataset says it saw, within range" if role in said else "the boxes' shadows"


def _role(outcome: Outcome, role: str) -> str:
    return "ego" if role == "ego" else role_of("CAV", outcome.cav_id)


def caption_line(outcome: Outcome) -> list[str]:
    """The caption's line of a late message (none when it is not late)."""
    late = outcome.late()
    if late is None or not (late.age_s > 0 or gap_words(outcome)):
        return []
    parts = [gap_words(outcome), f"message {1000 * late.age_s:.0f} ms old" if late.age_s > 0 else None,
             f"moved up to {late.moved.max():.1f} m" if late.moving.any() else None]
    return [" · ".join(part for part in parts if part)]

