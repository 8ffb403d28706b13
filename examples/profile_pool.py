"""Profile following in the CIRS-like pool (reference Section 5.5.2.2, Figures 84 and 85).

The built-in `pool` mission, in one dive: horizontal following at 4 m depth, two full laps of
the 16 m x 8 m pool despite its 90 degree corners, then vertical following of the V-shaped
bottom from the shallow end up the far wall (the "cliff").

1. Clean sonar (`sonar_noise: clean`, the missions' realistic default switched off),
   exact navigation: the true frontal distance (a ray against the true pool
   along the direction the vehicle faces the wall with: its port-looking payload's axis)
   must stay within 1 m of the nominal 2 m after the first 20 s of the laps.
   Figures like Figure 84 (frontal distance and slope against time) and Figure 85 (distance
   to the cliff against time, the track in the x-z plane).
2. The same mission with spurious returns and range noise on (seeded), and again with a
   drifting navigation (compass bias, DVL scale error, random walk; seeded): the returns are
   placed with the estimated pose, as at sea.

Writes out/profile_pool/: pool_horizontal.png, pool_horizontal_spurious.png,
pool_horizontal_drift.png, pool_vertical.png, pool.html (Meshcat recording of the clean
dive), summary.json. Run:
    MPLBACKEND=Agg .venv/bin/python examples/profile_pool.py [--out DIR] [--spurious 0.1]
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from drake_auv.geometry.raycast import RayCaster
from drake_auv.mission.config import load_mission
from drake_auv.mission.plan import plan_mission
from drake_auv.mission.recording import finish_recording, prepare_scene
from drake_auv.mission.runner import run_mission
from drake_auv.mission.site import load_site
from drake_auv.vehicle.control import wrap_angle

SETTLE = 20.0  # s, the reference's pool result holds after the first 20 s of following
RANGE = 20.0  # m, of the truth rays
DRIFT = dict(heading_bias_deg=3.0, dvl_scale_error=0.03, random_walk=0.05)
RANGE_SIGMA = 0.05  # m, range noise of the spurious-returns run


def follow_leg(result, mode: str) -> dict:
    """The samples of the follow leg in `mode`: t (s since it began), x (n, 12) true state,
    profile (n, 7) the controller's output, clearance (n,) true, and its `FollowingParams`."""
    leg, config = next((i, c) for i, c in result.plan.legs_of("follow").items() if c.mode == mode)
    mask = result.log.leg_at == leg
    t = result.log.times[mask]
    return dict(t=t - t[0], x=result.log.state[mask], profile=result.log.profile[mask],
                clearance=result.log.clearance[mask], params=config.params,
                offset=config.params.offset)


def horizontal(result, caster: RayCaster) -> dict:
    """The laps, with the true frontal distance and wall slope (a ray along the direction the
    vehicle faces the wall with, its heading less the following's yaw offset: the payload's
    axis, port with the built-in mission's multibeam) beside the controller's estimates."""
    run = follow_leg(result, "horizontal")
    x, profile = run["x"], run["profile"]
    facing = x[:, 5] - run["params"].yaw_offset
    hits = caster.cast(x[:, :3], np.column_stack([np.cos(facing), np.sin(facing),
                                                  np.zeros(len(x))]), RANGE)
    wall_normal = caster.face_normals[np.maximum(hits.faces, 0)]
    lo, hi = result.site.target_mesh.bounds
    centre = 0.5 * (lo + hi)
    angle = np.unwrap(np.arctan2(x[:, 1] - centre[1], x[:, 0] - centre[0]))
    return dict(run, frontal=hits.ranges, estimated=profile[:, 0],
                true_slope=np.degrees(wrap_angle(
                    np.arctan2(-wall_normal[:, 1], -wall_normal[:, 0]) - facing)),
                est_slope=np.degrees(wrap_angle(
                    np.arctan2(-profile[:, 3], -profile[:, 2]) - facing)),
                laps=abs(angle[-1] - angle[0]) / (2 * np.pi))


def vertical(result, caster: RayCaster) -> dict:
    """The V profile, with the true horizontal distance to the cliff (the +x end wall)."""
    run = follow_leg(result, "vertical")
    forward = np.tile([1.0, 0.0, 0.0], (len(run["x"]), 1))
    return dict(run, cliff=caster.cast(run["x"][:, :3], forward, RANGE).ranges,
                estimated=run["profile"][:, 0])


def _horizontal_figure(run, title, filename):
    t, late = run["t"], run["t"] > SETTLE
    fig, (a, b) = plt.subplots(2, 1, figsize=(9, 6), sharex=True)
    a.axhspan(run["offset"] - 1, run["offset"] + 1, color="0.9", label="nominal +/- 1 m")
    a.axhline(run["offset"], color="k", lw=0.8)
    a.plot(t, run["frontal"], label="true frontal distance (along the facing direction)")
    a.plot(t, run["estimated"], lw=0.8, label="estimated distance to profile")
    a.axvline(SETTLE, color="r", ls=":", lw=0.8)
    a.set_ylabel("distance (m)")
    a.set_title(f"{title}: max |frontal - nominal| after {SETTLE:.0f} s = "
                f"{np.nanmax(np.abs(run['frontal'][late] - run['offset'])):.2f} m")
    a.legend(loc="upper right", fontsize=8)
    b.plot(t, run["true_slope"], label="true (wall hit by the facing ray)")
    b.plot(t, run["est_slope"], lw=0.8, label="estimated (profile normal)")
    b.set_ylabel("slope: wall normal vs facing (deg)")
    b.set_xlabel("time since following began (s)")
    b.set_ylim(-60, 60)
    b.legend(loc="upper right", fontsize=8)
    fig.tight_layout()
    fig.savefig(filename, dpi=120)
    plt.close(fig)


def _vertical_figure(run, world, filename):
    import trimesh

    fig, (a, b) = plt.subplots(2, 1, figsize=(9, 7))
    a.plot(run["t"], run["cliff"], label="true distance to the cliff (far wall, horizontal)")
    a.plot(run["t"], run["estimated"], lw=0.8, label="estimated distance to profile")
    a.axhline(run["offset"], color="k", lw=0.8)
    a.set_xlabel("time since following began (s)")
    a.set_ylabel("distance (m)")
    a.legend(fontsize=8)
    for segment in trimesh.intersections.mesh_plane(world, [0, 1, 0], [0, 0, 0]):
        b.plot(segment[:, 0], segment[:, 2], color="0.3", lw=1.2)
    b.plot([], [], color="0.3", label="pool section (y = 0)")
    b.plot(run["x"][:, 0], run["x"][:, 2], label="vehicle (true)")
    b.axhline(0.0, color="b", lw=0.5)
    b.set_aspect("equal")
    b.set_xlabel("x (m)")
    b.set_ylabel("z (m)")
    b.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(filename, dpi=120)
    plt.close(fig)


def _summary(run):
    error = np.abs(run["frontal"][run["t"] > SETTLE] - run["offset"])
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
    parser.add_argument("--seed", type=int, default=1, help="seed of the noisy and drift runs")
    args = parser.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    from drake_auv.visualization import Scene

    spec = load_mission("pool", overrides=["sonar_noise=clean"])
    site = load_site(spec.site, spec.seed)
    caster = RayCaster(site.world)
    scene = Scene()
    prepare_scene(scene, site, plan_mission(spec, site))
    scene.start_recording(playback_speed=10.0, live=False)
    clean = run_mission(spec, site, scene=scene)
    finish_recording(clean, scene, out / "pool.html")
    laps = horizontal(clean, caster)
    _horizontal_figure(laps, "Horizontal following, pool, 4 m depth", out / "pool_horizontal.png")
    v = vertical(clean, caster)
    _vertical_figure(v, site.world, out / "pool_vertical.png")

    noisy = horizontal(run_mission(load_mission("pool", seed=args.seed, overrides=[
        "sonar_noise=clean", f"sonar_noise.spurious_prob={args.spurious}",
        f"sonar_noise.range_sigma={RANGE_SIGMA}"]), site), caster)
    _horizontal_figure(noisy, f"With spurious returns (p = {args.spurious}) and "
                              f"{100 * RANGE_SIGMA:.0f} cm noise",
                       out / "pool_horizontal_spurious.png")
    drift = horizontal(run_mission(load_mission("pool", seed=args.seed, overrides=[
        "sonar_noise=clean", *(f"navigation.{k}={v}" for k, v in DRIFT.items())]), site),
        caster)
    _horizontal_figure(drift, f"With navigation drift ({DRIFT['heading_bias_deg']:g} deg compass"
                              f" bias, {100 * DRIFT['dvl_scale_error']:g} % DVL scale)",
                       out / "pool_horizontal_drift.png")

    summary = dict(horizontal=_summary(laps),
                   horizontal_spurious=dict(_summary(noisy), spurious_prob=args.spurious,
                                            range_sigma_m=RANGE_SIGMA, seed=args.seed),
                   horizontal_drift=dict(_summary(drift), **DRIFT, seed=args.seed),
                   vertical=dict(duration_s=float(v["t"][-1]),
                                 min_clearance_m=float(v["clearance"].min()),
                                 final_cliff_distance_m=float(v["cliff"][-1]),
                                 offset_error_after_20s_max_m=float(np.nanmax(np.abs(
                                     v["clearance"][v["t"] > SETTLE] - v["offset"])))),
                   mission_outcomes=clean.dive.outcomes)
    (out / "summary.json").write_text(json.dumps(summary, indent=2))
    print(json.dumps(summary, indent=2))
    return summary


if __name__ == "__main__":
    main()
