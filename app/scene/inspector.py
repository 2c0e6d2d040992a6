"""The context inspector: one object's context -- the vectors to its neighbours in its own frame
(eq. 5-6) -- for the ego and for its CAV counterpart, side by side next to the scene; for the anchor
pair they form, the sigma1 angular band and the sigma2 region (an L1 ball: a diamond) around each
context vector (eq. 7), the candidate set ``L_ij`` (eq. 8), what consensus removed and the votes
each pair got (eq. 9-11), from ``cbm.inspect``. The panels go left of the scene (+y), away from the
control panel on the page's right; each neighbour is labelled with its object id, and a legend
names the colours.

The panels are drawn in the ego frame's orientation: the object's own forward axis points like the
ego's (x), so a context vector sits where CBM compares it.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cbm import CBMParams
from cbm.inspect import AnchorDetail, Inspection
from evaluation.diagnosis import pair_name, short_id

from ..session.explorer import Outcome
from . import geometry
from .colours import CAV_BOXES, EGO_BOXES, RIGHT, WRONG
from .drawing import Drawing, Lines, no_lines

ARC_SEGMENTS = 6
"""Segments of the arc closing each sigma1 band."""
PANEL_GAP = 15.0
"""Metres between the scene and the first panel, and between the panels."""
HEIGHT = 0.1
BAND = (120, 120, 120)
REGION = (150, 60, 200)
MAX_ROWS = 30
"""Rows of the candidate table shown (the rest is counted)."""
MAX_TIP_LABELS = 12
"""Neighbours labelled with their ids per panel, nearest first."""
TIP_SPACING = 4.0
"""Metres between labelled tips (a tip closer to one already labelled is left unlabelled)."""
THICKNESS = {"vectors": 3.0, "bands": 1.5, "regions": 2.5, "kept": 6.0, "removed": 6.0}
"""Line widths in screen pixels."""
LEGEND = "legend: grey = σ1 band · purple = σ2 region · green = kept · red = removed by consensus"


@dataclass(frozen=True)
class ContextPicture:
    """What the inspector draws (line sets by name, labels) and says (markdown)."""

    ego: int
    cav: int | None
    lines: dict[str, Lines]
    labels: dict[str, tuple[str, tuple[float, float, float]]]
    markdown: str
    centre: tuple[float, float] = (0.0, 0.0)
    """Middle of the panels drawn (where a camera looks to see them)."""
    span: float = 1.0
    """Metres from the first panel's far edge to the last's."""

    def drawing(self) -> Drawing:
        """As a ``Drawing`` for a ``SceneView``."""
        return Drawing(meshes={}, lines=self.lines, labels=self.labels, metrics_markdown=self.markdown)


def counterpart(outcome: Outcome, group: str, index: int) -> tuple[int | None, int | None]:
    """(ego index, CAV index) of a clicked object and its counterpart on the other side: the pair
    the method matched it to, else its true pair, else None."""
    column = 0 if group == "ego" else 1
    for pairs in (outcome.result.pairs, outcome.trial.gt_pairs):
        pairs = np.asarray(pairs).reshape(-1, 2)
        hit = pairs[pairs[:, column] == index]
        if len(hit):
            return int(hit[0, 0]), int(hit[0, 1])
    return (index, None) if group == "ego" else (None, index)


def band_segments(origin: np.ndarray, vectors: np.ndarray, sigma1_deg: float, reach: float) -> np.ndarray:
    """(n * (2 + ARC_SEGMENTS), 2, 3): for each vector, the two rays at +-sigma1 from ``origin`` out
    to its length plus ``reach``, and the arc joining their ends."""
    if len(vectors) == 0:
        return no_lines()
    angle = np.arctan2(vectors[:, 1], vectors[:, 0])
    radius = np.linalg.norm(vectors, axis=1) + reach
    sweep = angle[:, None] + np.radians(sigma1_deg) * np.linspace(-1.0, 1.0, ARC_SEGMENTS + 1)[None, :]
    arc = origin + radius[:, None, None] * np.stack([np.cos(sweep), np.sin(sweep)], axis=-1)
    starts = np.concatenate([np.broadcast_to(origin, (2 * len(vectors), 2)), arc[:, :-1].reshape(-1, 2)])
    ends = np.concatenate([arc[:, [0, -1]].reshape(-1, 2), arc[:, 1:].reshape(-1, 2)])
    return geometry.segments(starts, ends, HEIGHT)


def region_segments(origin: np.ndarray, vectors: np.ndarray, sigma2: float) -> np.ndarray:
    """(4n, 2, 3): the L1 ball of radius ``sigma2`` (a diamond) around each vector's tip."""
    if len(vectors) == 0:
        return no_lines()
    corners = np.array([[sigma2, 0.0], [0.0, sigma2], [-sigma2, 0.0], [0.0, -sigma2]])
    tips = origin + vectors
    points = tips[:, None, :] + corners[None]
    return geometry.segments(points.reshape(-1, 2), np.roll(points, -1, axis=1).reshape(-1, 2), HEIGHT)


def vector_segments(origin: np.ndarray, vectors: np.ndarray) -> np.ndarray:
    """(n, 2, 3) segments from ``origin`` to each vector's tip."""
    return geometry.segments(np.broadcast_to(origin, vectors.shape), origin + vectors, HEIGHT)


def inspect(outcome: Outcome, picture: Drawing, ego: int | None, cav: int | None,
            inspection: Inspection | None = None) -> ContextPicture:
    """The inspector's picture and text for the object pair (``ego``, ``cav``); either may be None
    (an object seen by one agent only), then only its own context is shown."""
    inspection = inspection or outcome.inspection()
    params = inspection.sets.params
    trial = outcome.trial
    contexts = {}
    if ego is not None:
        contexts["ego"] = inspection.context("ego", ego)
    if cav is not None:
        contexts["cav"] = inspection.context("cav", cav, against=ego)
    reach = max([float(np.linalg.norm(v, axis=1).max()) for _, v in contexts.values() if len(v)] or [1.0])
    reach += params.sigma2
    drawn = [boxes[:, 1] + np.hypot(boxes[:, 3], boxes[:, 4]) for boxes, _ in picture.objects.values() if len(boxes)]
    edge = float(max(np.concatenate(drawn).max(), 0.0)) if drawn else 0.0
    origins = {"ego": np.array([0.0, edge + PANEL_GAP + reach]),
               "cav": np.array([0.0, edge + 2 * PANEL_GAP + 3 * reach])}
    detail = inspection.anchor(ego, cav) if ego is not None and cav is not None else None
    lines: dict[str, Lines] = dict(empty().lines)
    labels = {}
    for agent, (members, vectors) in contexts.items():
        origin, color = origins[agent], EGO_BOXES if agent == "ego" else CAV_BOXES
        index = ego if agent == "ego" else cav
        ids = trial.ego_ids if agent == "ego" else trial.cav_ids
        lines[f"inspector_{agent}_vectors"] = Lines(vector_segments(origin, vectors), color, THICKNESS["vectors"])
        labels[f"inspector_{agent}"] = (f"{agent.upper()} {short_id(ids[index])}: context in its own frame",
                                        (float(origin[0] + reach + 3.0), float(origin[1]), 1.0))
        labels.update(tip_labels(agent, origin, members, vectors, ids))
        if detail is not None:
            bands = band_segments(origin, vectors, params.sigma1, params.sigma2)
            lines[f"inspector_{agent}_bands"] = Lines(bands, BAND, THICKNESS["bands"])
            lines[f"inspector_{agent}_regions"] = Lines(region_segments(origin, vectors, params.sigma2), REGION,
                                                        THICKNESS["regions"])
            column = 0 if agent == "ego" else 1
            kept = detail.kept_by_consensus
            for name, mask, colour in (("kept", kept, RIGHT), ("removed", ~kept, WRONG)):
                chosen = np.isin(members, detail.candidates[mask, column])
                lines[f"inspector_{agent}_{name}"] = Lines(vector_segments(origin, vectors[chosen]), colour,
                                                           THICKNESS[name])
    shown = [origins[agent] for agent in contexts]
    centre = np.mean(shown, axis=0)
    left = max(float(origin[1]) for origin in shown) + reach
    labels["inspector_legend"] = (LEGEND, (float(-reach - 4.0), left, 1.0))
    return ContextPicture(ego=ego, cav=cav, lines=lines, labels=labels,
                          markdown=_markdown(outcome, ego, cav, detail, params),
                          centre=(float(centre[0]), float(centre[1])),
                          span=2 * reach * len(shown) + PANEL_GAP * (len(shown) - 1))


def tip_labels(agent: str, origin: np.ndarray, members: np.ndarray, vectors: np.ndarray,
               ids: np.ndarray) -> dict[str, tuple[str, tuple[float, float, float]]]:
    """A label with the object id at the tip of up to ``MAX_TIP_LABELS`` context vectors, nearest
    first, each at least ``TIP_SPACING`` from the others."""
    chosen: list[int] = []
    for n in np.argsort(np.linalg.norm(vectors, axis=1), kind="stable"):
        if len(chosen) == MAX_TIP_LABELS:
            break
        if all(np.linalg.norm(vectors[n] - vectors[k]) >= TIP_SPACING for k in chosen):
            chosen.append(int(n))
    return {f"inspector_{agent}_tip{k}": (short_id(ids[int(members[n])]),
                                          (float(origin[0] + vectors[n, 0]), float(origin[1] + vectors[n, 1]), 0.5))
            for k, n in enumerate(chosen)}


def _markdown(outcome: Outcome, ego: int | None, cav: int | None, detail: AnchorDetail | None,
              params: CBMParams) -> str:
    trial = outcome.trial
    if detail is None:
        who = f"ego {short_id(trial.ego_ids[ego])}" if ego is not None else f"CAV {short_id(trial.cav_ids[cav])}"
        return (f"**{who}** is seen by one agent only: its context is drawn (left of the scene), "
                f"but there is no pair to compare.")
    truth = {tuple(p) for p in np.asarray(trial.gt_pairs).reshape(-1, 2).tolist()}
    final = {tuple(p) for p in detail.final.tolist()}
    kind = "a true pair" if (ego, cav) in truth else "not a true pair"
    lines = [f"**Anchor {pair_name(trial, (ego, cav))}**: {kind}.",
             "",
             (f"Grey wedges: σ1 = {params.sigma1:g}° around each context vector; purple diamonds: "
              f"σ2 = {params.sigma2:g} m (L1). Thick green: in L_ij and kept by consensus; thick red: removed by "
              f"consensus."),
             "",
             f"L_ij holds {len(detail.candidates)} pairs; consensus kept {int(detail.kept_by_consensus.sum())}; "
             f"{len(detail.final)} are left after the one-to-one rule"
             + (f" ({detail.mean_distance:.1f} m apart on average, limit {params.distance_limit:g} m"
                f"{': rejected' if detail.rejected else ''})" if len(detail.final) else "") + "."]
    if outcome.result.anchor is not None:
        result = outcome.result
        lines.append(f"The winning anchor is {pair_name(trial, result.anchor)} with {result.consensus_count} pairs.")
    if len(detail.candidates):
        lines += ["", "| ego | CAV | votes | consensus | final | true |", "|---|---|---|---|---|---|"]
        for (i, j), votes, kept in list(zip(detail.candidates.tolist(), detail.votes.tolist(),
                                            detail.kept_by_consensus.tolist()))[:MAX_ROWS]:
            lines.append(f"| {short_id(trial.ego_ids[i])} | {short_id(trial.cav_ids[j])} | {votes} | "
                         f"{'kept' if kept else 'removed'} | "
                         f"{'yes' if (i, j) in final else 'no'} | {'yes' if (i, j) in truth else 'no'} |")
        if len(detail.candidates) > MAX_ROWS:
            lines.append(f"\n… and {len(detail.candidates) - MAX_ROWS} more pairs.")
    return "\n".join(lines)


def empty() -> Drawing:
    """A drawing that hides every inspector node (a ``SceneView`` hides empty line sets and
    labels it is not given)."""
    names = [f"inspector_{agent}_{part}" for agent in ("ego", "cav")
             for part in ("vectors", "bands", "regions", "kept", "removed")]
    return Drawing(meshes={}, lines={name: Lines(no_lines(), BAND) for name in names},
                   labels={}, metrics_markdown="")

