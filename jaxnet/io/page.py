"""net.html: a page of a run that any browser opens offline, one file: the net in 3D, turned with the mouse,
coloured by tension, and the run's figures beside it.

The 3D view is drawn by a small viewer of its own written into the page (about 10 kB of JavaScript on the
browser's 2D canvas), not by plotly: plotly's library is 4.8 MB, which every run's page would carry (it is
not a dependency of jaxnet's, only of its notebooks), and its 3D views need WebGL, which browsers without a GPU
(a headless one, a remote desktop) may not have. The 2D canvas draws everywhere, and the netting the way
net.png draws it (:mod:`jaxnet.io.plot`): the painter's algorithm (far triangles first) on an orthographic
projection, every triangle's U and V twines as lines coloured by their own tension over the grey netting, on
the same logarithmic scale with the same colours, cables by their bar tension, and what holds the net (fixings,
holds in some axes, floats and sinkers with their values in the legend). A choice colours the triangles instead
by one twine family at a time (U, V) or the larger of the two.

The page carries the modelled part's positions, triangles and twine lines, and its symmetry planes: the viewer
mirrors them to the whole net, as the pictures do. After drawing, the page sets ``data-triangles`` on its
``<html>`` element to the number of triangles drawn (diamond and hexagonal), and writes any script error into
``data-errors`` (what a test in a headless browser reads back).
"""

from __future__ import annotations

import html
import json
import pathlib

import numpy as np

#: colours of a colour map sampled for the page (its table, from matplotlib's map)
_SAMPLES = 64


def _table(name):
    """``_SAMPLES`` colours "#rrggbb" of matplotlib's colour map ``name``, from its bottom to its top."""
    import matplotlib

    rgba = matplotlib.colormaps[name](np.linspace(0.0, 1.0, _SAMPLES))
    return ["#%02x%02x%02x" % tuple(int(round(255 * c)) for c in row[:3]) for row in rgba]


def _rounded(values, extent):
    """``values`` (m) as a flat list rounded to a millionth of ``extent`` (m): enough for a picture, and the
    page's size is mostly its numbers."""
    decimals = max(0, int(6 - np.floor(np.log10(max(extent, 1e-12)))))
    return np.round(np.asarray(values, dtype=float).ravel(), decimals).tolist()


def page_data(scene, x, twine_tension=None, bar_tension=None, catch_front=None):
    """What the page's viewer draws, as a JSON-ready dict: positions x (N, 3) (m) of the modelled part, the
    symmetry planes that mirror it, the netting's triangles and twine lines (:func:`jaxnet.io.plot.twine_lines`)
    with their U and V tensions (N) and colour scale, the hexagonal netting, the cables with their bar tensions
    (N), the marks of what holds the net and the catch front's cut across the netting (``catch_front``: its
    position along the catch's axis, m; both already of the whole net), the current and the view's
    directions."""
    from jaxnet import figures, scene as scene_lib
    from jaxnet.io import plot

    x = np.asarray(x, dtype=float)
    net, bars, env = scene.netting, scene.bars, scene.environment
    whole = scene_lib.mirrored(scene, x)
    extent = float(np.ptp(whole.reshape(-1, 3), axis=0).max()) or 1.0
    data = {"points": _rounded(x, extent), "nodes": int(x.shape[0]),
            "planes": [[int(axis), float(at)] for axis, at in scene.symmetry_planes],
            "triangles": [], "twines": [], "tension": [], "hexagonal": [], "bars": [], "barTension": [],
            "front": []}
    if net is not None:
        tension = figures.twine_tensions(scene, x) if twine_tension is None else twine_tension
        tension = np.asarray(tension, dtype=float).reshape(-1, 2)
        scale = plot.twine_scale(tension)
        data.update(triangles=np.asarray(net.vertices).ravel().tolist(),
                    twines=_rounded(plot.twine_lines(x, np.asarray(net.vertices), net.uv), extent),
                    tension=np.round(tension.ravel(), 6).tolist(),
                    twineScale={"log": scale.__class__.__name__ == "LogNorm", "lo": float(scale.vmin),
                                "hi": float(scale.vmax), "ticks": plot.twine_ticks(scale),
                                "colours": _table(plot.TWINE_COLOURS)},
                    twineNote=plot.twine_note(scale))
    if scene.hexagonal is not None:
        data["hexagonal"] = np.asarray(scene.hexagonal.vertices).ravel().tolist()
    if bars is not None:
        tension = figures.bar_tensions(scene, x) if bar_tension is None else bar_tension
        tension = np.asarray(tension, dtype=float).ravel()
        scale = plot.bar_scale(tension)
        data.update(bars=np.asarray(bars.ends).ravel().tolist(), barTension=np.round(tension, 6).tolist(),
                    barScale={"log": False, "lo": float(scale.vmin), "hi": float(scale.vmax),
                              "colours": _table(plot.BAR_COLOURS)})
    if scene.catch is not None and catch_front is not None and net is not None:
        cut = plot.front_cut(x, np.asarray(net.vertices), np.asarray(scene.catch.axis, dtype=float),
                             float(catch_front))
        data["front"] = _rounded(scene_lib.mirrored(scene, cut.reshape(-1, 3)), extent)
    data["marks"] = [{"kind": m.gid, "label": m.label, "points": _rounded(m.points, extent), "texts": list(m.texts)}
                     for m in plot.marks(scene, whole)]
    right, vertical, toward = plot.oblique_directions(scene)
    along, across, up = plot.view_directions(scene)
    direction = np.asarray(env.current_direction, dtype=float)
    data.update(view={"right": right.tolist(), "vertical": vertical.tolist(), "up": up.tolist()},
                current={"speed": float(env.current_speed),
                         "direction": (direction / (np.linalg.norm(direction) or 1.0)).tolist(),
                         "heading": plot.heading(along, up)})
    return data


#: result.json's figures the page lists first, in this order (the others follow under "all figures")
_MAIN = ("converged", "reason", "iterations", "residual_N", "max_twine_tension_N", "max_bar_tension_N",
         "reaction_N", "load_N", "water_N", "forces_N", "weight_and_buoyancy_by_carrier_N", "enclosed_volume_m3",
         "catch", "panel_catches", "whole_net", "modelled_part", "n_nodes", "n_triangles", "n_bars", "n_dof",
         "bounding_box_m")


def _number(value):
    return f"{value:.4g}" if isinstance(value, float) else html.escape(str(value))


def _shown(value):
    """A figure in words: a number to 4 digits, a vector [x, y, z] with its magnitude, a list, a word."""
    if isinstance(value, bool) or value is None:
        return html.escape(str(value).lower() if isinstance(value, bool) else "null")
    if isinstance(value, (int, float)):
        return _number(value)
    if isinstance(value, list) and len(value) == 3 and all(isinstance(v, (int, float)) for v in value):
        norm = float(np.linalg.norm(np.asarray(value, dtype=float)))
        return f"[{', '.join(_number(float(v)) for v in value)}] <span class=m>|{norm:.4g}|</span>"
    if isinstance(value, list):
        return "[" + ", ".join(_shown(v) for v in value) + "]"
    return html.escape(str(value))


def _rows(result):
    """The figures table's rows (HTML) of ``result`` (figures.summary's dict): the main figures first, a nested
    dict's entries under its name ("forces_N.drag_netting_N")."""
    about = result.get("about", {})
    rows = []

    def add(key, value, depth):
        title = f' title="{html.escape(about[key])}"' if key in about else ""
        name = html.escape(key.split(".")[-1])
        if isinstance(value, dict):
            rows.append(f'<tr class="d{depth}"><th colspan=2{title}>{name}</th></tr>')
            for k, v in value.items():
                add(f"{key}.{k}", v, depth + 1)
        elif isinstance(value, list) and value and isinstance(value[0], dict):
            for k, v in enumerate(value):
                add(f"{key}.{k}", v, depth)
        else:
            rows.append(f'<tr class="d{depth}"><th{title}>{name}</th><td>{_shown(value)}</td></tr>')

    for key in _MAIN:
        if key in result:
            add(key, result[key], 0)
    return "\n".join(rows)


def write_html(path, scene, x, result=None, title=None, *, twine_tension=None, bar_tension=None):
    """Write net.html to ``path``: the net at positions x (N, 3) (m) in 3D, coloured by tension (twine_tension
    (E, 2) and bar_tension (B,) in N, by default :mod:`jaxnet.figures`' at x), and beside it the run's figures
    ``result`` (the dict of :func:`jaxnet.figures.summary`, result.json's: converged, iterations, reactions,
    forces by group, largest tensions, catch...; none listed if None; its catch front drawn), under ``title``.
    One file, no network: its script and data are in it. Returns the path."""
    path = pathlib.Path(path)
    front = (result or {}).get("catch", {}).get("front_m")
    data = page_data(scene, x, twine_tension, bar_tension, front)
    figures_html = ""
    if result:
        everything = html.escape(json.dumps(result, indent=1))
        figures_html = (f"<h2>figures</h2><table>{_rows(result)}</table>"
                        f"<details><summary>all figures (result.json)</summary><pre>{everything}</pre></details>")
    payload = json.dumps(data, separators=(",", ":")).replace("</", "<\\/")
    name = html.escape(title or "jaxnet: the net")
    page = (_PAGE.replace("@TITLE@", name).replace("@FIGURES@", figures_html)
            .replace("@DATA@", payload).replace("@SCRIPT@", _SCRIPT))
    path.write_text(page, encoding="utf-8")
    return path


_PAGE = """<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>@TITLE@</title>
<meta name="viewport" content="width=device-width, initial-scale=1">
<style>
body{margin:0;font:13px/1.35 system-ui,sans-serif;color:#222;display:flex;height:100vh}
#view{flex:1 1 auto;position:relative;min-width:300px}
#net{width:100%;height:100%;display:block;cursor:grab;touch-action:none}
#side{flex:0 0 400px;overflow-y:auto;overflow-x:hidden;padding:8px 14px;border-left:1px solid #ccc;background:#fafafa}
h1{font-size:15px;margin:4px 0 8px} h2{font-size:13px;margin:12px 0 4px}
table{border-collapse:collapse;width:100%} th,td{text-align:left;padding:1px 4px;vertical-align:top}
th{font-weight:normal;color:#555;white-space:nowrap} td{font-variant-numeric:tabular-nums}
tr.d1 th{padding-left:14px} tr.d2 th{padding-left:26px} tr.d3 th{padding-left:38px}
.m{color:#777} pre{font-size:11px;white-space:pre-wrap} .note{color:#555;font-size:12px}
.bar{height:12px;border:1px solid #999;margin:3px 22px 0}
.ticks{position:relative;height:15px;font-size:11px;margin:0 22px}
.ticks span{position:absolute;transform:translateX(-50%)} .legend div{margin:2px 0}
.sym{display:inline-block;width:16px;text-align:center}
#hint{position:absolute;left:8px;bottom:6px;color:#777;font-size:11px}
</style></head>
<body>
<div id="view"><canvas id="net"></canvas>
<div id="hint">drag: turn &middot; wheel: zoom &middot; double-click: back</div></div>
<div id="side"><h1>@TITLE@</h1>
<div id="colouring"></div>
<div id="scales"></div>
<div class="legend" id="legend"></div>
@FIGURES@
</div>
<script type="application/json" id="net-data">@DATA@</script>
<script>@SCRIPT@</script>
</body></html>
"""

_SCRIPT = r"""
"use strict";
(function () {
const root = document.documentElement;
const errors = [];
function report(message) {
  errors.push(String(message));
  root.setAttribute("data-errors", errors.join(" | "));
}
window.addEventListener("error", e => report(e.message || "failed to load " +
  ((e.target && (e.target.src || e.target.href)) || "a resource")), true);
window.addEventListener("unhandledrejection", e => report("unhandled rejection: " + e.reason));
const consoleError = console.error.bind(console);
console.error = function () { report(Array.from(arguments).join(" ")); consoleError.apply(null, arguments); };
function safe(f) { try { f(); } catch (err) { report(err && err.stack ? err.stack : err); } }

const D = JSON.parse(document.getElementById("net-data").textContent);
const canvas = document.getElementById("net"), g = canvas.getContext("2d");

// the whole net: the modelled part and its images in the symmetry planes, copy after copy
let copies = [D.points], lineCopies = [D.twines];
for (const [axis, at] of D.planes) {
  const mirror = a => a.map((v, k) => (k % 3 === axis ? 2 * at - v : v));
  copies = copies.concat(copies.map(mirror));
  lineCopies = lineCopies.concat(lineCopies.map(mirror));
}
const P = [].concat(...copies), L = [].concat(...lineCopies), C = copies.length, n = D.nodes;
const E = D.triangles.length / 3, H = D.hexagonal.length / 3, B = D.bars.length / 2;

// colours: the pictures' maps and scales
function level(v, scale) {   // 0 at the scale's bottom, 1 at its top
  const s = scale.log ? Math.log(Math.max(v, scale.lo) / scale.lo) / Math.log(scale.hi / scale.lo)
                      : (v - scale.lo) / (scale.hi - scale.lo);
  return Math.min(1, Math.max(0, isFinite(s) ? s : 0));
}
const colour = (v, scale) => scale.colours[Math.round(level(v, scale) * (scale.colours.length - 1))];

// the view: orthographic, the screen's axes right and vertical, depth along toward = vertical x right
const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
const unit = a => { const l = Math.hypot(a[0], a[1], a[2]) || 1; return [a[0] / l, a[1] / l, a[2] / l]; };
function turn(v, axis, angle) {   // Rodrigues' rotation of v about the unit axis
  const c = Math.cos(angle), s = Math.sin(angle), k = cross(axis, v), d = dot(axis, v);
  return [0, 1, 2].map(i => v[i] * c + k[i] * s + axis[i] * d * (1 - c));
}
const lo = [Infinity, Infinity, Infinity], hi = [-Infinity, -Infinity, -Infinity];
for (let i = 0; i < P.length; i++) { lo[i % 3] = Math.min(lo[i % 3], P[i]); hi[i % 3] = Math.max(hi[i % 3], P[i]); }
const centre = [0, 1, 2].map(i => (lo[i] + hi[i]) / 2);
const radius = Math.max(1e-9, Math.hypot(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]) / 2);
let right = D.view.right.slice(), vertical = D.view.vertical.slice(), zoom = 1, colouring = "twines";
let w = 600, h = 400, scale = 1, toward = cross(vertical, right);
function screen(A, k) {   // the point A[k..k+2] (m) on the screen (pixels), and its depth (m)
  const x = A[k] - centre[0], y = A[k + 1] - centre[1], z = A[k + 2] - centre[2];
  return [w / 2 + scale * (x * right[0] + y * right[1] + z * right[2]),
          h / 2 - scale * (x * vertical[0] + y * vertical[1] + z * vertical[2]),
          x * toward[0] + y * toward[1] + z * toward[2]];
}
function shape(points, close) {
  g.beginPath();
  g.moveTo(points[0][0], points[0][1]);
  for (let i = 1; i < points.length; i++) g.lineTo(points[i][0], points[i][1]);
  if (close) g.closePath();
}
function mark(kind, x, y) {   // the pictures' marks of what holds the net
  const r = kind === "fixed nodes" ? 2.5 : 4;
  g.beginPath();
  if (kind === "held nodes") { g.moveTo(x, y - r); g.lineTo(x + r, y); g.lineTo(x, y + r); g.lineTo(x - r, y); }
  else if (kind === "floats" || kind === "sinkers") {
    const s = kind === "floats" ? -1 : 1;
    g.moveTo(x, y + s * r); g.lineTo(x + r, y - s * r); g.lineTo(x - r, y - s * r);
  } else g.arc(x, y, r, 0, 2 * Math.PI);
  g.closePath();
}
const MARKS = {"fixed nodes": ["none", "red"], "held nodes": ["none", "darkorange"], "floats": ["gold", "black"],
               "sinkers": ["#404040", "black"]};

function draw() {
  const ratio = window.devicePixelRatio || 1;
  w = canvas.clientWidth || 600; h = canvas.clientHeight || 400;
  if (canvas.width !== Math.round(w * ratio) || canvas.height !== Math.round(h * ratio)) {
    canvas.width = Math.round(w * ratio); canvas.height = Math.round(h * ratio);
  }
  g.setTransform(ratio, 0, 0, ratio, 0, 0);
  g.fillStyle = "#fff"; g.fillRect(0, 0, w, h);
  toward = cross(vertical, right); scale = zoom * 0.46 * Math.min(w, h) / radius;
  const S = [];
  for (let k = 0; k < P.length; k += 3) S.push(screen(P, k));
  // every triangle (with its twines), hexagonal triangle and bar, far to near (the painter's algorithm)
  const items = [];
  for (let c = 0; c < C; c++) {
    for (let e = 0; e < E; e++) {
      const v = [0, 1, 2].map(i => c * n + D.triangles[3 * e + i]);
      items.push({depth: (S[v[0]][2] + S[v[1]][2] + S[v[2]][2]) / 3, kind: 0, c: c, e: e, v: v});
    }
    for (let e = 0; e < H; e++) {
      const v = [0, 1, 2].map(i => c * n + D.hexagonal[3 * e + i]);
      items.push({depth: (S[v[0]][2] + S[v[1]][2] + S[v[2]][2]) / 3, kind: 1, c: c, e: e, v: v});
    }
    for (let e = 0; e < B; e++) {
      const v = [0, 1].map(i => c * n + D.bars[2 * e + i]);
      items.push({depth: (S[v[0]][2] + S[v[1]][2]) / 2, kind: 2, c: c, e: e, v: v});
    }
  }
  items.sort((p, q) => q.depth - p.depth);
  let triangles = 0;
  g.lineJoin = "round";
  for (const it of items) {
    const corners = it.v.map(i => S[i]);
    if (it.kind === 2) {
      g.strokeStyle = colour(D.barTension[it.e], D.barScale); g.lineWidth = 2.5;
      shape(corners, false); g.stroke();
      continue;
    }
    let fill = "#bbbbbb";
    triangles++;
    if (it.kind === 0) {
      const u = D.tension[2 * it.e], v = D.tension[2 * it.e + 1];
      if (colouring === "twines") {   // grey, the brighter the more it faces the viewer
        const a = it.v.map(i => [P[3 * i], P[3 * i + 1], P[3 * i + 2]]);
        const normal = unit(cross([0, 1, 2].map(i => a[1][i] - a[0][i]), [0, 1, 2].map(i => a[2][i] - a[0][i])));
        const grey = Math.round(255 * (0.80 + 0.17 * Math.abs(dot(normal, toward))));
        fill = "rgb(" + grey + "," + grey + "," + grey + ")";
      } else {
        fill = colour(colouring === "U" ? u : colouring === "V" ? v : Math.max(u, v), D.twineScale);
      }
    }
    g.fillStyle = fill; g.strokeStyle = fill; g.lineWidth = 0.5;
    shape(corners, true); g.fill(); g.stroke();
    if (it.kind === 0 && colouring === "twines") {
      for (let f = 0; f < 2; f++) {
        const k = 12 * (it.c * E + it.e) + 6 * f, t = D.tension[2 * it.e + f];
        g.strokeStyle = colour(t, D.twineScale); g.lineWidth = 0.7 + 1.3 * level(t, D.twineScale);
        shape([screen(L, k), screen(L, k + 3)], false); g.stroke();
      }
    }
  }
  // the catch front across the netting, then what holds the net, over the net, with values where the pictures
  // write them
  g.strokeStyle = "magenta"; g.lineWidth = 1.5;
  for (let k = 0; k < D.front.length; k += 6) {
    shape([screen(D.front, k), screen(D.front, k + 3)], false); g.stroke();
  }
  g.font = "10px sans-serif";
  for (const m of D.marks) {
    const [face, edge] = MARKS[m.kind] || ["none", "black"];
    for (let i = 0; i < m.points.length; i += 3) {
      const [x, y] = screen(m.points, i);
      mark(m.kind, x, y);
      g.fillStyle = face; g.strokeStyle = edge; g.lineWidth = 1;
      if (face !== "none") g.fill();
      g.stroke();
      if (m.texts.length) { g.fillStyle = "#222"; g.fillText(m.texts[i / 3], x + 5, y - 4); }
    }
  }
  // the current, and the coordinate axes' directions in the corner
  g.strokeStyle = g.fillStyle = "#1f77b4"; g.lineWidth = 2; g.font = "12px sans-serif";
  if (D.current.speed > 0) {
    const c = D.current.direction, sr = dot(c, right), sv = dot(c, vertical), l = Math.hypot(sr, sv);
    g.fillText("current " + D.current.speed.toPrecision(3) + " m/s, heading " + D.current.heading, 14, 18);
    if (l > 0.05) {
      const ux = sr / l, uy = -sv / l, x = 40 + 18 * ux, y = 40 + 18 * uy;
      shape([[40 - 18 * ux, 40 - 18 * uy], [x, y]], false); g.stroke();
      shape([[x, y], [x - 8 * ux - 4 * uy, y - 8 * uy + 4 * ux], [x - 8 * ux + 4 * uy, y - 8 * uy - 4 * ux]], true);
      g.fill();
    }
  }
  g.font = "11px sans-serif"; g.lineWidth = 1; g.strokeStyle = g.fillStyle = "#555";
  ["x", "y", "z"].forEach((name, i) => {
    const e = [0, 0, 0]; e[i] = 1;
    const dx = 22 * dot(e, right), dy = -22 * dot(e, vertical), x = w - 40, y = h - 40;
    shape([[x, y], [x + dx, y + dy]], false); g.stroke();
    g.fillText(name, x + 1.25 * dx - 3, y + 1.25 * dy + 4);
  });
  root.setAttribute("data-triangles", String(triangles));
}

let pending = false;
function redraw() {
  if (!pending) { pending = true; requestAnimationFrame(() => { pending = false; safe(draw); }); }
}
// a drag across turns the net about the vertical, a drag up or down tilts it; the wheel zooms
let dragging = null;
canvas.addEventListener("pointerdown", e => {
  dragging = [e.clientX, e.clientY]; canvas.setPointerCapture(e.pointerId); canvas.style.cursor = "grabbing";
});
canvas.addEventListener("pointerup", () => { dragging = null; canvas.style.cursor = "grab"; });
canvas.addEventListener("pointermove", e => {
  if (!dragging) return;
  const dx = e.clientX - dragging[0], dy = e.clientY - dragging[1], up = unit(D.view.up);
  dragging = [e.clientX, e.clientY];
  right = unit(turn(right, up, dx * 0.01)); vertical = unit(turn(vertical, up, dx * 0.01));
  vertical = unit(turn(vertical, right, dy * 0.01));
  right = unit(cross(cross(vertical, right), vertical));   // square to vertical again
  redraw();
});
canvas.addEventListener("wheel", e => { e.preventDefault(); zoom *= Math.exp(-e.deltaY * 0.001); redraw(); },
                        {passive: false});
canvas.addEventListener("dblclick", () => {
  right = D.view.right.slice(); vertical = D.view.vertical.slice(); zoom = 1; redraw();
});
window.addEventListener("resize", redraw);

// the side panel: how the netting is coloured, the colour scales, what holds the net
function scaleBar(title, scale, ticks) {
  const div = document.createElement("div");
  const stops = scale.colours.map((c, i) => c + " " + (100 * i / (scale.colours.length - 1)).toFixed(1) + "%");
  div.innerHTML = "<h2></h2><div class=bar></div><div class=ticks></div>";
  div.querySelector("h2").textContent = title;
  div.querySelector(".bar").style.background = "linear-gradient(to right," + stops.join(",") + ")";
  let digits = 3;   // enough digits that neighbouring ticks read apart
  while (digits < 10 && new Set(ticks.map(t => t.toPrecision(digits))).size < ticks.length) digits++;
  for (const t of ticks) {
    const span = document.createElement("span");
    span.textContent = Number(t.toPrecision(digits)).toString();
    span.style.left = (100 * level(t, scale)) + "%";
    div.querySelector(".ticks").appendChild(span);
  }
  return div;
}
const SYMBOLS = {"fixed nodes": ["#9675", "red"], "held nodes": ["#9671", "darkorange"],
                 "floats": ["#9650", "goldenrod"], "sinkers": ["#9660", "#404040"]};
safe(() => {
  const scales = document.getElementById("scales");
  if (E) {
    const chooser = document.getElementById("colouring");
    chooser.innerHTML = "<h2>netting</h2><div class=note></div>";
    chooser.querySelector(".note").textContent = D.twineNote;
    const choices = [["twines", "U and V twines drawn apart"], ["larger", "triangles: the larger of U and V"],
                     ["U", "triangles: U twines"], ["V", "triangles: V twines"]];
    for (const [key, words] of choices) {
      const label = document.createElement("label"), input = document.createElement("input");
      input.type = "radio"; input.name = "colouring"; input.value = key; input.checked = key === colouring;
      input.addEventListener("change", () => { colouring = key; redraw(); });
      label.appendChild(input); label.appendChild(document.createTextNode(" " + words));
      label.style.display = "block";
      chooser.appendChild(label);
    }
    const title = "twine tension (N)" + (D.twineScale.log ? ", log scale" : "");
    scales.appendChild(scaleBar(title, D.twineScale, D.twineScale.ticks));
  }
  if (B) {
    const s = D.barScale;
    scales.appendChild(scaleBar("bar tension (N)", s, [0, 0.25, 0.5, 0.75, 1].map(f => s.lo + f * (s.hi - s.lo))));
  }
  const legend = document.getElementById("legend");
  if (D.marks.length) legend.innerHTML = "<h2>what holds the net</h2>";
  for (const m of D.marks) {
    const div = document.createElement("div"), [code, tint] = SYMBOLS[m.kind] || ["#9679", "black"];
    div.innerHTML = "<span class=sym style='color:" + tint + "'>&" + code + ";</span>";
    div.appendChild(document.createTextNode(" " + m.label));
    legend.appendChild(div);
  }
});
safe(draw);
})();
"""
