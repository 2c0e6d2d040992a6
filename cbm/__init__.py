"""CBM: context-based matching for cooperative-perception pose calibration (Song et al., RA-L 2024).

    from cbm import CBMParams, match
    result = match(ego_boxes, cav_boxes, init=T_tilde, params=CBMParams())

``cbm.reference`` states eq. 5-13 plainly; ``cbm.match`` runs them fast (``cbm.engine``);
``cbm.SequenceCalibrator`` calibrates a sequence frame after frame (``cbm.sequence``).
"""
from .params import CBMParams
from .pipeline import match
from .result import MatchResult, TrackNote
from .sequence import SequenceCalibrator, TrackingParams

__all__ = ["CBMParams", "MatchResult", "SequenceCalibrator", "TrackNote", "TrackingParams", "match"]
