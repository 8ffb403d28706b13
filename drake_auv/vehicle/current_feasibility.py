"""A coverage plan in a current: ground speed, thrust and duration per lane and contour (pure
numpy).

The vehicle tracks its plan over the ground: on a segment of the path with unit direction t
(world) and the vehicle's planned heading psi (the segment's start or end sample's, whichever
asks less: the plan turns the vehicle between them, in place where it must), flying at the ground speed g in a horizontal
current c (world, m/s) its velocity through the water is v_r = g t - c, and in the body frame
(FLU, yawed by psi) the thrusters must hold the damping of the vehicle's model against it,

    F = D_lin v_r,b + D_quad |v_r,b| v_r,b     (surge, sway, heave; `Girona500Params`)

plus the net buoyancy in heave. The thrusts are the allocation of that wrench
(`Girona500Params.allocation_matrix`); the segment's thrust share is the largest of them over
the thrust limit, which on one axis alone is F over that axis' `axis_force_limits`. A segment
is flown at the planned speed when its share is at most 1; otherwise at the highest ground
speed below it that the thrusters can give (a grid of `SPEED_STEPS`), and not at all when
none (0 included: the current across it is more than the thrusters can hold).

The sea is a mean current of `speed_mps` towards `towards_deg` (clockwise from north) and a
tidal envelope: the tide floods and ebbs along the same axis with an amplitude of up to
`tide_mps`, so the current along that axis spans [speed - tide, speed + tide]. The thrust is
convex in the current, so the worst case over the envelope is at one of its two ends; the
report gives the mean current's figures and the envelope's worst.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from drake_auv.ocean.current import MAX_CURRENT_MPS, towards_unit
from drake_auv.params import param, validate
from drake_auv.planning.path import PlannedPath
from drake_auv.vehicle.control import axis_force_limits
from drake_auv.vehicle.model import Girona500Params

SPEED_STEPS = 100  # ground speeds tried below the planned one, evenly spaced from 0
TURN_DEG = 45.0  # a change of direction above this ends a lane
MIN_LANE_M = 5.0  # a straight piece of lane shorter than this is a turn between lanes
AXES = ("surge", "sway", "heave")
KINDS = {"planar": "lane", "slice": "contour", "transit": "transit", "lawnmower": "lane"}


@dataclass(frozen=True)
class PlanCurrent:
    """The current a plan is checked against: a mean and a tidal envelope along its axis."""

    speed_mps: float = param(0.0, low=0.0, high=MAX_CURRENT_MPS, unit="m/s")
    towards_deg: float = param(0.0, low=-360.0, high=360.0, unit="deg")
    tide_mps: float = param(0.0, low=0.0, high=MAX_CURRENT_MPS, unit="m/s")

    def __post_init__(self):
        validate(self)

    def cases(self) -> np.ndarray:
        """(3, 2) world velocities, m/s: the mean, then the envelope's two ends."""
        axis = towards_unit(self.towards_deg)
        return np.array([self.speed_mps, self.speed_mps + self.tide_mps,
                         self.speed_mps - self.tide_mps])[:, None] * axis


def parse_current(text: str, tide: float | None = None) -> PlanCurrent:
    """`--current SPEED,TOWARDS_DEG` and `--tide AMPLITUDE` (m/s) as a `PlanCurrent`."""
    try:
        speed, towards = (float(v) for v in text.split(","))
    except ValueError:
        raise ValueError(f"--current: expected 'SPEED,TOWARDS_DEG' (m/s, degrees clockwise "
                         f"from north the water flows towards), got {text!r}") from None
    for name, value, high in (("SPEED", speed, MAX_CURRENT_MPS), ("TOWARDS_DEG", towards, 360.0),
                              ("--tide", 0.0 if tide is None else tide, MAX_CURRENT_MPS)):
        low = -360.0 if name == "TOWARDS_DEG" else 0.0
        if not (np.isfinite(value) and low <= value <= high):
            raise ValueError(f"--current: {name} = {value:g} is out of range; must be in "
                             f"[{low:g}, {high:g}]" if name != "--tide" else
                             f"--tide: {value:g} is out of range; must be in [0, {high:g}] m/s")
    return PlanCurrent(speed, towards, 0.0 if tide is None else float(tide))


def aligned_sweep_angle(current: PlanCurrent) -> float:
    """The lane direction along the current's axis, degrees from +x in [0, 180) (the planner's
    `sweep_angle_deg`): lanes fly with and against the current, never across it."""
    return float((90.0 - current.towards_deg) % 180.0)


def thrust_share(direction: np.ndarray, heading: np.ndarray, ground_speed, water: np.ndarray,
                 params: Girona500Params | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The largest thrust over the limit (..., ) and the body force (..., 3), N, to fly
    segments of unit `direction` (n, 3) with yaw `heading` (n,) rad at `ground_speed` (m/s,
    broadcast against (..., n)) in the horizontal current `water` (2,) or (n, 2) m/s."""
    p = params if params is not None else Girona500Params()
    g = np.asarray(ground_speed, dtype=float)[..., None]
    relative = g * direction
    relative[..., :2] -= water
    cos, sin = np.cos(heading)[:, None], np.sin(heading)[:, None]
    body = np.stack([cos[:, 0] * relative[..., 0] + sin[:, 0] * relative[..., 1],
                     -sin[:, 0] * relative[..., 0] + cos[:, 0] * relative[..., 1],
                     relative[..., 2]], axis=-1)
    d_lin, d_quad = (np.asarray(d, dtype=float)[:3] for d in (p.linear_damping,
                                                                p.quadratic_damping))
    force = d_lin * body + d_quad * np.abs(body) * body
    wrench = np.concatenate([force, np.zeros(force.shape[:-1] + (1,))], axis=-1)
    wrench[..., 2] -= p.buoyancy - p.weight  # the heave thrusters hold the net buoyancy
    thrust = wrench @ p.allocation_matrix().T
    return np.abs(thrust).max(axis=-1) / p.max_thrust, force


def _pieces(path: PlannedPath) -> list[tuple[str, int, int]]:
    """(kind, first, last sample) of the path's lanes, contours and transits: runs of one
    label, a lane also ending where the horizontal direction turns by more than `TURN_DEG`;
    a piece of lane shorter than `MIN_LANE_M` is a "turn" (the step between two lanes)."""
    labels = path.labels
    cut = np.flatnonzero(labels[1:] != labels[:-1]) + 1
    step = np.diff(path.points[:, :2], axis=0)
    angle = np.arctan2(step[:, 1], step[:, 0])
    turn = np.abs(np.angle(np.exp(1j * np.diff(angle))))
    lanes = np.isin(labels[1:-1], ("planar", "lawnmower")) & (turn > np.radians(TURN_DEG))
    cut = np.union1d(cut, np.flatnonzero(lanes) + 1)
    bounds = np.concatenate([[0], cut, [len(path) - 1]])
    along = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(path.points, axis=0),
                                                            axis=1))])
    out = []
    for a, b in zip(bounds[:-1], bounds[1:]):
        kind = KINDS.get(str(labels[a]), str(labels[a]))
        if kind == "lane" and along[b] - along[a] < MIN_LANE_M:
            kind = "turn"
        if b > a:
            out.append((kind, int(a), int(b)))
    return out


def current_report(path: PlannedPath, current: PlanCurrent, speed: float,
                   params: Girona500Params | None = None,
                   yaw_rate: float = np.radians(15.0), aligned: bool = True) -> dict:
    """Per lane, contour and transit of `path` flown at the ground `speed` (m/s) in `current`:
    length (m), the mean current along and across it (m/s, + with the motion, + to port), the
    thrust share and ground speed in the mean current and the envelope's worst, the axis that
    limits, flyable or not; the mission's duration at those ground speeds (s) against the
    planned one; one warning line per piece that cannot be flown as planned; the worst of its
    lanes (`lanes`) and, with `aligned`, of lanes along the current (`aligned_lanes`)."""
    if not (np.isfinite(speed) and speed > 0):
        raise ValueError(f"speed must be > 0 m/s, got {speed}")
    p = params if params is not None else Girona500Params()
    points = path.points
    step = np.diff(points, axis=0)
    length = np.linalg.norm(step, axis=1)
    moving = length > 1e-9
    direction = np.zeros_like(step)
    direction[moving] = step[moving] / length[moving, None]
    headings = np.asarray(path.heading, dtype=float)
    cases = current.cases()

    def share(rows, g, water):
        """The lesser share of the segments `rows` over their start and end headings."""
        first = thrust_share(direction[rows], headings[:-1][rows], g, water, p)
        last = thrust_share(direction[rows], headings[1:][rows], g, water, p)
        better = last[0] < first[0]
        return np.where(better, last[0], first[0]), np.where(better[..., None], last[1],
                                                               first[1])

    every = np.arange(len(step))
    shares = np.stack([share(every, speed, c)[0] for c in cases])
    ground = np.full(shares.shape, float(speed))
    trial = np.arange(SPEED_STEPS - 1, -1, -1) / SPEED_STEPS * speed  # below it, fastest first
    for k, c in enumerate(cases):  # the segments the planned speed overloads, on the grid
        slow = np.flatnonzero(shares[k] > 1.0)
        if len(slow):
            feasible = share(slow, trial[:, None], c)[0] <= 1.0
            ground[k, slow] = np.where(feasible.any(axis=0), trial[feasible.argmax(axis=0)], 0.0)
    planned_share, force = share(every, speed, cases[0])
    worst_share = shares.max(axis=0)
    limits = axis_force_limits(p)
    along = direction[:, :2] @ cases[0]
    across = direction[:, 0] * cases[0][1] - direction[:, 1] * cases[0][0]  # + to port
    still = np.sum(length / speed)
    planned = path.times(speed, yaw_rate)[-1]
    pieces, warnings = [], []
    count = {}
    for kind, a, b in _pieces(path):
        seg = slice(a, b)
        metres = float(length[seg].sum())
        if metres <= 1e-9:
            continue
        count[kind] = count.get(kind, 0) + 1
        weights = length[seg] / metres
        mean_ground = ground[0, seg][moving[seg]]
        worst_ground = ground[:, seg][:, moving[seg]].min(axis=0)
        k = a + int(np.argmax(planned_share[seg]))
        axis = int(np.argmax(np.abs(force[k]) / limits))
        piece = dict(kind=kind, index=count[kind], first_sample=a, last_sample=b,
                     length_m=round(metres, 2),
                     current_along_mps=round(float(weights @ along[seg]), 3),
                     current_across_mps=round(float(weights @ across[seg]), 3),
                     thrust_share=round(float(planned_share[seg].max()), 3),
                     thrust_share_worst=round(float(worst_share[seg].max()), 3),
                     limiting_axis=AXES[axis],
                     axis_force_n=round(float(abs(force[k, axis])), 1),
                     axis_limit_n=round(float(limits[axis]), 1),
                     ground_speed_mps=round(float(mean_ground.min()), 3),
                     ground_speed_worst_mps=round(float(worst_ground.min()), 3),
                     flyable=bool(mean_ground.min() > 0.0),
                     flyable_worst=bool(worst_ground.min() > 0.0))
        pieces.append(piece)
        name = f"{kind} {count[kind]} ({metres:.0f} m)"
        if not piece["flyable"]:
            warnings.append(f"{name} cannot be flown: the current "
                            f"({piece['current_along_mps']:+.2f} m/s along, "
                            f"{piece['current_across_mps']:+.2f} across) needs more "
                            f"{AXES[axis]} thrust than the thrusters give even at rest")
        elif piece["ground_speed_mps"] < speed:
            warnings.append(f"{name}: {piece['thrust_share']:.2f} of the thrust limit at "
                            f"{speed:g} m/s ({AXES[axis]} {piece['axis_force_n']:.0f} N of "
                            f"{piece['axis_limit_n']:.0f} N); flies at "
                            f"{piece['ground_speed_mps']:.2f} m/s")
        elif not piece["flyable_worst"]:
            warnings.append(f"{name} cannot be flown at the tide's worst "
                            f"({current.speed_mps:g} +- {current.tide_mps:g} m/s)")
        elif piece["ground_speed_worst_mps"] < speed:
            warnings.append(f"{name}: at the tide's worst flies at "
                            f"{piece['ground_speed_worst_mps']:.2f} m/s, not {speed:g}")

    def duration(speeds):
        if np.any(speeds[moving] <= 0.0):
            return None
        return float(planned - still + np.sum(length[moving] / speeds[moving]))

    return dict(current=dict(speed_mps=current.speed_mps, towards_deg=current.towards_deg,
                             tide_mps=current.tide_mps),
                speed_mps=float(speed), pieces=pieces, warnings=warnings,
                duration_planned_s=round(float(planned), 1),
                duration_s=_round(duration(ground[0])),
                duration_worst_s=_round(duration(ground.min(axis=0))),
                lanes=_worst([q for q in pieces if q["kind"] == "lane"]),
                aligned_sweep_angle_deg=aligned_sweep_angle(current),
                aligned_lanes=_worst(aligned_lanes(current, speed, p)) if aligned else None)


def _worst(pieces) -> dict | None:
    """The largest thrust share and least ground speed of `pieces` (dicts of
    `current_report`), over the mean current and the envelope's worst; None without any."""
    if not pieces:
        return None
    return dict(thrust_share=max(q["thrust_share"] for q in pieces),
                thrust_share_worst=max(q["thrust_share_worst"] for q in pieces),
                ground_speed_mps=min(q["ground_speed_mps"] for q in pieces),
                ground_speed_worst_mps=min(q["ground_speed_worst_mps"] for q in pieces))


def aligned_lanes(current: PlanCurrent, speed: float,
                  params: Girona500Params | None = None) -> list[dict]:
    """The figures of two level lanes along the current's axis, one each way, heading along
    the motion (as the planner's lanes), at the ground `speed`: what `--align-with-current`
    would give its lanes."""
    angle = np.radians(aligned_sweep_angle(current))
    out = []
    for yaw in (angle, angle + np.pi):
        points = np.outer(np.arange(3.0), [np.cos(yaw), np.sin(yaw), 0.0])
        lane = PlannedPath(points, np.full(3, yaw), (0.0, 0.0, -1.0),
                    np.array(["planar"] * 3, dtype=object))
        out += [q for q in current_report(lane, current, speed, params, aligned=False)["pieces"]]
    return out


def _round(value):
    return None if value is None else round(value, 1)


def current_markdown(report: dict) -> str:
    """The report as markdown: the sea, the durations, one row per piece, the warnings."""
    c = report["current"]
    sea = f"{c['speed_mps']:g} m/s towards {c['towards_deg']:g} deg" + (
        f", tide +- {c['tide_mps']:g} m/s along it" if c["tide_mps"] else "")

    def secs(value):
        return "cannot be flown" if value is None else f"{value:.0f} s"

    lines = [f"## In a current: {sea}", "",
             f"Duration at {report['speed_mps']:g} m/s over the ground: planned "
             f"{report['duration_planned_s']:.0f} s; at ground speed, mean current "
             f"{secs(report['duration_s'])}, the tide's worst {secs(report['duration_worst_s'])}. "
             f"Lanes along the current: sweep angle {report['aligned_sweep_angle_deg']:g} deg "
             "(`--align-with-current`)" + _aligned_text(report) + ".", "",
             "| piece | length (m) | current along / across (m/s) | thrust share: mean / worst "
             "| limiting axis (N of N) | ground speed: mean / worst (m/s) |",
             "|---|---|---|---|---|---|"]
    for p in report["pieces"]:
        lines.append(f"| {p['kind']} {p['index']} | {p['length_m']:.0f} | "
                     f"{p['current_along_mps']:+.2f} / {p['current_across_mps']:+.2f} | "
                     f"{p['thrust_share']:.2f} / {p['thrust_share_worst']:.2f} | "
                     f"{p['limiting_axis']} ({p['axis_force_n']:.0f} of {p['axis_limit_n']:.0f})"
                     f" | {p['ground_speed_mps']:.2f} / {p['ground_speed_worst_mps']:.2f} |")
    lines += ["", *(f"- warning: {w}" for w in report["warnings"])]
    return "\n".join(lines).rstrip() + "\n"


def _aligned_text(report: dict) -> str:
    along = report.get("aligned_lanes")
    if along is None:
        return ""
    return (f", their largest thrust share {along['thrust_share']:.2f} in the mean current, "
            f"{along['thrust_share_worst']:.2f} at the tide's worst")


def summary_lines(report: dict, sweep_angle_deg: float | None = None) -> list[str]:
    """What `plan` prints: the durations at ground speed, one line per warning and, when the
    lanes (at `sweep_angle_deg`, degrees from +x) do not run along the current, the offer of
    lanes that do, with their largest thrust share against the plan's lanes' (along the
    current is not always the lighter: a head current adds to the speed through the water,
    a cross current loads the weaker sway)."""
    def secs(value):
        return "cannot be flown" if value is None else f"{value:.0f} s"

    c = report["current"]
    lines = [f"in a current of {c['speed_mps']:g} m/s towards {c['towards_deg']:g} deg"
             + (f" (tide +- {c['tide_mps']:g} m/s)" if c["tide_mps"] else "")
             + f": duration {secs(report['duration_s'])} at ground speed (planned "
             f"{report['duration_planned_s']:.0f} s), the tide's worst "
             f"{secs(report['duration_worst_s'])}"]
    lines += [f"warning: {w}" for w in report["warnings"]]
    aligned = report["aligned_sweep_angle_deg"]
    if sweep_angle_deg is not None and c["speed_mps"] + c["tide_mps"] > 0 and abs(
            (sweep_angle_deg - aligned + 90.0) % 180.0 - 90.0) > 1.0:
        line = (f"lanes along the current: --align-with-current (sweep angle {aligned:g} "
                f"deg instead of {sweep_angle_deg % 180.0:g})")
        now, along = report.get("lanes"), report.get("aligned_lanes")
        if now is not None and along is not None:
            line += (f"; lanes' largest thrust share, mean current / the tide's worst: "
                     f"{along['thrust_share']:.2f} / {along['thrust_share_worst']:.2f} along it"
                     f", {now['thrust_share']:.2f} / {now['thrust_share_worst']:.2f} now")
        lines.append(line)
    return lines
