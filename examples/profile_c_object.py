"""Vertical profile following of the C-shaped object (reference Section 5.5.2.1, Figure 81).

The GIRONA 500 starts in front of the C's opening and follows the vertical profile in the x-z
plane at a 2 m offset: the seabed, into the C over the bottom flange, up the inner wall, along
the ceiling (where it turns 180 degrees instead of moving backwards), out around the upper
flange, over the top (turning again to face its motion), down the back wall and onto the
seabed behind: the built-in `c_object` mission, whose follow step ends 26 m along the plane
from the start, beyond the object (x > 20 m).
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

from drake_auv.mission.config import load_mission
from drake_auv.mission.plan import plan_mission
from drake_auv.mission.recording import finish_recording, prepare_scene
from drake_auv.mission.runner import VEHICLE_RADIUS, run_mission
from drake_auv.mission.site import load_site
from drake_auv.signals import Profile

# The C in its x-z section (scenarios._c_object_geometry) and the seabed, for the figure.
C_OUTLINE = np.array([[0, -20], [0, -17], [10, -17], [10, -9], [0, -9], [0, -6], [13, -6],
                      [13, -20]], dtype=float)


def run(spec, site, scene=None):
    """Flies `spec` (the `c_object` mission) at `site`; returns the follow leg's time series
    and the turn count."""
    result = run_mission(spec, site, scene=scene)
    leg = next(iter(result.plan.legs_of("follow")))
    mask = result.log.leg_at == leg
    controller = result.run.handles.controller
    follower = controller.follower(controller.GetMyContextFromRoot(result.run.context))
    t = result.log.times[mask]
    return dict(result=result, t=t - t[0], x=result.log.state[mask].T,
                mode=Profile(result.log.profile[mask]).mode,
                estimated=Profile(result.log.profile[mask]).distance,
                clearance=result.log.clearance[mask], turns=follower.turns,
                offset=result.plan.legs_of("follow")[leg].params.offset)


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
    b.set_xlabel("time since following began (s)")
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
    from drake_auv.visualization import Scene

    spec = load_mission("c_object")
    site = load_site(spec.site, spec.seed)
    scene = Scene()
    prepare_scene(scene, site, plan_mission(spec, site))
    scene.start_recording(playback_speed=10.0, live=False)
    result = run(spec, site, scene)
    finish_recording(result["result"], scene, out / "c_object.html")
    figure(result, out / "c_object_trajectory.png")
    x = result["x"]
    summary = dict(duration_s=float(result["t"][-1]), turns=int(result["turns"]),
                   outcomes=result["result"].dive.outcomes,
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
