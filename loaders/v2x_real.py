"""V2X-Real (Xiang et al., ECCV 2024): what sets its per-agent YAML apart from OPV2V's; the folders
are walked and the boxes read by ``loaders.opv2v``.

Layout, as its OpenCOOD-based code walks it: ``v2xreal/{train,validate,test}/<scenario>/<agent
id>/<timestamp>.yaml`` (scenarios such as ``2023-03-17-15-53-02_1_0``), each beside a
``<timestamp>.bin`` sweep (float32 x, y, z, intensity; not read). Vehicles have ids ``1``, ``2``;
infrastructure ``-1``, ``-2`` -- a negative id is infrastructure, as for V2XSet's roadside units,
and every file says so again with ``infra: true|false`` (a file whose flag contradicts its folder
is refused).

Keys: ``lidar_pose`` and ``true_ego_pose`` (not OPV2V's ``true_ego_pos``), six numbers ``[x, y, z,
roll, yaw, pitch]`` in metres and degrees; ``vehicles: {id: {location, center, extent, angle,
obj_type}}`` in the world frame, as OPV2V's (``location + center``, half ``extent``), but from real
sensors: right-handed, nothing mirrored. Object ids are shared by the agents (OpenCOOD merges the
agents' boxes by id). ``attribute: static`` marks parked objects; they stay road users. The files keep no capture time
of an agent: the ``<timestamp>`` of a file name is the frame's, shared by the agents (its code pairs
their files by it), so ``Sequence.agent_times`` stays empty, as for OPV2V.

``obj_type`` -> our categories by :data:`CATEGORY_NAMES` (part of ``loaders.opv2v.CATEGORY_NAMES``;
an unknown name is kept as written); the static props of
:data:`STATIC_PROPS` (TrashCan, FireHydrant) are not road users: they keep a category of their own
and are left out of trials, with one warning counting them.
"""
from __future__ import annotations

from pathlib import Path

from .errors import LoaderError, shown

MARKERS = ("infra", "true_ego_pose")
"""Top-level keys only V2X-Real's files have."""
CATEGORY_NAMES = {
    "car": "car", "policecar": "car", "van": "van", "truck": "truck", "concretetruck": "truck",
    "longvehicle": "truck", "bus": "bus", "pedestrian": "pedestrian", "child": "pedestrian",
    "roadworker": "pedestrian", "scooterrider": "bicycle", "bicyclerider": "bicycle",
    "motorcycle": "motorcycle", "motorcylerider": "motorcycle", "motorcyclerider": "motorcycle",
}
"""V2X-Real's ``obj_type`` (normalised; ``MotorcyleRider`` as its class list spells it) -> our
categories: riders of scooters and bicycles are our cyclist class, ``bicycle``."""
STATIC_PROPS = {"trashcan": "trash_can", "firehydrant": "fire_hydrant"}
"""Labelled street furniture -> its category, left out of trials."""


def is_record(record) -> bool:
    """Whether a parsed per-agent file is V2X-Real's."""
    return isinstance(record, dict) and any(key in record for key in MARKERS)


def check_infra(path: Path, record: dict, agent: str) -> None:
    """``LoaderError`` unless the file's ``infra`` flag (when present) is a boolean that agrees with
    its folder: a negative id is infrastructure."""
    if "infra" not in record:
        return
    flag, expected = record["infra"], int(agent) < 0
    if not isinstance(flag, bool):
        raise LoaderError(f"{path}: infra: expected true or false, got {shown(flag)}")
    if flag != expected:
        raise LoaderError(f"{path}: infra: expected {str(expected).lower()} in agent folder {agent!r} (negative ids "
                          f"are infrastructure), got {str(flag).lower()}")


def agent_of(folder: str, record) -> tuple[str, str | None]:
    """The agent id of a folder not named by one (the dataset tool's example ``infra_2``), from its
    file's ``infra`` flag: infrastructure ``-N``, a vehicle ``N``, ``N`` the digits ending the
    folder's name (else 1 for infrastructure, 0 for a vehicle); and a note saying so (None for a
    file that is not V2X-Real's: agent 0, as before)."""
    flag = record.get("infra") if isinstance(record, dict) else None
    if not isinstance(flag, bool):
        return "0", None
    digits = folder[len(folder.rstrip("0123456789")):].lstrip("0")
    agent = f"-{digits or 1}" if flag else digits or "0"
    role = "infrastructure" if flag else "a vehicle"
    return agent, f"not an agent id; read as agent {agent} ({role}, as its files' infra flag says)"


def left_out_note(count: int, names: set[str]) -> str:
    """The note of a V2X-Real load that left static props out of the trials (not a gap: how it is read)."""
    return f"{count} static object(s) ({', '.join(sorted(names))}) are not road users: left out of trials"
