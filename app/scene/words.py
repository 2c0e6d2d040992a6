"""The words the app shows for every method parameter (``cbm.methods``) and every tracking parameter
of CBM over time (``cbm.TrackingParams``): a label with its unit and a hint in plain words, so that no
control, note or export shows a field's raw name."""
from __future__ import annotations

import ast
import inspect
import re
import textwrap

from cbm import TrackingParams
from cbm.methods import METHODS

WORDS = {
    # (parameter set, field): (label, hint in plain words)
    ("cbm", "sigma1"): ("σ1 angle (°)", "Two neighbour vectors (from an object to one of its neighbours, eq. 6-7) "
                        "count as the same neighbour only if they point within this angle of each other (eq. 8)."),
    ("cbm", "sigma2"): ("σ2 distance (m)", "Two neighbour vectors count as the same neighbour only if their "
                        "tips are at most this far apart, |Δx| + |Δy| in metres (eq. 8). Larger: more candidate "
                        "matches, more of them wrong."),
    ("cbm", "sigma3"): ("σ3 voting (m)", "In the consensus vote, a candidate pair backs another when their "
                        "neighbourhoods agree within this distance, |Δx| + |Δy| in metres (the released code's "
                        "vote, beyond the paper's eq. 10); pairs nobody backs are dropped."),
    ("cbm", "distance_limit"): ("distance limit (m)", "An anchor whose pairs lie farther apart than this on average "
                                "under the initial pose is rejected."),
    ("cbm", "consensus"): ("consensus", "The global consensus vote of eq. 10-11 (off: the paper's ablation)."),
    ("cbm", "consensus_rule"): ("consensus rule", "paper: every candidate needs a vote from another member "
                                "(eq. 10-11). released: as the authors' code, only candidates that share an object "
                                "with another need one."),
    ("cbm", "heading"): ("heading handling", "align: turn a CAV object's heading by 180° where that brings it "
                         "closer to the ego object's. fold: fold every heading into (-90°, 90°], as the released "
                         "code."),
    ("cbm", "estimator"): ("pose estimator", "welsch: the robust fit of eq. 15, outliers weigh little. "
                           "least_squares: the released code's plain fit, every pair weighs the same."),
    ("cbm", "welsch_floor"): ("Welsch scale floor (m)", "The robust fit's scale ν never goes below this: the least "
                              "detection noise assumed."),
    ("cbm", "refine"): ("guided re-association", "After CBM, pair all boxes one-to-one under its estimate and refit "
                        "until the pairs stop changing (beyond the paper)."),
    ("cbm", "refine_gate"): ("refine gate (σ)", "The re-association pairs boxes closer than this many standard "
                             "deviations of the pairs' noise."),
    ("icp", "max_iterations"): ("most iterations", "ICP stops after this many rounds of closest points and fit."),
    ("icp", "tolerance"): ("convergence tolerance", "ICP stops when the pose changes by less than this."),
    ("icp", "max_correspondence_distance"): ("pairing distance (m)", "A CAV box farther than this from its nearest "
                                             "ego box takes no part in the fit, and final pairs must be closer."),
    ("ricp", "max_iterations"): ("most iterations per scale", "Most reweighted fits at one Welsch scale."),
    ("ricp", "tolerance"): ("convergence tolerance", "The next scale starts when the pose changes by less than this."),
    ("ricp", "nu_begin_k"): ("first scale (× median gap)", "The first Welsch scale is this times the median distance "
                             "from a CAV box to its nearest ego box under the initial pose."),
    ("ricp", "nu_end_k"): ("last scale (× spacing)", "The scale never falls below this times the median spacing "
                           "of the ego's boxes."),
    ("ricp", "nu_alpha"): ("scale shrink factor", "The scale is multiplied by this after each round."),
    ("ricp", "anderson"): ("Anderson acceleration", "Speeds up the iteration by combining the last poses."),
    ("ricp", "anderson_m"): ("Anderson window", "How many previous poses Anderson acceleration combines."),
    ("ricp", "max_correspondence_distance"): ("pairing distance (m)", "Final pairs are mutual nearest boxes closer "
                                              "than this."),
    ("vips", "lambda_size"): ("size decay λ1 (1/m²)", "How fast the node affinity falls as two boxes' sizes differ."),
    ("vips", "lambda_position"): ("position decay λ2 (1/m)", "How fast the node affinity falls with the distance "
                                  "between two boxes under the initial pose."),
    ("vips", "lambda_distance"): ("distance decay λ3 (1/m²)", "How fast the edge affinity falls as the distances "
                                  "between two pairs of boxes differ."),
    ("vips", "lambda_heading"): ("heading decay λ4", "How fast the edge affinity falls as relative headings differ."),
    ("vips", "mu_size"): ("size weight μ1", "Weight of the size term in the node affinity."),
    ("vips", "mu_position"): ("position weight μ2", "Weight of the position term in the node affinity."),
    ("vips", "mu_distance"): ("distance weight μ3", "Weight of the distance term in the edge affinity."),
    ("vips", "mu_heading"): ("heading weight μ4", "Weight of the relative-heading term in the edge affinity."),
    ("vips", "candidate_radius"): ("candidate radius (m)", "Only boxes this close under the initial pose can pair."),
    ("vips", "top_k"): ("candidates per object", "Each ego box keeps this many candidates of highest affinity."),
    ("vips", "edge_gate"): ("edge gate (m)", "Two candidate pairs whose box distances differ by more than this do "
                            "not support each other."),
    ("vips", "score_threshold"): ("score threshold", "A pair is kept when its score is at least this share of the "
                                  "best pair's."),
    ("v2xregpp", "top_k"): ("boxes kept per agent", "Each agent keeps this many boxes: buses, trucks and cars "
                            "first, larger first."),
    ("v2xregpp", "max_range"): ("range (m)", "Boxes farther than this from their own agent are left out."),
    ("v2xregpp", "affinity"): ("affinity", "distance: a pose guessed from one pair of boxes scores the other boxes "
                               "it brings together, by centres and corners. oiou: the boxes it makes overlap."),
    ("v2xregpp", "distance_scale"): ("match distance (×)", "Scales how close two boxes must come to count as "
                                     "brought together: 1.5 m for buses and trucks, 1 m for cars, 0.5 m for people "
                                     "and bikes."),
    ("v2xregpp", "filter_threshold"): ("score to keep", "Pairs scoring at least this are kept when the best scores "
                                       "above 5; otherwise only the best-scoring pairs."),
    ("freealign", "anchor_error"): ("anchor tolerance (m)", "Two boxes become anchors when their distances to the "
                                    "other anchors agree within this (twice this between anchors)."),
    ("freealign", "box_error"): ("growth tolerance (m)", "After the anchors, a pair joins when its distances to "
                                 "every anchor agree within this."),
    ("freealign", "min_anchors"): ("fewest anchors", "A match needs at least this many anchors, and more pairs "
                                   "than this in all."),
    ("freealign", "max_boxes"): ("boxes per agent", "Only each agent's nearest boxes take part: the search "
                                 "compares every pair of boxes with every other, so its time grows fast."),
}
"""Every method parameter's label (words and unit) and hint: no control shows a field's raw name."""


def field_docs(cls: type) -> dict[str, str]:
    """The docstring under each field of the dataclass ``cls``, as one line of plain text."""
    body = ast.parse(textwrap.dedent(inspect.getsource(cls))).body[0].body
    return {field.target.id: " ".join(doc.value.value.replace("``", "").split())
            for field, doc in zip(body, body[1:])
            if isinstance(field, ast.AnnAssign) and isinstance(field.target, ast.Name)
            and isinstance(doc, ast.Expr) and isinstance(doc.value, ast.Constant) and isinstance(doc.value.value, str)}


TRACKING = "tracking"
"""The parameter set of CBM over time's tracking (``Settings.tracking``), beside the methods' sets."""
TRACKING_LABELS = {
    "gate": "agreement gate (σ)",
    "drift_m": "error drift (m/√s)",
    "drift_deg": "yaw error drift (°/√s)",
    "drift_share": "persisting error spread (share)",
    "chain": "start after (frames)",
    "window": "chain span (frames)",
    "lost_m": "lost past position spread (m)",
    "lost_deg": "lost past yaw spread (°)",
    "lost_after": "lost after misses (frames)",
    "reacquire_after": "jump after rejections (frames)",
    "sure_margin": "sure margin (ln)",
    "max_gap_s": "start over after a gap (s)",
}
"""Each tracking parameter's label, with its unit; its hint is the field's docstring."""
WORDS.update({(TRACKING, name): (label, field_docs(TrackingParams)[name]) for name, label in TRACKING_LABELS.items()})


def label_of(key: str, name: str) -> str:
    """The label of parameter ``name`` of the parameter set ``key`` (``Method.params_key``)."""
    return WORDS[(key, name)][0]


def plural(count: int, noun: str, nouns: str | None = None) -> str:
    """``count`` and the noun in the number it takes: "1 pair", "3 pairs" (``nouns``: an irregular plural)."""
    return f"{count} {noun if count == 1 else nouns or noun + 's'}"


def error_words(error: BaseException) -> str:
    """What went wrong in words: the message of an error raised on purpose (a frame that makes no
    trial, a file that cannot be read: ``ValueError``), the error's kind besides for an unexpected one."""
    if isinstance(error, ValueError) and str(error):
        return str(error)
    return f"an unexpected error in the app ({type(error).__name__}: {error})"


def margin_words(count: int, runner_up: int) -> str:
    """The consensus vote as the app prints it (its margin is the difference): the winning anchor's
    pairs and the runner-up's."""
    return f"{count} pairs vs {runner_up} for the runner-up"


FIELD_ERROR = re.compile(r"^(\w+Params)\.(\w+) (must .*)$", re.S)
"""A parameter class's own complaint about one field (``CBMParams.sigma2 must be at most 10, got 25``)."""


def field_label(cls: str, name: str) -> str:
    """The label the app shows for field ``name`` of the parameter class named ``cls``."""
    if cls == "ScenarioParams":
        return SCENARIO_WORDS.get(name, name)
    key = TRACKING if cls == "TrackingParams" else next(
        (m.params_key for m in METHODS.values() if m.params.__name__ == cls), "")
    return WORDS.get((key, name), (name, ""))[0]


def setting_words(error: BaseException) -> str:
    """A refused setting in the app's words: the control's label for the field a parameter class
    names (``σ2 distance (m) must be at most 10, got 25``), any other message as it is."""
    found = FIELD_ERROR.match(str(error))
    if found is None:
        return str(error)
    cls, name, rest = found.groups()
    return f"{field_label(cls, name)} {rest}"


SCENARIO_WORDS = {
    "protocol": "protocol",
    "localization": "localization error",
    "eta": "co-visibility eta",
    "sigma_p": "position noise σp (m)",
    "sigma_theta": "heading noise σθ (°)",
    "flip_prob": "heading flip prob.",
    "loc_x": "localization x (m)",
    "loc_y": "localization y (m)",
    "loc_yaw": "localization yaw (°)",
    "loc_tau": "drift time constant (s)",
    "loc_white": "drift white noise (share)",
    "sensor_range": "sensor range (m)",
    "miss_rate": "missed detections (share)",
    "false_rate": "false boxes (per detection)",
    "min_score": "detector score at least",
    "sight": "line of sight",
    "sight_share": "visible share at least",
    "delay_ms": "message delay (ms)",
    "jitter_ms": "delay jitter ± (ms)",
    "seed": "seed",
}
"""Every scenario field's label (words and unit), as the Scenario tab shows it."""
