"""Dataset readers that turn every supported dataset into one scene model.

    import loaders
    seq = loaders.open("argoverse2")           # the shipped default scene
    seq = loaders.open("synthetic:200:seed=7")  # a generated intersection
    seq = loaders.open("path/to/dataset")       # the loader is picked from what is found there
    frame = seq[0]
    boxes = frame.boxes()                       # (N, 7): x, y, z, length, width, height, yaw

See ``loaders/README.md`` for the datasets, the generic table schema and the bad-input policy.
"""
from . import synthetic
from .categories import is_roadside, is_vehicle
from .dispatch import open, repository_data
from .errors import LoaderError
from .scene import AGENT_COLUMNS, BOX_COLUMNS, OBJECT_COLUMNS, Frame, MapGeometry, Sequence

__all__ = [
    "AGENT_COLUMNS", "BOX_COLUMNS", "OBJECT_COLUMNS", "Frame", "LoaderError", "MapGeometry",
    "Sequence", "is_roadside", "is_vehicle", "open", "repository_data", "synthetic",
]
