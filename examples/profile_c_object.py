"""Vertical profile following of the C-shaped object (reference Section 5.5.2.1, Figure 81).

The GIRONA 500 starts in front of the C's opening and follows the vertical profile in the x-z
plane at a 2 m offset: the seabed, into the C over the bottom flange, up the inner wall, along
the ceiling (where it turns 180 degrees instead of moving backwards), out around the upper
flange, over the top (turning again to face its motion), down the back wall and onto the
seabed behind. The run stops once the vehicle is back on the seabed beyond the object.
Acceptance: no contact (the true clearance to the mesh stays above the vehicle's radius,
1 m, at every logged step), the whole C followed, the ceiling turn made.

Writes out/profile_c_object/: c_object_trajectory.png, c_object.html (Meshcat recording),
summary.json. Run:
    MPLBACKEND=Agg .venv/bin/python examples/profile_c_object.py [--out DIR]
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from drake_auv.diagrams.profile_following import build_profile_following_diagram, run_mission
from drake_auv.geometry.distance import mesh_distance
from drake_auv.perception import FollowingParams
from drake_auv.scenarios import get_scenario

VEHICLE_RADIUS = 1.0  # m
# The C in its x-z section (scenarios._c_object_geometry) and the seabed, for the figure.
C_OUTLINE = np.array([[0, -20], [0, -17], [10, -17], [10, -9], [0, -9], [0, -6], [13, -6],
                      [13, -20]], dtype=float)


def run(scene=None, max_time=400.0, seed=0):
    """Follows the C; returns a dict of time series and the turn count."""
    scenario = get_scenario("c_object")
    params = FollowingParams(offset=scenario.params["omega"], speed=scenario.params["speed"])
    diagram, handles = build_profile_following_diagram(
        scenario.world, scenario.start_state, "vertical", params, plane_yaw=0.0, seed=seed,
        scene=scene)
    passed_top = {"flag": False}

    def behind_the_c(context):  # over the top, then back down on the seabed beyond the C
        x = handles.state_log.FindLog(context).data()
        if x.shape[1] == 0:
            return False
        passed_top["flag"] |= bool(x[2, -1] > -6.0)
        return passed_top["flag"] and x[0, -1] > 20.0 and x[2, -1] < -17.0

    simulator = run_mission(diagram, max_time, stop=behind_the_c, label="C object")
    context = simulator.get_context()
    log = handles.state_log.FindLog(context)
    x = log.data()
    profile = handles.profile_log.FindLog(context).data()
    follower = handles.controller.follower(handles.controller.GetMyContextFromRoot(context))
    return dict(t=log.sample_times(), x=x, mode=profile[6], estimated=profile[0],
                clearance=mesh_distance(scenario.world, x[:3].T), turns=follower.turns,
                offset=params.offset, world=scenario.world)


def figure(result, filename):
    t, x, mode = result["t"], result["x"], result["mode"]
    fig, (a, b) = plt.subplots(2, 1, figsize=(9, 9), gridspec_kw=dict(height_ratios=[3, 1.2]))
    a.fill(C_OUTLINE[:, 0], C_OUTLINE[:, 1], color="0.6", label="C object (section y = 0)")
    a.fill_between([-10, 35], -20, -21, color="0.8", label="seabed")
    a.plot(x[0], x[2], color="tab:blue", lw=1.5, label="vehicle (true)")
    stride = max(1, len(t) // 40)
    a.quiver(x[0, ::stride], x[2, ::stride], np.cos(x[5, ::stride]), 0 * x[5, ::stride],
             color="tab:blue", scale=30, width=0.003, label="heading")
    turning = mode == 2
    a.plot(x[0, turning], x[2, turning], "o", color="tab:red", ms=3, label="180 degree turns")
    a.set_aspect("equal")
    a.set_xlim(-10, 25)
    a.set_ylim(-21, -1)
    a.set_xlabel("x (m)")
    a.set_ylabel("z (m)")
    a.set_title(f"Vertical profile following of the C object at {result['offset']:.0f} m "
                f"({result['turns']} turns)")
    a.legend(loc="upper right", fontsize=8)
    b.plot(t, result["clearance"], label="true clearance to the object and seabed")
    b.plot(t, result["estimated"], lw=0.8, label="estimated distance to profile")
    b.axhline(VEHICLE_RADIUS, color="r", ls="--", lw=0.8, label="vehicle radius")
    b.axhline(result["offset"], color="k", lw=0.8)
    b.set_xlabel("time (s)")
    b.set_ylabel("distance (m)")
    b.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(filename, dpi=120)
    plt.close(fig)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="out/profile_c_object")
    args = parser.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    from drake_auv.visualization.scene import Scene
    scene = Scene()
    scene.add_mesh("c_object", get_scenario("c_object").world, rgba=(0.6, 0.55, 0.5, 1.0))
    scene.start_recording(playback_speed=10.0, live=False)
    result = run(scene=scene)
    scene.write_html(out / "c_object.html")
    figure(result, out / "c_object_trajectory.png")
    x = result["x"]
    summary = dict(duration_s=float(result["t"][-1]), turns=int(result["turns"]),
                   min_clearance_m=float(result["clearance"].min()),
                   no_contact=bool(result["clearance"].min() > VEHICLE_RADIUS),
                   max_offset_error_m=float(np.abs(result["clearance"][result["t"] > 20]
                                                   - result["offset"]).max()),
                   reached_top_z_m=float(x[2].max()), final_position_m=x[:3, -1].tolist())
    (out / "summary.json").write_text(json.dumps(summary, indent=2))
    print(json.dumps(summary, indent=2))
    return summary


if __name__ == "__main__":
    main()
