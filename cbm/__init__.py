"""CBM: context-based matching for cooperative-perception pose calibration (Song et al., RA-L 2024).

    from cbm import CBMParams, match
    result = match(ego_boxes, cav_boxes, init=T_tilde, params=CBMParams())

``cbm.reference`` states the paper's eq. 5-14 plainly; ``cbm.match`` runs them fast (``cbm.engine``)
and is the one way to run CBM: ``reuse=`` keeps what a threshold edit does not change,
``explain=True`` hands the result the run's own ``Explanation``, ``stop=`` abandons it
(``Cancelled``). ``cbm.SequenceCalibrator`` calibrates a sequence frame after frame; ``cbm.methods``
holds every method, CBM's peers included. What this package offers anyone outside it is named here:

- running: ``match``, ``CBMParams`` (``MOST``: the largest value of each field), ``MatchResult``
  (``MIN_SHARED``: the fewest pairs of a pose CBM stands by),
  ``Fit``, ``robust_fit``, ``Explanation``, ``AnchorDetail``, ``Reuse``, ``SequenceCalibrator``,
  ``TrackingParams``, ``TrackNote``, ``se2``;
- stopping: ``stoppable`` (a block in which CBM asks whether to stop), ``Cancelled``;
- the compiler: ``warm_up``, ``load_kernels``, ``kernels_cached``, ``compile_side_by_side``,
  ``CompileFailed``, ``interpreted`` (CBM without the compiler), ``guard_compiles``,
  ``COMPILE_LOCK``, ``INTERPRETED_UP_TO``;
- memory: ``return_memory`` (hands what CBM's threads freed back to the system).
"""
from . import se2
from .engine import Reuse
from .engine.interpreted import COMPILE_LOCK, INTERPRETED_UP_TO, guard_compiles, interpreted
from .engine.threads import Cancelled, stoppable
from .engine.threads import trim_freed as return_memory
from .estimate import robust_fit
from .explain import AnchorDetail, Explanation
from .hypotheses import MIN_SHARED
from .params import MOST, CBMParams
from .pipeline import match
from .result import Fit, MatchResult, TrackNote
from .sequence import SequenceCalibrator
from .track import TrackingParams

_COMPILER = {"warm_up", "load_kernels", "kernels_cached", "compile_side_by_side", "CompileFailed"}
"""Names of ``cbm.warmup``, imported on first use: ``python -m cbm.warmup`` then runs the module once."""


def __getattr__(name: str):
    if name in _COMPILER:
        from . import warmup
        return getattr(warmup, name)
    raise AttributeError(f"module 'cbm' has no attribute {name!r}")


__all__ = ["COMPILE_LOCK", "INTERPRETED_UP_TO", "MIN_SHARED", "MOST", "AnchorDetail", "CBMParams", "Cancelled",
           "CompileFailed", "Explanation", "Fit", "MatchResult", "Reuse", "SequenceCalibrator", "TrackNote",
           "TrackingParams", "compile_side_by_side", "guard_compiles", "interpreted", "kernels_cached",
           "load_kernels", "match", "return_memory", "robust_fit", "se2", "stoppable", "warm_up"]
