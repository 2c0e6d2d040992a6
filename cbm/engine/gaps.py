"""How far apart a pair's two boxes, and two poses, are: the distances the verification of
hypotheses reads (``cbm.hypotheses``: each pair's evidence, and whether two answers are one pose),
compiled, each summed as numpy sums it."""
from __future__ import annotations

import math

import numba
import numpy as np


@numba.njit(cache=True, nogil=True)
def pair_gaps(ego, moved, pairs):
    """Each pair's centre distance and the angle between its heading axes (``cbm.engine.assignment.axis_difference``),
    each as numpy computes it elementwise."""
    d, turn = np.empty(len(pairs)), np.empty(len(pairs))
    for k in range(len(pairs)):
        e, c = pairs[k, 0], pairs[k, 1]
        dx, dy = moved[c, 0] - ego[e, 0], moved[c, 1] - ego[e, 1]
        d[k] = math.sqrt(dx * dx + dy * dy)
        angle = abs((moved[c, 6] - ego[e, 6] + math.pi) % (2.0 * math.pi) - math.pi)
        turn[k] = min(angle, math.pi - angle)
    return d, turn


@numba.njit(cache=True, nogil=True)
def pose_gap(a, b):
    """(metres, degrees, scale): how far and by how many degrees (absolute) the correction ``b``
    moves and turns away from ``a`` (the transform ``inverse(a) @ b``), summed in plain order, and
    1 plus the corrections' translations, to which its rounding is proportional."""
    dx, dy = b[0, 2] - a[0, 2], b[1, 2] - a[1, 2]
    x, y = a[0, 0] * dx + a[1, 0] * dy, a[0, 1] * dx + a[1, 1] * dy
    cos_part = a[0, 0] * b[0, 0] + a[1, 0] * b[1, 0]
    sin_part = a[0, 1] * b[0, 0] + a[1, 1] * b[1, 0]
    scale = 1.0 + abs(a[0, 2]) + abs(a[1, 2]) + abs(b[0, 2]) + abs(b[1, 2])
    return math.hypot(x, y), abs(math.degrees(math.atan2(sin_part, cos_part))), scale
