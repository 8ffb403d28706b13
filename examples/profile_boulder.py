"""Horizontal profile following around the boulder (reference Section 5.5.4.2).

The GIRONA 500 circumnavigates the l'Amarrador-like boulder at constant depth, its port-looking
payload facing the boulder at a fixed offset, guided only by its pencil-beam profiler in the
horizontal plane: the follow step of the built-in `boulder` mission flown alone, under that
mission's navigation drift and chart error (the loop is judged around the charted centre).
Acceptance: a closed loop around the boulder (one full turn about its true centre) without
contact (true 3D clearance to the mesh above the vehicle's radius, 1 m, at every logged step).

Writes out/profile_boulder/: boulder_loop.png (top view over the boulder's cross-section and
the offset against time), boulder.html (Meshcat recording), summary.json. Run:
    MPLBACKEND=Agg .venv/bin/python examples/profile_boulder.py [--depth 34] [--offset 3]
"""

from __future__ import annotations

import argparse
import json
from dataclasses import replace
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
import trimesh

from drake_auv.mission.config import FollowStep, load_mission
from drake_auv.mission.plan import plan_mission
from drake_auv.mission.recording import finish_recording, prepare_scene
from drake_auv.mission.runner import VEHICLE_RADIUS, run_mission
from drake_auv.mission.site import load_site


def follow_spec(depth: float, offset: float):
    """The `boulder` mission reduced to its follow step, at `depth` and `offset` (m)."""
    spec = load_mission("boulder", overrides=[f"steps.1.follow.depth={depth}",
                                              f"steps.1.follow.offset={offset}"])
    return replace(spec, steps=tuple(s for s in spec.steps if isinstance(s, FollowStep)))


def run(spec, site, scene=None):
    """Flies `spec` at `site`; returns the follow leg's time series."""
    result = run_mission(spec, site, scene=scene)
    leg = next(iter(result.plan.legs_of("follow")))
    mask = result.log.leg_at == leg
    x = result.log.state[mask].T
    lo, hi = site.target_mesh.bounds
    centre = 0.5 * (lo + hi)
    angle = np.unwrap(np.arctan2(x[1] - centre[1], x[0] - centre[0]))
    t = result.log.times[mask]
    return dict(result=result, t=t - t[0], x=x, estimated=result.log.profile[mask, 0],
                centre=centre, clearance=result.log.clearance[mask],
                turns=abs(angle[-1] - angle[0]) / (2 * np.pi),
                navigation_error=np.linalg.norm(result.log.estimated[mask, :3] - x[:3].T, axis=1),
                depth=spec.steps[0].depth, offset=spec.steps[0].offset, world=site.world)


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
    b.set_xlabel("time since following began (s)")
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
        raise ValueError(f"--depth must be in [29, 39] m (the boulder spans 28-40 m), "
                         f"got {args.depth}")
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    from drake_auv.visualization import Scene

    spec = follow_spec(args.depth, args.offset)
    site = load_site(spec.site, spec.seed)
    scene = Scene()
    prepare_scene(scene, site, plan_mission(spec, site))
    scene.start_recording(playback_speed=10.0, live=False)
    result = run(spec, site, scene)
    finish_recording(result["result"], scene, out / "boulder.html")
    figure(result, out / "boulder_loop.png")
    late = result["t"] > 30.0
    summary = dict(depth_m=args.depth, offset_m=args.offset, duration_s=float(result["t"][-1]),
                   loops=round(float(result["turns"]), 3), outcomes=result["result"].dive.outcomes,
                   min_clearance_m=float(result["clearance"].min()),
                   no_contact=bool(result["clearance"].min() > VEHICLE_RADIUS),
                   offset_error_after_30s_max_m=float(np.abs(result["clearance"][late]
                                                             - args.offset).max()),
                   offset_error_after_30s_mean_m=float(np.abs(result["clearance"][late]
                                                              - args.offset).mean()),
                   navigation_error_max_m=float(result["navigation_error"].max()))
    (out / "summary.json").write_text(json.dumps(summary, indent=2))
    print(json.dumps(summary, indent=2))
    return summary


if __name__ == "__main__":
    main()
