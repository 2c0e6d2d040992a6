"""The shareable recording: one self-contained HTML page (inline script and style, no library, no
network) that replays the frames a tab has shown, seen from above in the ego frame.

Each frame draws what the app's top-down view draws, flat in one plane: the ego's boxes and the CAV's
where the estimate puts them as the app's footprints (the CAV's narrowed on the same centre,
``cavs.SLIM``), their corners written in the page's data, so that a pair the metrics call aligned
shows its two footprints on one centre; over them the CAV's boxes where the wrong pose put them
(outlines), the match lines from footprint centre to footprint centre right, wrong and missed, and the
boxes of wrong and missed pairs outlined, in the app's palette (Okabe-Ito when the tab is in
presentation mode), beside the frame's metrics, worded and numbered as the app's metrics panel; a
slider, previous, next and play above the view move through the frames; the view is the app's
top-down one (x up the page); the wheel zooms and a drag pans (double click: fit again). The view
takes the height the window leaves, so the controls and the metrics are in the first screen of a 1280x720 window.
"""
from __future__ import annotations

import dataclasses
import html
import importlib.metadata
import json
import re
import time
from typing import Any

import numpy as np

from cbm.methods import METHODS

from ..session.recording import FrameRecord, Recording
from ..session.settings import Settings
from . import colours, geometry
from .cavs import SLIM
from .text import VOTE_ROW, number
from .words import label_of, margin_words, plural

APP_NAME = "CBM Explorer"
DATA_ID = "recording-data"


def app_version() -> str:
    try:
        return importlib.metadata.version("cbm-explorer")
    except importlib.metadata.PackageNotFoundError:
        return "unknown"


def _rounded(array: np.ndarray, digits: int = 3) -> list:
    return np.round(np.asarray(array, float), digits).tolist()


def _ratio(value: float | None) -> str:
    return number(float("nan") if value is None else value)


def _with_unit(value: float | None, unit: str) -> str:
    return number(float("nan") if value is None else value, unit)


def metrics_rows(metrics: dict[str, Any]) -> list[list[str]]:
    """The frame's metrics table as (label, text) rows, worded as the app's metrics panel."""
    m = metrics
    rows = [["objects (ego / CAV)", f"{m['n_ego']} / {m['n_cav']}"],
            ["co-visible", str(m["n_true"])],
            ["matches", f"{m['n_matched']} ({m['n_correct']} right)"],
            ["precision / recall", f"{_ratio(m['precision'])} / {_ratio(m['recall'])}"],
            ["AD", _with_unit(m["ad"], " m")],
            ["RTE before → after", f"{_with_unit(m['rte_before'], ' m')} → {_with_unit(m['rte'], ' m')}"],
            ["RRE before → after", f"{_with_unit(m['rre_before'], '°')} → {_with_unit(m['rre'], '°')}"]]
    if m.get("consensus_count") is not None:
        rows.append([VOTE_ROW, margin_words(m["consensus_count"], m["runner_up_count"])])
    rows.append(["result", "success (RTE < 1 m, RRE < 1°)" if m["success"] else "failed"])
    return rows


def footprints(top: np.ndarray, slim: float = 1.0) -> list:
    """The (N, 4, 2) corners of top-down boxes (N, 5: x, y, length, width, yaw) as the app draws their
    footprints (``geometry.footprints``), length and width times ``slim``, rounded for the page."""
    top = np.asarray(top, dtype=float).reshape(-1, 5)
    boxes = np.zeros((len(top), 7))
    boxes[:, [0, 1, 3, 4, 6]] = top
    boxes[:, 3:5] *= slim
    return _rounded(geometry.footprints(boxes))


def frame_data(record: FrameRecord) -> dict[str, Any]:
    """One frame as the page's script reads it: every box as the corners of its footprint drawn."""
    return {"frame": record.frame, "agents": record.agents, "ego": footprints(record.ego),
            "before": footprints(record.cav_before), "after": footprints(record.cav_after, SLIM[0]),
            "poseBefore": _rounded(record.cav_pose_before), "poseAfter": _rounded(record.cav_pose_after),
            "right": record.right.tolist(), "wrong": record.wrong.tolist(), "missed": record.missed.tolist(),
            "success": bool(record.metrics["success"]), "table": metrics_rows(record.metrics)}


def settings_lines(settings: Settings) -> list[str]:
    """The method, its thresholds and the scenario, one line each."""
    method = METHODS[settings.method]
    params = dataclasses.asdict(settings.params) if dataclasses.is_dataclass(settings.params) else {}
    s = settings.scenario
    scenario = (f"protocol {s.protocol} · η {s.eta:g} · σp {s.sigma_p:g} m · σθ {s.sigma_theta:g}° · "
                f"flip {s.flip_prob:g} · localization {s.localization} ({s.loc_x:g} m, {s.loc_y:g} m, "
                f"{s.loc_yaw:g}°) · range {s.sensor_range:g} m · seed {s.seed}")
    worded = " · ".join(f"{label_of(method.params_key, k)} {v}" for k, v in params.items())
    return [f"Method: {method.label}", f"Parameters: {worded or 'none'}", f"Scenario: {scenario}"]


def palette_data(palette: colours.Palette) -> dict[str, Any]:
    def stroke(s: colours.Stroke) -> dict[str, Any]:
        return {"color": list(s.color), "width": s.thickness, "dash": s.dash}

    return {"ego": list(palette.ego_boxes), "cav": list(palette.cav_boxes), "before": list(palette.cav_before),
            "egoVehicle": list(palette.ego_vehicle), "cavVehicle": list(palette.cav_vehicle),
            "right": stroke(palette.right), "wrong": stroke(palette.wrong), "missed": stroke(palette.missed)}


def recording_data(recording: Recording, dataset: str, presentation: bool) -> dict[str, Any]:
    """Everything the page shows, as JSON-ready data."""
    settings, records = recording.snapshot()
    palette = colours.palette(dataclasses.replace(settings.view, presentation=presentation, dark=False))
    return {"app": APP_NAME, "version": app_version(), "dataset": dataset, "count": plural(len(records), "frame"),
            "exported": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
            "settings": settings_lines(settings),
            "legend": re.sub(r"\*\*", "", palette.legend).replace(colours.LABELS_NOTE, "")
                                                             .replace(colours.CROSSED_NOTE, ""),
            "palette": palette_data(palette), "frames": [frame_data(r) for r in records]}


def recording_html(recording: Recording, dataset: str, presentation: bool = False) -> bytes:
    """The page of ``recording`` (at least one frame) as UTF-8 bytes."""
    if not len(recording):
        raise ValueError("the recording has no frame")
    content = recording_data(recording, dataset, presentation)
    data = json.dumps(content, ensure_ascii=False, separators=(",", ":"))
    title = html.escape(f"{APP_NAME} — {dataset} — {content['count']}")
    page = PAGE.replace("%TITLE%", title).replace("%DATA%", data.replace("</", "<\\/"))
    return page.replace("%STYLE%", STYLE).replace("%SCRIPT%", SCRIPT).encode("utf-8")


PAGE = """<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><meta name="viewport" content="width=device-width">
<title>%TITLE%</title><style>%STYLE%</style></head>
<body><header><h1 id="title"></h1><div id="settings"></div>
<div id="controls"><button id="prev" title="previous frame (←)">◀ prev</button>
<button id="play">▶ play</button><button id="next" title="next frame (→)">next ▶</button>
<input id="frame-slider" type="range" min="0" max="0" value="0"><span id="frame-label"></span></div></header>
<main><div id="stage"><canvas id="view" width="900" height="560"></canvas><p id="legend"></p></div>
<aside><h2 id="frame-title"></h2><p id="agents"></p><table id="metrics"></table>
<p class="hint">Wheel: zoom · drag: pan · double click: fit · ← →: frames</p></aside></main>
<script type="application/json" id="recording-data">%DATA%</script><script>%SCRIPT%</script></body></html>
"""

STYLE = """
html,body{height:100%}
body{font-family:system-ui,-apple-system,'Segoe UI',sans-serif;margin:0;color:#222;background:#fafafa;
display:flex;flex-direction:column}
header{padding:8px 16px 6px;background:#fff;border-bottom:1px solid #ddd}h1{font-size:17px;margin:0 0 2px}
#settings div{font-size:12px;color:#555;white-space:nowrap;overflow:hidden;text-overflow:ellipsis}
#controls{display:flex;gap:8px;align-items:center;margin-top:6px}#frame-slider{flex:1;max-width:640px}
main{display:flex;gap:16px;padding:10px 16px;flex:1;min-height:0}
#stage{flex:1;min-width:0;display:flex;flex-direction:column}
canvas{background:#fff;border:1px solid #ccc;cursor:grab;width:100%;flex:1;min-height:200px}
button{padding:4px 10px}aside{width:320px;flex:none;overflow:auto}h2{font-size:16px;margin:2px 0}
#agents{margin:2px 0 6px}
table{border-collapse:collapse;font-size:13px}td{padding:3px 8px;border-bottom:1px solid #eee}
td:first-child{color:#555}.failed{color:#c0392b}.success{color:#1e8c3c}
.hint,#legend{font-size:12px;color:#666;margin:4px 0 0}
"""

SCRIPT = r"""
const data = JSON.parse(document.getElementById('recording-data').textContent);
const frames = data.frames, pal = data.palette;
const canvas = document.getElementById('view'), ctx = canvas.getContext('2d');
const slider = document.getElementById('frame-slider');
let index = 0, timer = null, view = null, drag = null;
const rgb = (c, a) => `rgba(${c[0]},${c[1]},${c[2]},${a === undefined ? 1 : a})`;
const toScreen = (x, y) => [view.ox - y * view.scale, view.oy - x * view.scale];

function quad(q) { return q.map(([x, y]) => toScreen(x, y)); }
function centre(q) { return [0, 1].map(k => q.reduce((sum, p) => sum + p[k], 0) / q.length); }
function rect(x, y, l, w, yaw) {
  const c = Math.cos(yaw), s = Math.sin(yaw);
  return [[1, 1], [-1, 1], [-1, -1], [1, -1]].map(([u, v]) => {
    const a = u * l / 2, d = v * w / 2;
    return toScreen(x + c * a - s * d, y + s * a + c * d);
  });
}
function polygon(points, fill, stroke, width) {
  ctx.beginPath(); points.forEach(([px, py], i) => i ? ctx.lineTo(px, py) : ctx.moveTo(px, py)); ctx.closePath();
  if (fill) { ctx.fillStyle = fill; ctx.fill(); }
  if (stroke) { ctx.strokeStyle = stroke; ctx.lineWidth = width || 1; ctx.stroke(); }
}
function vehicle(pose, colour) {
  const [x, y, yaw] = pose;
  polygon(rect(x, y, 4.8, 2.0, yaw), rgb(colour, 0.9), '#000', 0.5);
  const c = Math.cos(yaw), s = Math.sin(yaw), tip = toScreen(x + 2.4 * c, y + 2.4 * s), [cx, cy] = toScreen(x, y);
  ctx.beginPath(); ctx.moveTo(cx, cy); ctx.lineTo(tip[0], tip[1]);
  ctx.strokeStyle = '#fff'; ctx.lineWidth = 2; ctx.stroke();
}
function pairLines(f, pairs, stroke) {
  ctx.strokeStyle = rgb(stroke.color); ctx.lineWidth = stroke.width;
  ctx.setLineDash(stroke.dash ? [stroke.dash * view.scale, stroke.dash * view.scale] : []);
  for (const [e, c] of pairs) {
    const [ax, ay] = toScreen(...centre(f.ego[e])), [bx, by] = toScreen(...centre(f.after[c]));
    ctx.beginPath(); ctx.moveTo(ax, ay); ctx.lineTo(bx, by); ctx.stroke();
  }
  ctx.setLineDash([]);
}
function marks(f, pairs, stroke, width) {
  for (const [e, c] of pairs) for (const q of [f.ego[e], f.after[c]]) polygon(quad(q), null, rgb(stroke.color), width);
}
function sized() {
  const r = canvas.getBoundingClientRect();
  canvas.width = Math.max(200, Math.round(r.width)); canvas.height = Math.max(200, Math.round(r.height));
}
function fit() {
  let lo = [Infinity, Infinity], hi = [-Infinity, -Infinity];
  for (const f of frames) for (const b of [...f.ego.flat(), ...f.after.flat(), [0, 0]]) {
    lo = [Math.min(lo[0], b[0]), Math.min(lo[1], b[1])]; hi = [Math.max(hi[0], b[0]), Math.max(hi[1], b[1])];
  }
  const w = Math.max(hi[1] - lo[1], 10), h = Math.max(hi[0] - lo[0], 10);
  const scale = 0.9 * Math.min(canvas.width / w, canvas.height / h);
  view = {scale, ox: canvas.width / 2 + scale * (hi[1] + lo[1]) / 2,
          oy: canvas.height / 2 + scale * (hi[0] + lo[0]) / 2};
}
function draw() {
  const f = frames[index];
  ctx.clearRect(0, 0, canvas.width, canvas.height);
  for (const q of f.ego) polygon(quad(q), rgb(pal.ego), null);
  for (const q of f.after) polygon(quad(q), rgb(pal.cav), null);
  for (const q of f.before) polygon(quad(q), null, rgb(pal.before), 1.5);
  marks(f, f.missed, pal.missed, 2); marks(f, f.wrong, pal.wrong, 3);
  pairLines(f, f.missed, pal.missed); pairLines(f, f.wrong, pal.wrong); pairLines(f, f.right, pal.right);
  vehicle([0, 0, 0], pal.egoVehicle); vehicle(f.poseAfter, pal.cavVehicle);
  ctx.globalAlpha = 0.35; vehicle(f.poseBefore, pal.cavVehicle); ctx.globalAlpha = 1;
}
function cell(row, text, cls) { const td = row.insertCell(); td.textContent = text; if (cls) td.className = cls; }
function show(i) {
  index = (i + frames.length) % frames.length;
  const f = frames[index];
  slider.value = index;
  document.getElementById('frame-label').textContent = `frame ${f.frame} (${index + 1} / ${frames.length})`;
  document.getElementById('frame-title').textContent = `Frame ${f.frame}`;
  document.getElementById('agents').textContent = f.agents;
  const table = document.getElementById('metrics'); table.innerHTML = '';
  for (const [label, text] of f.table) {
    const row = table.insertRow(); cell(row, label);
    cell(row, text, label === 'result' ? (f.success ? 'success' : 'failed') : '');
  }
  draw();
}
function play() {
  if (timer) { clearInterval(timer); timer = null; } else { timer = setInterval(() => show(index + 1), 700); }
  document.getElementById('play').textContent = timer ? '❚❚ pause' : '▶ play';
}
document.getElementById('title').textContent =
  `${data.app} ${data.version} — recording of ${data.count} · dataset ${data.dataset}` +
  ` · exported ${data.exported}`;
for (const line of data.settings) {
  const div = document.createElement('div'); div.textContent = line; div.title = line;
  document.getElementById('settings').appendChild(div);
}
document.getElementById('legend').textContent = data.legend;
slider.max = frames.length - 1;
slider.addEventListener('input', () => show(Number(slider.value)));
document.getElementById('prev').addEventListener('click', () => show(index - 1));
document.getElementById('next').addEventListener('click', () => show(index + 1));
document.getElementById('play').addEventListener('click', play);
document.addEventListener('keydown', e => {
  if (e.key === 'ArrowLeft') show(index - 1);
  if (e.key === 'ArrowRight') show(index + 1);
});
canvas.addEventListener('wheel', e => {
  e.preventDefault();
  const r = canvas.getBoundingClientRect(), k = e.deltaY < 0 ? 1.15 : 1 / 1.15;
  const mx = (e.clientX - r.left) * canvas.width / r.width, my = (e.clientY - r.top) * canvas.height / r.height;
  view = {scale: view.scale * k, ox: mx + (view.ox - mx) * k, oy: my + (view.oy - my) * k}; draw();
}, {passive: false});
canvas.addEventListener('mousedown', e => { drag = [e.clientX, e.clientY]; });
window.addEventListener('mouseup', () => { drag = null; });
window.addEventListener('mousemove', e => {
  if (!drag) return;
  const r = canvas.getBoundingClientRect(), k = canvas.width / r.width;
  view.ox += (e.clientX - drag[0]) * k; view.oy += (e.clientY - drag[1]) * k; drag = [e.clientX, e.clientY]; draw();
});
canvas.addEventListener('dblclick', () => { fit(); draw(); });
window.addEventListener('resize', () => { sized(); fit(); draw(); });
sized(); fit(); show(0);
"""
