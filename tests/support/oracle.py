"""A literal, loop-by-loop transcription of CBM (paper eq. 5-13) to check the fast implementation.

Slow on purpose: every quadruple is tested, every set is a Python set. Only for a dozen objects.
"""
from __future__ import annotations

import math

import numpy as np


def _fold(theta: float) -> float:
    """Released code: heading into (-pi/2, pi/2]."""
    folded = math.fmod(theta, math.pi)
    if folded > math.pi / 2:
        folded -= math.pi
    if folded <= -math.pi / 2:
        folded += math.pi
    return folded


def _context(p_anchor, theta, p_other):
    """Eq. 5: R(theta)^T (p_other - p_anchor)."""
    dx, dy = p_other[0] - p_anchor[0], p_other[1] - p_anchor[1]
    c, s = math.cos(theta), math.sin(theta)
    return (c * dx + s * dy, -s * dx + c * dy)


def _similar(z, w, sigma1, tolerance):
    """Eq. 7 with Algorithm 1: S1 <= 1 and S2 <= 1."""
    nz, nw = math.hypot(*z), math.hypot(*w)
    if nz == 0 or nw == 0:
        return False
    angle = math.acos(min(abs(z[0] * w[0] + z[1] * w[1]) / (nz * nw), 1.0))
    return angle / sigma1 <= 1 and (abs(z[0] - w[0]) + abs(z[1] - w[1])) / tolerance <= 1


def _rigid_rms(pairs, ego_xy, cav_xy):
    src = np.array([cav_xy[j] for _, j in pairs])
    dst = np.array([ego_xy[i] for i, _ in pairs])
    order = np.lexsort((src[:, 1], src[:, 0], dst[:, 1], dst[:, 0]))
    src, dst = src[order], dst[order]
    if len(pairs) < 2:
        return 0.0, dst, src
    sm, dm = src.mean(axis=0), dst.mean(axis=0)
    s, d = src - sm, dst - dm
    yaw = math.atan2(float(np.sum(s[:, 0] * d[:, 1] - s[:, 1] * d[:, 0])),
                     float(np.sum(s[:, 0] * d[:, 0] + s[:, 1] * d[:, 1])))
    c, n = math.cos(yaw), math.sin(yaw)
    moved = np.stack([c * s[:, 0] - n * s[:, 1], n * s[:, 0] + c * s[:, 1]], axis=1)
    return float(np.sqrt(np.mean(np.sum((moved - d) ** 2, axis=1)))), dst, src


def oracle(ego, cav, init, sigma1_deg, sigma2, sigma3, distance_limit, consensus, rule, heading):
    """Eq. 5-13 with ties broken like ``cbm.selection``: (pairs, card(L) of the winner, runner-up size).

    The runner-up is the largest filtered set that shares no pair with the winner's."""
    ne, nc = len(ego), len(cav)
    R, t = init[:2, :2], init[:2, 2]
    init_yaw = math.atan2(init[1, 0], init[0, 0])
    ego_xy = [tuple(b[:2]) for b in ego]
    cav_xy = [tuple(R @ b[:2] + t) for b in cav]
    ego_th = [_fold(b[6]) for b in ego]
    cav_th = [_fold(b[6] + init_yaw) for b in cav]
    sigma1 = math.radians(sigma1_deg)

    def sign(i, j):
        return 1.0 if heading == "fold" or abs(cav_th[j] - ego_th[i]) <= math.pi / 2 else -1.0

    def accepted_set(i, j, tolerance):
        """Algorithm 1 for anchor (i, j), then eq. 8 (the anchor joins a set of at least 2)."""
        s = sign(i, j)
        found = set()
        for ip in range(ne):
            for jp in range(nc):
                if ip == i or jp == j:
                    continue
                z = _context(ego_xy[i], ego_th[i], ego_xy[ip])
                w = _context(cav_xy[j], cav_th[j], cav_xy[jp])
                if _similar(z, (s * w[0], s * w[1]), sigma1, tolerance):
                    found.add((ip, jp))
        return found | {(i, j)} if found else set()

    anchors = [(i, j) for i in range(ne) for j in range(nc)]
    L = {a: accepted_set(*a, sigma2) for a in anchors}
    V = {a: accepted_set(*a, sigma3) for a in anchors} if consensus else {}

    def lone(members):
        return {(ip, jp) for (ip, jp) in members
                if sum(1 for (k, _) in members if k == ip) == 1 and sum(1 for (_, h) in members if h == jp) == 1}

    final = {}
    for a in anchors:
        members = L[a]
        if consensus and rule == "paper":  # eq. 9-10
            members = {m for m in members if sum(1 for k in L[a] if m in V[k]) > 1}
        elif consensus and rule == "released":
            alone = lone(members)
            members = alone | {m for m in members if any(m in V[k] for k in alone)}
        members = lone(members)  # eq. 11
        if members and np.mean([math.dist(ego_xy[i], cav_xy[j]) for i, j in members]) > distance_limit:
            members = set()
        final[a] = members

    best = max(len(m) for m in final.values()) if final else 0
    if best == 0:
        return np.zeros((0, 2), dtype=int), 0, 0

    def key(a):
        pairs = sorted(final[a])
        rms, dst, src = _rigid_rms(pairs, ego_xy, cav_xy)
        values = (rms, *dst.mean(axis=0), *src.mean(axis=0))
        return tuple(round(float(v), 9) for v in values) + (*ego_xy[a[0]], *cav_xy[a[1]])

    winner = min((a for a in anchors if len(final[a]) == best), key=key)  # eq. 12-13
    runner_up = max((len(m) for m in final.values() if not (m & final[winner])), default=0)
    return np.array(sorted(final[winner]), dtype=int).reshape(-1, 2), len(L[winner]), runner_up
