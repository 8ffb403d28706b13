"""A mission's operating envelope: the current (speed x direction) in which no seed touched.

The grid is `--speeds A:B:STEP` (A, A + STEP, ..., up to B included) x `--directions N`
(towards 0, 360/N, ... degrees, clockwise from north) x `--seeds`; speed 0 is flown once per
seed (a still mean current has no direction). Each run is the mission with
`ocean.current.speed_mps` and `ocean.current.towards_deg` set (a mission without a sea gets
still water plus that mean current; one with a sea keeps its tides, turbulence, waves and
file), flown by the campaign machinery (`run_task` on Dask, rows written as they finish).

The verdict (`envelope_verdict`, pure): per direction, the highest tested speed such that
every run at it and at every slower speed (still water included) ended without contact; a
contact, a failed run or a missing cell stops the climb there. The mission's envelope is the
least of these over the directions: the highest current, from every direction, at which no
seed touched.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from drake_auv.campaign.grid import CampaignRun, check_run_count, expand_runs
from drake_auv.campaign.task import TIMING, metrics_row
from drake_auv.mission.config import MissionFileError
from drake_auv.ocean.current import MAX_CURRENT_MPS
from drake_auv.output_files import replacing, write_json, write_text

SPEED_KEY, TOWARDS_KEY = "ocean.current.speed_mps", "ocean.current.towards_deg"
KEYS = ("speed_mps", "towards_deg")  # the envelope's varied values, as envelope.csv names them
MAX_SPEEDS = 100
MAX_DIRECTIONS = 360  # one degree apart
OCEAN_METRICS = ("tracking_error_p95_m", "thrust_saturation_share_max", "current_mean_mps",
                 "current_max_mps", "navigation_current_drift_m")
COLUMNS = ("speed_mps", "towards_deg", "seed", "contact", "min_clearance_m",
           "coverage_multibeam", "coverage_camera", *OCEAN_METRICS, "status",
           "distance_mean_m", "distance_min_m", "completed", "aborted", "responses",
           "first_response_s", "sim_s", *TIMING, "error")


def parse_speeds(text: str) -> list[str]:
    """`A:B:STEP` -> the speed texts A, A + STEP, ..., B (B included when on the grid), m/s;
    ValueError (one line) unless 0 <= A <= B <= 5 m/s, STEP > 0 and at most `MAX_SPEEDS`."""
    allowed = (f"A:B:STEP in m/s with 0 <= A <= B <= {MAX_CURRENT_MPS:g} and STEP > 0, at "
               f"most {MAX_SPEEDS} speeds, e.g. 0:0.6:0.1")
    try:
        a, b, step = (float(part) for part in text.split(":"))
    except ValueError:
        raise ValueError(f"--speeds: {text!r} is not A:B:STEP; allowed: {allowed}") from None
    if not all(map(math.isfinite, (a, b, step))) or not 0 <= a <= b <= MAX_CURRENT_MPS \
            or step <= 0:
        raise ValueError(f"--speeds: {text!r} is out of range; allowed: {allowed}")
    count = math.floor((b - a) / step + 1e-9) + 1
    if count > MAX_SPEEDS:
        raise ValueError(f"--speeds: {text!r} gives {count} speeds; allowed: {allowed}")
    return [f"{round(a + k * step, 6):g}" for k in range(count)]


def parse_directions(count: int) -> list[str]:
    """N -> the direction texts towards 0, 360/N, ... degrees (clockwise from north);
    ValueError unless 1 <= N <= `MAX_DIRECTIONS`."""
    if not 1 <= count <= MAX_DIRECTIONS:
        raise ValueError(f"--directions: {count} is out of range; allowed: an integer in "
                         f"[1, {MAX_DIRECTIONS}] (directions evenly spaced from north)")
    return [f"{round(360.0 * k / count, 4):g}" for k in range(count)]


def envelope_runs(mission, speeds, directions, seeds, overrides=()) -> list[CampaignRun]:
    """Every run of the grid (the texts of `parse_speeds` and `parse_directions`), validated
    (`MissionFileError` names the first bad value); a run's values are (speed_mps,
    towards_deg). Speed 0 is one run per seed, towards 0."""
    taken = [o for o in overrides if o.partition("=")[0].strip() in (SPEED_KEY, TOWARDS_KEY)]
    if taken:
        raise ValueError(f"--set {taken[0]}: the mean current is the envelope's grid; allowed: "
                         "--speeds and --directions (--set any other key)")
    cells = [(speed, towards) for speed in speeds
             for towards in (["0"] if float(speed) == 0 else directions)]
    check_run_count(len(cells) * len(seeds), "--speeds x --directions x --seeds")
    runs = []
    for speed, towards in cells:
        vary = [(SPEED_KEY, [speed]), (TOWARDS_KEY, [towards])]
        try:
            expanded = expand_runs(mission, seeds, vary, overrides)
        except MissionFileError as err:
            label = (f"{err.label.replace(' (--vary)', '')} (current {speed} m/s towards "
                     f"{towards} deg)")
            raise MissionFileError(label, err.where, err.what, err.allowed) from None
        runs += [CampaignRun(run.seed, tuple(zip(KEYS, (speed, towards))), run.mission)
                 for run in expanded]
    return runs


def envelope_row(summary: dict) -> dict:
    """The campaign's metrics of a report's `summarise` dict plus the sea's cost: tracking
    error p95, the largest thrust saturation share, the current met, navigation drift."""
    ocean = summary.get("ocean") or {}
    return {**metrics_row(summary), **{k: ocean.get(k) for k in OCEAN_METRICS}}


def _number(value) -> float:
    return math.nan if value in (None, "") else float(value)


def _rows(rows) -> list[dict]:
    """Rows (text as read from envelope.csv, or values) as numbers and booleans."""
    return [dict(speed=float(r["speed_mps"]), towards=float(r["towards_deg"]),
                 seed=int(r["seed"]), ok=r["status"] == "ok",
                 contact=str(r.get("contact")) == "True",
                 clearance=_number(r.get("min_clearance_m")),
                 coverage=_number(r.get("coverage_multibeam"))) for r in rows]


def _cell(rows: list[dict]) -> dict:
    ok = [r for r in rows if r["ok"]]
    contacts = sum(r["contact"] for r in ok)
    state = ("missing" if not rows else "contact" if contacts else
             "failed" if len(ok) < len(rows) else "clear")
    clearance = [r["clearance"] for r in ok if math.isfinite(r["clearance"])]
    coverage = [r["coverage"] for r in ok if math.isfinite(r["coverage"])]
    return dict(runs=len(rows), failed=len(rows) - len(ok), contacts=contacts, state=state,
                contact_rate=contacts / len(ok) if ok else None,
                least_clearance_m=min(clearance) if clearance else None,
                coverage_multibeam_median=float(np.median(coverage)) if coverage else None)


def envelope_verdict(rows) -> dict:
    """The envelope of result rows (columns `speed_mps, towards_deg, seed, status, contact,
    min_clearance_m, coverage_multibeam`): `directions` (per direction towards: `safe_mps`,
    the highest speed with no contact at it and below, None when even the slowest touched;
    `stop_mps` and `stop` ("contact", "failed" or "missing"), where the climb stopped, None
    when it reached the top speed), `safe_mps` (the least over directions), `worst` (the
    directions that give it), `speeds`, `seeds`, and `cells` (per speed and direction: runs,
    contacts, contact rate, least clearance, median multibeam coverage)."""
    rows = _rows(rows)
    speeds = sorted({r["speed"] for r in rows})
    directions = sorted({r["towards"] for r in rows if r["speed"] > 0})
    still = [r for r in rows if r["speed"] == 0]
    cells = {(s, d): _cell([r for r in rows if r["speed"] == s and r["towards"] == d])
             for s in speeds if s > 0 for d in directions}
    if still:
        cells.update({(0.0, d): _cell(still) for d in directions or [0.0]})
    per_direction = []
    for d in directions or [0.0]:
        safe = stop = stop_at = None
        for s in speeds:
            state = cells[(s, d)]["state"]
            if state != "clear":
                stop, stop_at = state, s
                break
            safe = s
        per_direction.append(dict(towards_deg=d, safe_mps=safe, stop_mps=stop_at, stop=stop))
    safes = [p["safe_mps"] for p in per_direction]
    safe = None if None in safes else min(safes)
    return dict(
        safe_mps=safe, worst=[p["towards_deg"] for p in per_direction if p["safe_mps"] == safe],
        directions=per_direction, speeds=speeds, seeds=sorted({r["seed"] for r in rows}),
        cells=[dict(speed_mps=s, towards_deg=d, **c) for (s, d), c in sorted(cells.items())])


STOP_WORDS = dict(contact="contacts begin at", failed="a run failed at", missing="no runs at")


def verdict_line(mission: str, verdict: dict) -> str:
    """The verdict in one line, e.g. `breakwater: no contact up to 0.3 m/s from every direction
    (...); per direction (towards deg: m/s) 0: 0.3, 90: >= 0.6, ...`."""
    seeds = len(verdict["seeds"])
    per = verdict["directions"]
    worst = [p for p in per if p["safe_mps"] == verdict["safe_mps"] and p["stop"] is not None]
    first = min(worst, key=lambda p: p["stop_mps"]) if worst else None
    why = "" if first is None else (f"; {STOP_WORDS[first['stop']]} {first['stop_mps']:g} m/s "
                                    f"towards {first['towards_deg']:g} deg")
    if verdict["safe_mps"] is None:
        head = f"{mission}: no current is safe from every direction{why}"
    elif first is None:
        head = (f"{mission}: no contact in {seeds} seed(s) up to {verdict['safe_mps']:g} m/s "
                f"(the fastest tested) from every direction")
    else:
        head = (f"{mission}: no contact in {seeds} seed(s) up to {verdict['safe_mps']:g} m/s "
                f"from every direction{why}")
    top = verdict["speeds"][-1] if verdict["speeds"] else 0.0
    cells = ", ".join(
        f"{p['towards_deg']:g}: " + ("none" if p["safe_mps"] is None else
                                     f">= {top:g}" if p["stop"] is None else
                                     f"{p['safe_mps']:g}") for p in per)
    return f"{head}; per direction (towards deg: m/s) {cells}"


def _edges(values: list[float], half_width: float) -> np.ndarray:
    """Cell edges around sorted centres: midpoints, the ends half a spacing out (at least 0)."""
    values = np.asarray(values, dtype=float)
    if len(values) == 1:
        return np.array([max(values[0] - half_width, 0.0), values[0] + half_width])
    mid = 0.5 * (values[1:] + values[:-1])
    return np.concatenate([[max(values[0] - (mid[0] - values[0]), 0.0)], mid,
                           [values[-1] + (values[-1] - mid[-1])]])


def envelope_figure(verdict: dict, title: str) -> Figure:
    """envelope.png: the three panels of `envelope_axes` and a title saying how to read them."""
    fig = Figure(figsize=(17, 6.2))
    envelope_axes(fig, verdict)
    fig.suptitle(f"{title}\n{READING}", fontsize=10)
    return fig


READING = ("radius: current speed (m/s); angle: the direction the current flows towards, "
           "clockwise from north (north up); black line: the envelope, no seed touched within "
           "it")


def envelope_axes(fig, verdict: dict, rows: int = 1, row: int = 0, label: str = "",
                  clearance_range=(None, None)) -> None:
    """Three polar panels in row `row` of `rows` of `fig`, speed as radius and the direction
    the current flows towards as angle (clockwise from north, north up): contact rate, least
    clearance (colour range `clearance_range`, m) and median multibeam coverage per cell, the
    no-contact envelope drawn in black on each; `label` heads their titles."""
    speeds = verdict["speeds"]
    towards = [p["towards_deg"] for p in verdict["directions"]]
    half = 180.0 / len(towards)
    sub = math.ceil(2 * half / 3.0)  # wedges drawn in steps of at most 3 deg (arcs, not chords)
    theta = np.radians(np.concatenate(
        [d - half + 2 * half * np.arange(sub) / sub for d in towards] + [[towards[-1] + half]]))
    radius = _edges(speeds, 0.05)
    grids = {k: np.full((len(speeds), len(towards)), np.nan)
             for k in ("contact_rate", "least_clearance_m", "coverage_multibeam_median")}
    for cell in verdict["cells"]:
        i, j = speeds.index(cell["speed_mps"]), towards.index(cell["towards_deg"])
        for key, grid in grids.items():
            grid[i, j] = np.nan if cell[key] is None else cell[key]
    outer = np.array([0.0 if p["safe_mps"] is None else radius[speeds.index(p["safe_mps"]) + 1]
                      for p in verdict["directions"]])
    boundary_r = np.append(np.repeat(outer, sub), outer[0])
    boundary_r = np.stack([boundary_r[:-1], boundary_r[:-1]], axis=1).ravel()
    boundary_t = np.stack([theta[:-1], theta[1:]], axis=1).ravel()
    panels = (("contact rate over the seeds (%)", "contact_rate", "Reds", 100.0, (0, 100)),
              ("least clearance over the seeds (m)", "least_clearance_m", "viridis", 1.0,
               clearance_range),
              ("median multibeam coverage (%)", "coverage_multibeam_median", "viridis", 100.0,
               (0, 100)))
    for k, (name, key, cmap, factor, (vmin, vmax)) in enumerate(panels):
        ax = fig.add_subplot(rows, 3, 3 * row + k + 1, projection="polar")
        ax.set_theta_zero_location("N")
        ax.set_theta_direction(-1)
        mesh = ax.pcolormesh(theta, radius,
                             np.ma.masked_invalid(factor * np.repeat(grids[key], sub, axis=1)),
                             cmap=cmap, shading="flat", vmin=vmin, vmax=vmax)
        ax.plot(boundary_t, boundary_r, color="black", linewidth=2.0)
        ax.set_ylim(0, radius[-1])
        ax.set_rticks([v for v in speeds if v > 0])
        ax.set_rlabel_position(half)
        ax.tick_params(axis="y", labelsize=7)
        ax.set_title(f"{label}: {name}" if label else name, pad=14)
        ax.grid(alpha=0.4)
        fig.colorbar(mesh, ax=ax, shrink=0.7, pad=0.1)


def envelope_markdown(mission: str, verdict: dict, line: str) -> str:
    """envelope.md: the verdict, the rule, the table per direction."""
    lines = [f"# Operating envelope: {mission}", "", line, "",
             "Rule: per direction, the highest tested speed at which every seed, at that speed "
             "and every slower one (still water included), ended without contact; a contact, a "
             "failed run or a missing cell stops the climb. The envelope is the least of these "
             "over the directions.", "",
             f"Speeds (m/s): {', '.join(f'{s:g}' for s in verdict['speeds'])}; seeds: "
             f"{len(verdict['seeds'])}.", "",
             "| towards (deg) | no contact up to (m/s) | stopped at (m/s) | by |",
             "| --- | --- | --- | --- |"]
    for p in verdict["directions"]:
        lines.append(f"| {p['towards_deg']:g} | "
                     f"{'none' if p['safe_mps'] is None else format(p['safe_mps'], 'g')} | "
                     f"{'' if p['stop_mps'] is None else format(p['stop_mps'], 'g')} | "
                     f"{p['stop'] or 'reached the fastest speed'} |")
    lines += ["", "Plot: `envelope.png`; one row per run: `envelope.csv`.", ""]
    return "\n".join(lines)


def write_envelope(rows, out, mission: str, meta: dict, dpi: int = 110) -> tuple[dict, str]:
    """Writes envelope.json (`meta` as its `command`, the verdict's line and `envelope_verdict`),
    envelope.md and envelope.png into `out` from every row of envelope.csv; returns (the
    verdict, its line)."""
    out = Path(out)
    verdict = envelope_verdict(rows)
    line = verdict_line(mission, verdict)
    write_json(out / "envelope.json", {"command": meta, "verdict": line, **verdict})
    write_text(out / "envelope.md", envelope_markdown(mission, verdict, line))
    fig = envelope_figure(verdict, f"Operating envelope of {mission}, "
                                   f"{len(verdict['seeds'])} seed(s)")
    with replacing(out / "envelope.png") as temporary:
        fig.savefig(temporary, dpi=dpi, bbox_inches="tight")
    return verdict, line
