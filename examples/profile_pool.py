"""Profile following in the CIRS-like pool (reference Section 5.5.2.2, Figures 84 and 85).

1. Horizontal following at 4 m depth, two full laps of the 16 m x 8 m pool despite its 90
   degree corners; the true frontal distance (a ray along the heading against the true pool)
   must stay within 1 m of the nominal 2 m after the first 20 s. PNG like Figure 84: frontal
   distance and slope against time.
2. The same with the profiler's spurious returns and range noise on (seeded), and again with
   a drifting navigation (compass bias, DVL scale error, random walk; seeded): the returns are
   placed with the estimated pose, as at sea.
3. Vertical following of the V-shaped bottom from the shallow end to the far wall (the
   "cliff"), with the distance to the cliff against time like Figure 85.

Writes out/profile_pool/: pool_horizontal.png, pool_horizontal_spurious.png,
pool_horizontal_drift.png, pool_vertical.png,
pool_horizontal.html (Meshcat recording), summary.json. Run:
    MPLBACKEND=Agg .venv/bin/python examples/profile_pool.py [--out DIR] [--spurious 0.1]
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from drake_auv.vehicle.control import wrap_angle
from drake_auv.diagrams.profile_following import build_profile_following_diagram, run_mission
from drake_auv.geometry.distance import mesh_distance
from drake_auv.vehicle.navigation import NavigationParams
from drake_auv.perception import FollowingParams
from drake_auv.scenarios import get_scenario
from drake_auv.sonar.noise import SonarNoise

SETTLE = 20.0  # s, the reference's pool result holds after the first 20 s
VEHICLE_RADIUS = 1.0  # m, GIRONA 500 envelope 1.5 x 1.0 x 1.0 m


def _logs(handles, context):
    state = handles.state_log.FindLog(context)
    return state.sample_times(), state.data(), handles.profile_log.FindLog(context).data()


def _laps(handles, context) -> float:
    x = handles.state_log.FindLog(context).data()
    if x.shape[1] < 2:
        return 0.0
    angle = np.unwrap(np.arctan2(x[1], x[0]))
    return abs(angle[-1] - angle[0]) / (2 * np.pi)


def horizontal(scenario, noise=None, navigation=None, seed=0, scene=None, max_time=500.0):
    """Two laps at the scenario depth; returns a dict of time series."""
    p = scenario.params
    params = FollowingParams(offset=p["omega"], speed=p["speed"], corner_weight=0.5)
    start = scenario.start_state.copy()
    start[2] = -p["depth"]
    diagram, handles = build_profile_following_diagram(
        scenario.world, start, "horizontal", params, noise=noise, navigation=navigation,
        seed=seed, scene=scene)
    simulator = run_mission(diagram, max_time,
                            stop=lambda c: _laps(handles, c) >= p["laps"],
                            label="pool horizontal" + (" (spurious)" if noise else "")
                            + (" (drift)" if navigation else ""))
    t, x, profile = _logs(handles, simulator.get_context())
    heading = np.column_stack([np.cos(x[5]), np.sin(x[5]), np.zeros_like(x[5])])
    hits = handles.caster.cast(x[:3].T, heading, 20.0)
    wall_normal = handles.caster.face_normals[np.maximum(hits.faces, 0)]
    true_slope = np.degrees(wrap_angle(np.arctan2(-wall_normal[:, 1], -wall_normal[:, 0]) - x[5]))
    est_slope = np.degrees(wrap_angle(np.arctan2(-profile[3], -profile[2]) - x[5]))
    return dict(t=t, x=x, frontal=hits.ranges, estimated=profile[0], true_slope=true_slope,
                est_slope=est_slope, clearance=mesh_distance(scenario.world, x[:3].T),
                laps=_laps(handles, simulator.get_context()), offset=params.offset)


def vertical(scenario, seed=0, max_time=200.0):
    """The V profile along the pool's length, from the shallow end to the far end wall."""
    p = scenario.params
    params = FollowingParams(offset=p["omega"], speed=p["speed"], min_depth=1.0)
    start = np.zeros(12)
    start[:3] = (-6.0, 0.0, -3.0)
    diagram, handles = build_profile_following_diagram(
        scenario.world, start, "vertical", params, plane_yaw=0.0, seed=seed)

    def at_cliff_top(context):  # climbed the far wall to the depth limit
        x = handles.state_log.FindLog(context).data()
        return x.shape[1] > 0 and x[0, -1] > 4.0 and x[2, -1] > -1.3

    simulator = run_mission(diagram, max_time, stop=at_cliff_top, label="pool vertical")
    t, x, profile = _logs(handles, simulator.get_context())
    forward = np.tile([1.0, 0.0, 0.0], (len(t), 1))  # the cliff is the +x end wall
    cliff = handles.caster.cast(x[:3].T, forward, 20.0).ranges
    return dict(t=t, x=x, cliff=cliff, estimated=profile[0],
                clearance=mesh_distance(scenario.world, x[:3].T), offset=params.offset)


def _horizontal_figure(run, title, filename):
    t, late = run["t"], run["t"] > SETTLE
    fig, (a, b) = plt.subplots(2, 1, figsize=(9, 6), sharex=True)
    a.axhspan(run["offset"] - 1, run["offset"] + 1, color="0.9", label="nominal +/- 1 m")
    a.axhline(run["offset"], color="k", lw=0.8)
    a.plot(t, run["frontal"], label="true frontal distance (along heading)")
    a.plot(t, run["estimated"], lw=0.8, label="estimated distance to profile")
    a.axvline(SETTLE, color="r", ls=":", lw=0.8)
    a.set_ylabel("distance (m)")
    a.set_title(f"{title}: max |frontal - nominal| after {SETTLE:.0f} s = "
                f"{np.nanmax(np.abs(run['frontal'][late] - run['offset'])):.2f} m")
    a.legend(loc="upper right", fontsize=8)
    b.plot(t, run["true_slope"], label="true (wall hit by the heading ray)")
    b.plot(t, run["est_slope"], lw=0.8, label="estimated (profile normal)")
    b.set_ylabel("slope: wall normal vs heading (deg)")
    b.set_xlabel("time (s)")
    b.set_ylim(-60, 60)
    b.legend(loc="upper right", fontsize=8)
    fig.tight_layout()
    fig.savefig(filename, dpi=120)
    plt.close(fig)


def _vertical_figure(run, scenario, filename):
    fig, (a, b) = plt.subplots(2, 1, figsize=(9, 7))
    a.plot(run["t"], run["cliff"], label="true distance to the cliff (far wall, horizontal)")
    a.plot(run["t"], run["estimated"], lw=0.8, label="estimated distance to profile")
    a.axhline(run["offset"], color="k", lw=0.8)
    a.set_xlabel("time (s)")
    a.set_ylabel("distance (m)")
    a.legend(fontsize=8)
    xs = np.linspace(-8, 8, 200)
    bottom = -5.0 - 2.0 * (1.0 - np.abs(xs) / 8.0)
    b.fill_between(xs, bottom, -8, color="0.7")
    b.plot([8, 8, 9], [-5, 0.5, 0.5], "k", [-8, -8, -9], [-5, 0.5, 0.5], "k")
    b.plot(run["x"][0], run["x"][2], label="vehicle")
    b.axhline(0.0, color="b", lw=0.5)
    b.set_aspect("equal")
    b.set_xlabel("x (m)")
    b.set_ylabel("z (m)")
    b.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(filename, dpi=120)
    plt.close(fig)


def _summary(run):
    late = run["t"] > SETTLE
    error = np.abs(run["frontal"][late] - run["offset"])
    return dict(laps=round(float(run["laps"]), 3), duration_s=float(run["t"][-1]),
                max_frontal_error_m=float(np.nanmax(error)),
                mean_frontal_error_m=float(np.nanmean(error)),
                frontal_within_1m=bool(np.nanmax(error) < 1.0),
                min_clearance_m=float(run["clearance"].min()))


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="out/profile_pool")
    parser.add_argument("--spurious", type=float, default=0.1,
                        help="probability of a spurious return per ping in the noisy run")
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    scenario = get_scenario("pool")

    from drake_auv.visualization.scene import Scene
    scene = Scene()
    scene.add_mesh("pool", scenario.world, rgba=(0.6, 0.7, 0.8, 0.5))
    scene.start_recording(playback_speed=10.0, live=False)
    clean = horizontal(scenario, scene=scene)
    scene.write_html(out / "pool_horizontal.html")
    _horizontal_figure(clean, "Horizontal following, pool, 4 m depth", out / "pool_horizontal.png")

    noise = SonarNoise(spurious_prob=args.spurious, range_sigma=0.05)
    noisy = horizontal(scenario, noise=noise, seed=args.seed)
    _horizontal_figure(noisy, f"With spurious returns (p = {args.spurious}) and 5 cm noise",
                       out / "pool_horizontal_spurious.png")

    navigation = NavigationParams(heading_bias=np.radians(3.0), scale_error=0.03,
                                  random_walk=0.05, seed=args.seed)
    drift = horizontal(scenario, navigation=navigation)
    _horizontal_figure(drift, "With navigation drift (3 deg compass bias, 3 % DVL scale)",
                       out / "pool_horizontal_drift.png")

    v = vertical(scenario)
    _vertical_figure(v, scenario, out / "pool_vertical.png")

    summary = dict(horizontal=_summary(clean),
                   horizontal_spurious=dict(_summary(noisy), spurious_prob=args.spurious,
                                            range_sigma_m=0.05, seed=args.seed),
                   horizontal_drift=dict(_summary(drift), heading_bias_deg=3.0, scale_error=0.03,
                                         random_walk=0.05, seed=args.seed),
                   vertical=dict(duration_s=float(v["t"][-1]),
                                 min_clearance_m=float(v["clearance"].min()),
                                 final_cliff_distance_m=float(v["cliff"][-1]),
                                 offset_error_after_20s_max_m=float(np.nanmax(np.abs(
                                     v["clearance"][v["t"] > SETTLE] - v["offset"])))))
    (out / "summary.json").write_text(json.dumps(summary, indent=2))
    print(json.dumps(summary, indent=2))
    return summary


if __name__ == "__main__":
    main()
