"""The paper's baselines (Song et al., RA-L 2024, sec. IV): ICP, RICP and VIPS; the prior-free methods
the field compares with today, V2X-Reg++ and FreeAlign; and the references
``none`` (no calibration) and ``oracle`` (the true pairs), each with the interface of
``cbm.match``: ``method(ego_boxes, cav_boxes, init, params=None, **kw) -> MatchResult``. The
registry of every method, CBM included, is ``cbm.methods``."""
from .freealign import FreeAlignParams, match_freealign
from .given import NoParams, match_none, match_oracle
from .icp import ICPParams, match_icp
from .ricp import RICPParams, match_ricp
from .v2xregpp import V2XRegParams, match_v2xregpp
from .vips import VIPSParams, match_vips

__all__ = ["FreeAlignParams", "ICPParams", "RICPParams", "NoParams", "V2XRegParams", "VIPSParams", "match_freealign",
           "match_icp", "match_none", "match_oracle", "match_ricp", "match_v2xregpp", "match_vips"]
