"""The paper's baselines (Song et al., RA-L 2024, sec. IV): ICP, RICP and VIPS, and the references
``none`` (no calibration) and ``oracle`` (the true pairs), each with the interface of
``cbm.match``: ``method(ego_boxes, cav_boxes, init, params=None, **kw) -> MatchResult``. The
registry of every method, CBM included, is ``cbm.methods``."""
from .given import NoParams, match_none, match_oracle
from .icp import ICPParams, match_icp
from .ricp import RICPParams, match_ricp
from .vips import VIPSParams, match_vips

__all__ = ["ICPParams", "RICPParams", "NoParams", "VIPSParams", "match_icp", "match_none", "match_oracle",
           "match_ricp", "match_vips"]
