"""Which category names denote vehicles that could carry sensors and act as a CAV."""
from __future__ import annotations

from collections.abc import Iterable

import numpy as np

VEHICLE_CATEGORIES = frozenset({
    "car", "van", "truck", "bus", "vehicle", "suv", "pickup",
    "regular_vehicle", "large_vehicle", "box_truck", "truck_cab", "school_bus", "articulated_bus",
})
"""Normalised names (lower case, spaces and hyphens as underscores): Argoverse 2's motor
vehicles (trailers, bicycles and motorcycles excluded), SinD / INTERACTION / DAIR-V2X / V2V4Real
cars, vans, trucks and buses, and the synthetic scenes' car, truck and bus."""


def normalised(name: str) -> str:
    return str(name).strip().lower().replace(" ", "_").replace("-", "_")


def is_vehicle(categories: Iterable[str] | np.ndarray) -> np.ndarray:
    """Boolean array: which of ``categories`` are motor vehicles that may act as the CAV."""
    return np.array([normalised(c) in VEHICLE_CATEGORIES for c in categories], dtype=bool)


def is_roadside(agent_id: object) -> bool:
    """Whether an agent is a roadside (infrastructure) unit, not a vehicle: DAIR-V2X's, V2X-Seq's and
    TUMTraf's ``infrastructure``, the OPV2V family's negative ids (V2XSet, Adver-City, V2X-Real)."""
    name = str(agent_id)
    return name == "infrastructure" or (name.startswith("-") and name[1:].isdigit())
