"""The context inspector: one object's context -- the vectors to its neighbours in its own frame
(eq. 6-7) -- for the ego and for its CAV counterpart, side by side next to the scene; for the anchor
pair they form, the sigma1 angular band and the sigma2 region (an L1 ball: a diamond) around each
context vector (eq. 8), the candidate set ``L_ij`` (eq. 9), what consensus removed and the votes
each pair got (eq. 10-12), from ``cbm.Explanation``. The panels go left of the scene (+y), away from the
control panel on the page's right, each on a plate that hides the map beneath; neighbours are
labelled with their object ids where a label does not cover another (as the camera that looks at
the panels shows them), and a legend names every colour.

The panels are drawn in the ego frame's orientation: the object's own forward axis points like the
ego's (x), so a context vector sits where CBM compares it.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from cbm import AnchorDetail, CBMParams, Explanation
from evaluation.diagnosis import pair_name, short_id

from ..session.explorer import Outcome
from . import geometry, layouts
from .captions import LABEL_PX
from .colours import CAV_BOXES, EGO_BOXES, RIGHT, WRONG
from .drawing import Drawing, Lines, Mesh, no_lines
from .linecolours import as_shown
from .words import plural

ARC_SEGMENTS = 6
"""Segments of the arc closing each sigma1 band."""
PANEL_GAP = 15.0
"""Metres between the scene and the first panel, and between the panels."""
HEIGHT = 0.7
"""Metres above the ground of the panels' lines: clear of their plates in the depth buffer of a
camera 200 m up."""
PLATE_HEIGHT = 0.3
PLATES = {False: (250, 250, 250), True: (34, 35, 40)}
"""The panels' plates, by the dark theme: the page's background, so that the map does not show through."""
BAND = (120, 120, 120)
REGION = (150, 60, 200)
MAX_ROWS = 30
"""Rows of the candidate table shown (the rest is counted)."""
MAX_TIP_LABELS = 12
"""Neighbours labelled with their ids per panel, nearest first."""
CHAR_PX, LINE_PX = 0.62 * LABEL_PX + 0.5, 1.45 * LABEL_PX
"""About how wide a label's character and how tall its line are on screen, in CSS pixels."""
THICKNESS = {"vectors": 3.0, "bands": 1.5, "regions": 2.5, "kept": 6.0, "removed": 6.0}
"""Line widths in screen pixels."""
LEGEND = ("legend: blue = the ego object's context vectors · orange = the CAV object's\n"
          "grey = σ1 band · purple = σ2 region · green = kept · red = removed by consensus")


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

    plate: Mesh | None = None
    """The plates under the panels."""

    def drawing(self) -> Drawing:
        """As a ``Drawing`` for a ``SceneView``: the lines in the colours that show as named."""
        lines = {name: dataclasses.replace(line, color=as_shown(line.color)) for name, line in self.lines.items()}
        return Drawing(meshes={"inspector_plates": self.plate or no_plates()}, lines=lines, labels=self.labels,
                       metrics_markdown=self.markdown)


def no_plates() -> Mesh:
    return Mesh(np.zeros((0, 3), np.float32), np.zeros((0, 3), np.uint32), PLATES[False])


def plates(centres: list[np.ndarray], half: float, dark: bool) -> Mesh:
    """A square plate of side ``2 half`` under each panel centre, at ``PLATE_HEIGHT``."""
    corners = np.array([[1.0, 1.0], [-1.0, 1.0], [-1.0, -1.0], [1.0, -1.0]]) * half
    vertices = np.concatenate([np.column_stack([c + corners, np.full(4, PLATE_HEIGHT)]) for c in centres])
    faces = np.concatenate([np.array([[0, 1, 2], [0, 2, 3]]) + 4 * k for k in range(len(centres))])
    return Mesh(vertices.astype(np.float32), faces.astype(np.uint32), PLATES[dark])


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
            explanation: Explanation | None = None) -> ContextPicture:
    """The inspector's picture and text for the object pair (``ego``, ``cav``); either may be None
    (an object seen by one agent only), then only its own context is shown."""
    explanation = explanation or outcome.cbm().explanation
    params = explanation.params
    trial = outcome.trial
    contexts = {}
    if ego is not None:
        contexts["ego"] = explanation.context("ego", ego)
    if cav is not None:
        contexts["cav"] = explanation.context("cav", cav, against=ego)
    reach = max([float(np.linalg.norm(v, axis=1).max()) for _, v in contexts.values() if len(v)] or [1.0])
    reach += params.sigma2
    drawn = [boxes[:, 1] + np.hypot(boxes[:, 3], boxes[:, 4]) for boxes, _ in picture.objects.values() if len(boxes)]
    edge = float(max(np.concatenate(drawn).max(), 0.0)) if drawn else 0.0
    origins = {"ego": np.array([0.0, edge + PANEL_GAP + reach]),
               "cav": np.array([0.0, edge + 2 * PANEL_GAP + 3 * reach])}
    span = 2 * reach * len(contexts) + PANEL_GAP * (len(contexts) - 1)
    metres_per_px = looked_at_scale(span)
    detail = explanation.anchor(ego, cav) if ego is not None and cav is not None else None
    lines: dict[str, Lines] = dict(empty().lines)
    labels = {}
    for agent, (members, vectors) in contexts.items():
        origin, color = origins[agent], EGO_BOXES if agent == "ego" else CAV_BOXES
        index = ego if agent == "ego" else cav
        ids = trial.ego_ids if agent == "ego" else trial.cav_ids
        lines[f"inspector_{agent}_vectors"] = Lines(vector_segments(origin, vectors), color, THICKNESS["vectors"])
        labels[f"inspector_{agent}"] = (f"{agent.upper()} {short_id(ids[index])}: context in its own frame",
                                        (float(origin[0] + reach + 3.0), float(origin[1]), 1.0))
        labels.update(tip_labels(agent, origin, members, vectors, ids, metres_per_px))
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
                          centre=(float(centre[0]), float(centre[1])), span=span,
                          plate=plates(shown, reach + 2.0, outcome.settings.view.dark))


def looked_at_scale(span: float, screen: tuple[float, int, int] = layouts.SCREEN) -> float:
    """Metres per CSS pixel of the camera that looks at panels ``span`` metres across (``look at
    the context panels``: they fill the canvas)."""
    fov, _, height = screen
    return 2.0 * layouts.fitting_height(span, screen) * float(np.tan(fov / 2.0)) / height


def tip_labels(agent: str, origin: np.ndarray, members: np.ndarray, vectors: np.ndarray, ids: np.ndarray,
               metres_per_px: float) -> dict[str, tuple[str, tuple[float, float, float]]]:
    """A label with the object id at the tip of up to ``MAX_TIP_LABELS`` context vectors, nearest
    first, each where it covers no label chosen before (its box on screen, ``metres_per_px``)."""
    texts = [short_id(ids[int(m)]) for m in members]
    chosen: list[int] = []
    for n in np.argsort(np.linalg.norm(vectors, axis=1), kind="stable"):
        if len(chosen) == MAX_TIP_LABELS:
            break
        box = label_box(vectors[n], texts[n], metres_per_px)
        if not any(_overlap(box, label_box(vectors[k], texts[k], metres_per_px)) for k in chosen):
            chosen.append(int(n))
    return {f"inspector_{agent}_tip{k}": (texts[n],
                                          (float(origin[0] + vectors[n, 0]), float(origin[1] + vectors[n, 1]), 0.5))
            for k, n in enumerate(chosen)}


def label_box(at: np.ndarray, text: str, metres_per_px: float) -> tuple[float, float, float, float]:
    """(x low, x high, y low, y high) in metres that a label anchored by its top-left corner at
    ``at`` covers: x points up the screen and y left, so it reaches down (-x) and right (-y)."""
    width, height = len(text) * CHAR_PX * metres_per_px, LINE_PX * metres_per_px
    return float(at[0]) - height, float(at[0]), float(at[1]) - width, float(at[1])


def _overlap(a: tuple[float, ...], b: tuple[float, ...]) -> bool:
    return a[0] < b[1] and b[0] < a[1] and a[2] < b[3] and b[2] < a[3]


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
             (f"Blue: the ego object's context vectors, orange: the CAV object's, each in its own frame. "
              f"Grey wedges: σ1 = {params.sigma1:g}° around each context vector; purple diamonds: "
              f"σ2 = {params.sigma2:g} m (L1). Thick green: in L_ij and kept by consensus; thick red: removed by "
              f"consensus."),
             "",
             f"L_ij holds {plural(len(detail.candidates), 'pair')}; consensus kept "
             f"{int(detail.kept_by_consensus.sum())}; {len(detail.final)} "
             f"{'is' if len(detail.final) == 1 else 'are'} left after the one-to-one rule"
             + (f" ({detail.mean_distance:.1f} m apart on average, limit {params.distance_limit:g} m"
                f"{': rejected' if detail.rejected else ''})" if len(detail.final) else "") + "."]
    if outcome.result.anchor is not None:
        result = outcome.result
        lines.append(f"The winning anchor is {pair_name(trial, result.anchor)} with "
                     f"{plural(result.consensus_count, 'pair')}.")
    if len(detail.candidates):
        lines += ["", "| ego | CAV | votes | consensus | final | true |", "|---|---|---|---|---|---|"]
        for (i, j), votes, kept in list(zip(detail.candidates.tolist(), detail.votes.tolist(),
                                            detail.kept_by_consensus.tolist()))[:MAX_ROWS]:
            lines.append(f"| {short_id(trial.ego_ids[i])} | {short_id(trial.cav_ids[j])} | {votes} | "
                         f"{'kept' if kept else 'removed'} | "
                         f"{'yes' if (i, j) in final else 'no'} | {'yes' if (i, j) in truth else 'no'} |")
        if len(detail.candidates) > MAX_ROWS:
            lines.append(f"\n… and {plural(len(detail.candidates) - MAX_ROWS, 'more pair')}.")
    return "\n".join(lines)


def empty() -> Drawing:
    """A drawing that hides every inspector node (a ``SceneView`` hides empty line sets and
    labels it is not given)."""
    names = [f"inspector_{agent}_{part}" for agent in ("ego", "cav")
             for part in ("vectors", "bands", "regions", "kept", "removed")]
    return Drawing(meshes={"inspector_plates": no_plates()}, lines={name: Lines(no_lines(), BAND) for name in names},
                   labels={}, metrics_markdown="")

