"""What the scene's colours and markers mean, and the mission clock, for a reader of the scene.

A `LegendEntry` names one layer or marker: its colour swatch (CSS), how it looks in words and
what it shows. `Scene.add_legend` collects them as layers are drawn. Meshcat has no text
overlay, so the legend reaches the two views differently:
- the standalone recording (`Scene.write_html`): `overlay_html` adds positioned panels to
  Meshcat's static page: the legend (bottom left; folded in windows under 800 x 600 px, a
  click opens it), one row per layer with a checkbox bound to the layer's visibility in the
  viewer (the rows' `data-visible` follow the viewer, also when a layer is toggled in
  Meshcat's own scene tree), and the mission clock (top left): the simulated time read from
  the animation's time (`viewer.animator.time` times the playback speed) and the leg flying
  then;
- the live view (`drake-auv run --meshcat`): read-only entries in Meshcat's control panel,
  one button per entry named "look: name" (a click does nothing), and the clock as a slider
  the mission moves (`mission.live_view`).
"""

from __future__ import annotations

import html
import json
from dataclasses import dataclass

import numpy as np

OVERLAY_ID = "drake_auv-overlay"
LEGEND_ID = "drake_auv-legend"
CLOCK_ID = "drake_auv-clock"


@dataclass(frozen=True)
class LegendEntry:
    """One row of the legend: `name` (short), `look` (its shape and colour in words, the live
    view's label), `meaning`, `swatch` (a CSS background) and `layer` (its scene-tree path,
    toggled by the row's checkbox; None: not a layer of its own)."""

    name: str
    look: str
    meaning: str
    swatch: str
    layer: str | None = None

    @property
    def label(self) -> str:
        """The live view's control-panel label."""
        return f"{self.look}: {self.name}"


def css_colour(rgb) -> str:
    """CSS `rgb(...)` of a colour given as 3 or 4 numbers in [0, 1] (or an `Rgba`)."""
    if hasattr(rgb, "r"):
        rgb = (rgb.r(), rgb.g(), rgb.b())
    r, g, b = (int(round(255 * float(c))) for c in tuple(rgb)[:3])
    return f"rgb({r},{g},{b})"


def swatch(colours, smooth: bool = True) -> str:
    """A CSS background, left to right through `colours` ((n, 3) in [0, 1]): a gradient, or
    (not `smooth`) n bands of equal width."""
    colours = [css_colour(c) for c in np.atleast_2d(np.asarray(colours, dtype=float))]
    if smooth:
        stops = colours if len(colours) > 1 else colours * 2
        parts = [f"{c} {100 * i / (len(stops) - 1):.0f}%" for i, c in enumerate(stops)]
    else:
        n = len(colours)
        parts = [f"{c} {100 * i / n:.1f}% {100 * (i + 1) / n:.1f}%" for i, c in enumerate(colours)]
    return f"linear-gradient(90deg,{','.join(parts)})"


_STYLE = f"""
#{OVERLAY_ID} .panel {{position:fixed;left:8px;z-index:10;background:rgba(20,22,28,0.78);
 color:#eee;font:12px/1.3 sans-serif;padding:5px 8px;border-radius:4px;max-width:390px}}
#{CLOCK_ID} {{top:8px;font-size:14px}}
#{LEGEND_ID} {{bottom:8px}}
#{LEGEND_ID} summary {{cursor:pointer;color:#aaa}}
#{LEGEND_ID} label {{display:flex;align-items:center;gap:5px;margin:1px 0;cursor:pointer}}
#{LEGEND_ID} .sw {{flex:0 0 34px;height:10px;border:1px solid #888}}
"""

_SCRIPT = """
(function () {
  const legs = %(legs)s, speed = %(speed)s;
  const split = (path) => path.split("/").filter((s) => s.length);
  const rows = document.querySelectorAll("#%(legend)s [data-layer]");
  rows.forEach((row) => {
    row.querySelector("input").addEventListener("change", (event) => {
      viewer.set_property(split(row.dataset.layer), "visible", event.target.checked);
      viewer.set_dirty();
    });
  });
  const legend = document.getElementById("%(legend)s");
  if (legend !== null && (innerWidth < 800 || innerHeight < 600)) legend.open = false;
  const clock = document.getElementById("%(clock)s");
  function tick() {
    rows.forEach((row) => {
      const visible = viewer.scene_tree.find(split(row.dataset.layer)).object.visible;
      row.dataset.visible = String(visible);
      row.querySelector("input").checked = visible;
    });
    if (clock !== null) {
      const t = (viewer.animator.time || 0) * speed;
      let leg = "";
      for (const [start, label] of legs) { if (start <= t + 1e-9) leg = label; }
      clock.dataset.time = t.toFixed(1);
      clock.querySelector(".time").textContent = "mission time " + t.toFixed(0) + " s";
      clock.querySelector(".speed").textContent = " (played " + speed + "x faster)";
      clock.querySelector(".leg").textContent = leg;
    }
    requestAnimationFrame(tick);
  }
  requestAnimationFrame(tick);
})();
"""


def overlay_html(entries, speed: float | None = None, legs=()) -> str:
    """The legend of `entries` and, with `speed` (the recording's playback speed: simulated
    seconds per second of animation), the mission clock showing the label of the last of
    `legs` ((start s, label), by start) begun; HTML to insert into Meshcat's static page."""
    rows = []
    for entry in entries:
        layer = "" if entry.layer is None else \
            f' data-layer="{html.escape(entry.layer)}" data-visible="true"'
        box = '<input type="checkbox" checked>' if entry.layer is not None else ""
        rows.append(f'<label{layer}>{box}<span class="sw" style="background:'
                    f'{html.escape(entry.swatch)}"></span><span><b>{html.escape(entry.name)}'
                    f'</b> {html.escape(entry.meaning)}</span></label>')
    clock = "" if speed is None else (
        f'<div id="{CLOCK_ID}" class="panel" data-time="0"><b class="time">mission time 0 s'
        f'</b><span class="speed"></span><br><span class="leg"></span></div>')
    script = _SCRIPT % dict(legs=json.dumps([[float(s), str(label)] for s, label in legs]),
                            speed=json.dumps(float(speed or 0.0)), legend=LEGEND_ID,
                            clock=CLOCK_ID)
    legend = "" if not rows else (
        f'<details id="{LEGEND_ID}" class="panel" open><summary>legend: tick a layer to show '
        f'it; the animation is under Open Controls</summary>{"".join(rows)}</details>')
    return (f'<div id="{OVERLAY_ID}"><style>{_STYLE}</style>{clock}{legend}</div>'
            f'<script>{script}</script>')


def with_overlay(page: str, overlay: str) -> str:
    """Meshcat's static `page` with `overlay` inserted at the end of its body (after the
    script that creates the viewer)."""
    end = page.rfind("</body>")
    if end < 0:
        raise ValueError("Meshcat's static page has no </body>: cannot add the legend")
    return page[:end] + overlay + "\n" + page[end:]
