"""Horizontal profile following around the boulder (reference Section 5.5.4.2).

The GIRONA 500 circumnavigates the l'Amarrador-like boulder at constant depth, facing it at a
fixed offset, guided only by its pencil-beam profiler in the horizontal plane. Acceptance: a
closed loop around the boulder (one full turn about its centre) without contact (true 3D
clearance to the mesh above the vehicle's radius, 1 m, at every logged step).

Writes out/profile_boulder/: boulder_loop.png (top view over the boulder's cross-section and
the offset against time), boulder.html (Meshcat recording), summary.json. Run:
    MPLBACKEND=Agg .venv/bin/python examples/profile_boulder.py [--depth 34] [--offset 3]
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import trimesh

from drake_auv.diagrams.profile_following import build_profile_following_diagram, run_mission
from drake_auv.geometry.distance import mesh_distance
from drake_auv.perception import EstimatorParams, FollowingParams
from drake_auv.scenarios import get_scenario

VEHICLE_RADIUS = 1.0  # m


def _turns(x, centre) -> float:
    angle = np.unwrap(np.arctan2(x[1] - centre[1], x[0] - centre[0]))
    return abs(angle[-1] - angle[0]) / (2 * np.pi)


def run(depth=34.0, offset=3.0, speed=None, loops=1.0, scene=None, max_time=600.0, seed=0):
    """Circumnavigates the boulder at `depth` (m) and `offset` (m); returns time series."""
    scenario = get_scenario("boulder")
    world = scenario.world
    target = world.vertices[world.faces[scenario.target_faces]].reshape(-1, 3)
    centre = target.mean(axis=0)
    params = FollowingParams(offset=offset, speed=speed or scenario.params["speed"],
                             estimator=EstimatorParams(window=offset + 3.0))
    start = np.zeros(12)
    start[:3] = (centre[0] - 16.0, centre[1], -depth)  # in front of the boulder's -x side
    diagram, handles = build_profile_following_diagram(
        world, start, "horizontal", params, seed=seed, scene=scene)

    def closed(context):
        x = handles.state_log.FindLog(context).data()
        return x.shape[1] > 1 and _turns(x, centre) >= loops

    simulator = run_mission(diagram, max_time, stop=closed, label="boulder loop")
    context = simulator.get_context()
    log = handles.state_log.FindLog(context)
    x = log.data()
    profile = handles.profile_log.FindLog(context).data()
    return dict(t=log.sample_times(), x=x, estimated=profile[0], centre=centre,
                clearance=mesh_distance(world, x[:3].T), turns=_turns(x, centre),
                depth=depth, offset=offset, world=world)


def figure(result, filename):
    x, t = result["x"], result["t"]
    lines = trimesh.intersections.mesh_plane(result["world"], [0, 0, 1], [0, 0, -result["depth"]])
    fig, (a, b) = plt.subplots(1, 2, figsize=(12, 5.5), gridspec_kw=dict(width_ratios=[1.2, 1]))
    for seg in lines:
        a.plot(seg[:, 0], seg[:, 1], color="0.4", lw=0.8)
    a.plot([], [], color="0.4", label=f"boulder section at {result['depth']:.0f} m depth")
    a.plot(x[0], x[1], color="tab:blue", label="vehicle (true)")
    stride = max(1, len(t) // 40)
    a.quiver(x[0, ::stride], x[1, ::stride], np.cos(x[5, ::stride]), np.sin(x[5, ::stride]),
             color="tab:blue", scale=25, width=0.003)
    a.plot(*result["centre"][:2], "k+")
    a.set_aspect("equal")
    a.set_xlabel("x (m)")
    a.set_ylabel("y (m)")
    a.legend(fontsize=8, loc="upper right")
    a.set_title(f"Horizontal following around the boulder ({result['turns']:.2f} loops)")
    b.plot(t, result["clearance"], label="true 3D clearance")
    b.plot(t, result["estimated"], lw=0.8, label="estimated distance to profile")
    b.axhline(result["offset"], color="k", lw=0.8)
    b.axhline(VEHICLE_RADIUS, color="r", ls="--", lw=0.8, label="vehicle radius")
    b.set_xlabel("time (s)")
    b.set_ylabel("distance (m)")
    b.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(filename, dpi=120)
    plt.close(fig)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="out/profile_boulder")
    parser.add_argument("--depth", type=float, default=34.0, help="m, between 29 and 39")
    parser.add_argument("--offset", type=float, default=3.0, help="m")
    args = parser.parse_args(argv)
    if not 29.0 <= args.depth <= 39.0:
        raise ValueError(f"--depth must be in [29, 39] m (the boulder spans 28-40 m), got {args.depth}")
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    from drake_auv.visualization.scene import Scene
    scene = Scene()
    scene.add_mesh("boulder", get_scenario("boulder").world, rgba=(0.55, 0.5, 0.42, 1.0))
    scene.start_recording(playback_speed=10.0, live=False)
    result = run(args.depth, args.offset, scene=scene)
    scene.write_html(out / "boulder.html")
    figure(result, out / "boulder_loop.png")
    late = result["t"] > 30.0
    summary = dict(depth_m=args.depth, offset_m=args.offset, duration_s=float(result["t"][-1]),
                   loops=round(float(result["turns"]), 3),
                   min_clearance_m=float(result["clearance"].min()),
                   no_contact=bool(result["clearance"].min() > VEHICLE_RADIUS),
                   offset_error_after_30s_max_m=float(np.abs(result["clearance"][late]
                                                             - args.offset).max()),
                   offset_error_after_30s_mean_m=float(np.abs(result["clearance"][late]
                                                              - args.offset).mean()))
    (out / "summary.json").write_text(json.dumps(summary, indent=2))
    print(json.dumps(summary, indent=2))
    return summary


if __name__ == "__main__":
    main()
