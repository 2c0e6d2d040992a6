"""How the page names an agent: its role and, when the id says more than the role, its short id."""
from __future__ import annotations

from evaluation.diagnosis import short_id
from loaders import is_roadside

ROLE_IDS = frozenset({"ego", "vehicle", "infrastructure"})
"""Agent ids that say no more than the agent's role (Argoverse 2's ``ego``, DAIR-V2X's two agents)."""
ROADSIDE = "roadside unit"
"""What the page calls an infrastructure agent: a unit on a pole by the road, not a car."""


def role_of(role: str, agent_id: object) -> str:
    """``role`` (``CAV``, ``CAV 1``) with ``CAV`` read as ``roadside unit`` for an infrastructure agent."""
    return role.replace("CAV", ROADSIDE) if is_roadside(agent_id) else role


def agent_id_shown(role: str, agent_id: object) -> str | None:
    """The agent's short id as labels show it, or None when it only repeats ``role`` (the shipped
    Argoverse 2 log names its recording car ``ego``, and abstract agents have no id)."""
    if agent_id is None or str(agent_id).casefold() in ROLE_IDS:
        return None
    shown = short_id(agent_id)
    return None if shown.casefold() == role.casefold() else shown


def agent_name(role: str, agent_id: object, code: bool = False) -> str:
    """``role`` (``role_of``) and the agent's short id (in backticks for markdown when ``code``), or
    the role alone."""
    role = role_of(role, agent_id)
    shown = agent_id_shown(role, agent_id)
    if shown is None:
        return role
    return f"{role} `{shown}`" if code else f"{role} {shown}"
