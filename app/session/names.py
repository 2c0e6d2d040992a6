"""How the page names an agent: its role and, when the id says more than the role, its short id."""
from __future__ import annotations

from evaluation.diagnosis import short_id


def agent_id_shown(role: str, agent_id: object) -> str | None:
    """The agent's short id as labels show it, or None when it only repeats ``role`` (the shipped
    Argoverse 2 log names its recording car ``ego``, and abstract agents have no id)."""
    if agent_id is None:
        return None
    shown = short_id(agent_id)
    return None if shown.casefold() == role.casefold() else shown


def agent_name(role: str, agent_id: object, code: bool = False) -> str:
    """``role`` and the agent's short id (in backticks for markdown when ``code``), or ``role`` alone."""
    shown = agent_id_shown(role, agent_id)
    if shown is None:
        return role
    return f"{role} `{shown}`" if code else f"{role} {shown}"
