"""Small recordings written on the fly for the tests of opening data."""
from __future__ import annotations

from pathlib import Path

HEADER = "track_id,frame_id,timestamp_ms,agent_type,x,y,vx,vy,psi_rad,length,width"


def intersection(path: Path, two_until: int = 10, frames: int = 30, cars: int = 8) -> Path:
    """An INTERACTION recording (``vehicle_tracks_000.csv`` in the folder ``path``) whose first
    ``two_until`` frames hold two cars (an ego and a CAV that see nothing else) and the others
    ``cars`` cars a few metres apart: CBM can run from frame ``two_until`` on (0-based)."""
    path.mkdir(parents=True, exist_ok=True)
    lines = [HEADER]
    for frame in range(1, frames + 1):
        for car in range(2 if frame <= two_until else cars):
            x, y = 6.0 * (car % 4) + 0.1 * frame, 7.0 * (car // 4) + 0.3 * car
            lines.append(f"{car + 1},{frame},{100 * frame},car,{x},{y},1,0,{0.05 * car},4.5,1.9")
    (path / "vehicle_tracks_000.csv").write_text("\n".join(lines) + "\n")
    return path
