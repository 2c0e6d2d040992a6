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


SIND_VEHICLE_HEADER = ("track_id,frame_id,timestamp_ms,agent_type,x,y,vx,vy,yaw_rad,heading_rad,length,width,"
                       "ax,ay,v_lon,v_lat,a_lon,a_lat")


def moving_traffic(path: Path, layout: str, objects: int = 120, frames: int = 100, seed: int = 0) -> Path:
    """The vehicles of a synthetic intersection (``loaders.synthetic.generate``: most of them
    moving, up to 10 m/s) written as a drone recording at 10 Hz in the folder ``path``: SinD's
    ``Veh_smoothed_tracks.csv`` (``layout="sind"``, its 18 columns) or INTERACTION's
    ``vehicle_tracks_000.csv`` (``"interaction"``); velocities are the positions' differences."""
    from loaders.synthetic import generate

    scene, last, lines = generate(objects, frames, seed), {}, []
    for k in range(len(scene)):
        frame, boxes = scene[k], scene[k].boxes()
        for (x, y, _, length, width, _, yaw), track, kind in zip(boxes, frame.track_ids, frame.categories):
            if kind == "pedestrian":
                continue
            vx, vy = (10 * (x - last[track][0]), 10 * (y - last[track][1])) if track in last else (0.0, 0.0)
            last[track] = (x, y)
            at = f"{int(track) + 1},{k + 1},{100 * (k + 1)}"
            moving = f"{x:.3f},{y:.3f},{vx:.3f},{vy:.3f}"
            if layout == "sind":
                lines.append(f"{at},{kind},{moving},{yaw:.4f},{yaw:.4f},{length:.2f},{width:.2f},0,0,0,0,0,0")
            else:
                lines.append(f"{at},car,{moving},{yaw:.4f},{length:.2f},{width:.2f}")
    path.mkdir(parents=True, exist_ok=True)
    name, header = (("Veh_smoothed_tracks.csv", SIND_VEHICLE_HEADER) if layout == "sind"
                    else ("vehicle_tracks_000.csv", HEADER))
    (path / name).write_text("\n".join([header, *lines]) + "\n")
    return path
