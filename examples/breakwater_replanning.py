"""The breakwater mission of the reference (Section 5.5.3): realtime replanning on and off.

The built-in `breakwater` mission: the east end block of the breakwater is targeted by one
contour at 5 m depth with offset Omega = 6 m around its free faces (the 0.5 m gaps between
blocks leave no room to pass), planned on a prior map shifted by up to 5 m (seeded); the
vehicle carries a port-looking multibeam and a horizontal pencil-beam profiler, both at 20 m
range. The same mission is flown twice per seed: with the replanner (octree map + STOMP at
1 Hz) and nominal-only (`steps.1.survey.replanning=false`). Written to `--out`:
`breakwater_replanning.md` (the table, from each dive's `drake_auv.mission.report.summary.summarise`),
`breakwater_replanning.png` (like the reference's Figure 88) and `breakwater_replanning.html`
(Meshcat recording of the first replanning dive).

    .venv/bin/python examples/breakwater_replanning.py --seeds 10 --out out/breakwater
"""

from __future__ import annotations

import argparse
from pathlib import Path

import matplotlib
import numpy as np
import trimesh

from drake_auv.mission.config import load_mission
from drake_auv.mission.plan import plan_mission
from drake_auv.mission.recording import finish_recording, prepare_scene
from drake_auv.mission.report.summary import summarise
from drake_auv.mission.runner import VEHICLE_RADIUS, run_mission
from drake_auv.mission.site import load_site
from drake_auv.progress import track
from drake_auv.signals import VehicleState
from drake_auv.visualization.octree import depth_colours

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402 (after the backend is chosen)
from matplotlib.collections import LineCollection  # noqa: E402

MODES = (("replanning", True), ("nominal only", False))


def overrides(args, replanning: bool) -> list[str]:
    """The `breakwater` mission's overrides for the command-line options."""
    out = [f"site.prior_error_m={args.error}", f"replanner.K={args.max_waypoints}",
           f"replanner.rollouts={args.rollouts}", f"replanner.iterations={args.iterations}",
           f"replanner.voxel_m={args.voxel}",
           f"steps.1.survey.replanning={str(replanning).lower()}"]
    if args.radius is not None:
        out.append(f"replanner.R={args.radius}")
    if args.no_drift:
        out += ["navigation.heading_bias_deg=0", "navigation.dvl_scale_error=0",
                "navigation.random_walk=0"]
    return out


def survey_xyz(result) -> np.ndarray:
    """(n, 3) true positions of the survey leg."""
    survey = [i for i, leg in enumerate(result.plan.legs) if leg.phase == "survey"]
    return VehicleState(result.log.state[np.isin(result.log.leg_at, survey)]).position


def figure(runs, filename) -> None:
    """Top views like the reference's Figure 88: nominal path (blue dotted), executed survey
    (black, with arrows), the last optimised section (red dotted), occupied voxels of the
    on-line map within 3 m of the depth (coloured by depth), the true structure at the survey
    depth (grey)."""
    fig, axes = plt.subplots(1, len(runs), figsize=(7 * len(runs), 6.5), squeeze=False)
    for ax, (title, result, summary) in zip(axes[0], runs):
        depth = result.spec.steps[0].depth
        segments = trimesh.intersections.mesh_plane(result.site.world, [0, 0, 1],
                                                    [0, 0, -depth])
        ax.add_collection(LineCollection(segments[:, :, :2], colors="0.35", linewidths=2.5,
                                         zorder=1, label=f"true structure at {depth:g} m"))
        occ = result.mapping.online_map.map.occupied_points()
        occ = occ[np.all(np.abs(occ[:, :2]) < 25.0, axis=1) & (np.abs(occ[:, 2] + depth) < 3.0)]
        order = np.argsort(occ[:, 2])
        ax.scatter(occ[order, 0], occ[order, 1], s=4, marker="s", zorder=2,
                   c=depth_colours(occ[order, 2]) / 255.0,
                   label="occupied voxels within 3 m of the depth")
        nominal = result.plan.nominal.points
        ax.plot(nominal[:, 0], nominal[:, 1], ":", color="tab:blue", lw=2, zorder=3,
                label="nominal path (prior map)")
        xyz = survey_xyz(result)
        ax.plot(xyz[:, 0], xyz[:, 1], "-", color="k", lw=1.2, zorder=4,
                label="executed survey (true)")
        idx = np.arange(0, len(xyz) - 1, max(len(xyz) // 25, 1))
        ax.quiver(xyz[idx, 0], xyz[idx, 1], xyz[idx + 1, 0] - xyz[idx, 0],
                  xyz[idx + 1, 1] - xyz[idx, 1], angles="xy", zorder=4, width=0.004)
        replanner = result.run.handles.replanner
        section = (replanner.section(replanner.GetMyContextFromRoot(result.run.context))
                   if replanner is not None else None)
        if section is not None:
            ax.plot(section.trajectory[:, 0], section.trajectory[:, 1], ":", color="tab:red",
                    lw=2.5, zorder=5, label="last optimised section")
        d = summary["distance_to_target"]
        ax.set_title(f"{title}: true distance {d['mean_m']:.2f} m (sd {d['sd_m']:.2f}), "
                     f"min {d['min_m']:.2f} m", fontsize=10)
        ax.set_xlim(-22, 16)
        ax.set_ylim(-16, 16)
        ax.set_aspect("equal")
        ax.set_xlabel("x (m)")
        ax.set_ylabel("y (m)")
        ax.legend(loc="lower left", fontsize=7)
    fig.tight_layout()
    fig.savefig(filename, dpi=130)
    plt.close(fig)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=10, help="prior-map error seeds (10)")
    parser.add_argument("--error", type=float, default=5.0,
                        help="prior-map horizontal error, m, in [0, 5] (5)")
    parser.add_argument("--no-drift", action="store_true",
                        help="exact navigation (default: DVL-like drift)")
    parser.add_argument("--no-html", action="store_true", help="skip the Meshcat recording")
    parser.add_argument("--radius", type=float, default=None,
                        help="replanning range R, m (default: the mission's, 5)")
    parser.add_argument("--max-waypoints", type=int, default=10, help="K (10)")
    parser.add_argument("--rollouts", type=int, default=10, help="STOMP rollouts (10)")
    parser.add_argument("--iterations", type=int, default=40, help="STOMP iteration cap (40)")
    parser.add_argument("--voxel", type=float, default=0.5, help="octree voxel edge, m (0.5)")
    parser.add_argument("--out", type=Path, default=Path("out/breakwater"))
    args = parser.parse_args(argv)
    if args.seeds < 1:
        raise ValueError(f"--seeds must be >= 1, got {args.seeds}")
    if not 0.0 <= args.error <= 5.0:
        raise ValueError(f"--error must be in [0, 5] m, got {args.error}")
    args.out.mkdir(parents=True, exist_ok=True)
    rows, figure_runs = [], []
    for seed in track(range(args.seeds), "seeds"):
        for mode, replanning in MODES:
            spec = load_mission("breakwater", seed=seed, overrides=overrides(args, replanning))
            site = load_site(spec.site, spec.seed)
            scene = None
            if seed == 0 and replanning and not args.no_html:
                from drake_auv.visualization import Scene

                scene = Scene()
                prepare_scene(scene, site, plan_mission(spec, site))
                scene.start_recording(playback_speed=10.0, live=False)
            result = run_mission(spec, site, scene=scene, progress=False)
            if scene is not None:
                finish_recording(result, scene, args.out / "breakwater_replanning.html")
            summary = summarise(result)
            rows.append((mode, seed, summary))
            if seed == 0:
                figure_runs.append((mode, result, summary))
        if seed == 0:
            figure(figure_runs, args.out / "breakwater_replanning.png")
            figure_runs = []
    table = report(rows, args)
    (args.out / "breakwater_replanning.md").write_text(table)
    print(table)


def _ms(value) -> str:
    return "-" if value is None or np.isnan(value) else f"{value:.1f}"


def _row(s: dict) -> dict:
    """The table's numbers of one dive's summary."""
    d, c, t = s["distance_to_target"], s["coverage"], s["timing"]
    return dict(mean=d["mean_m"], sd=d["sd_m"], min=d["min_m"],
                map_mean=np.nan if d["map_mean_m"] is None else d["map_mean_m"],
                clearance=s["min_clearance_m"],
                contact=s["contact"], camera=c["camera"], multibeam=c["multibeam"],
                step_median=t.get("replan_median_ms", np.nan),
                step_p95=t.get("replan_p95_ms", np.nan), rtf=t["real_time_factor"])


def report(rows, args) -> str:
    """The table: per dive, then per mode over all seeds."""
    omega = rows[0][2]["plan"]["omega_m"]
    head = ("| mode | seed | mean d (m) | sd d (m) | min d (m) | mean d to map (m) | "
            "min clearance (m) | contact | camera cov. | multibeam cov. | step median (ms) | "
            "step p95 (ms) | RTF |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|\n")
    lines = [f"# Breakwater replanning: {args.seeds} seeds, prior-map error {args.error} m, "
             f"navigation drift {'off' if args.no_drift else 'on'}, Omega {omega} m, "
             f"K {args.max_waypoints}, {args.rollouts} rollouts, {args.iterations} iterations, "
             f"voxel {args.voxel} m\n",
             f"d: true distance to the target block over the survey samples within 2 Omega "
             "(d to map: the same against the on-line map's voxels on the block); "
             f"clearance: to any structure or the seabed over the whole dive; contact: "
             f"clearance <= {VEHICLE_RADIUS} m (vehicle radius); coverage: share of the target "
             "block's area seen by the port-looking camera and multibeam over the dive.\n",
             head]
    values = [(mode, seed, _row(s)) for mode, seed, s in rows]
    for mode, seed, m in values:
        lines.append(f"| {mode} | {seed} | {m['mean']:.2f} | {m['sd']:.2f} | {m['min']:.2f} | "
                     f"{m['map_mean']:.2f} | {m['clearance']:.2f} | "
                     f"{'YES' if m['contact'] else 'no'} | {m['camera']:.3f} | "
                     f"{m['multibeam']:.3f} | {_ms(m['step_median'])} | "
                     f"{_ms(m['step_p95'])} | {m['rtf']:.1f} |\n")
    lines.append("\n## Over all seeds\n\n| mode | mean d (m) | mean sd (m) | worst min d (m) "
                 "| worst clearance (m) | contacts | camera cov. | multibeam cov. | step median "
                 "(ms) | step p95 (ms) |\n|---|---|---|---|---|---|---|---|---|---|\n")
    for mode, _ in MODES:
        ms = [m for md, _, m in values if md == mode]
        agg = lambda k: np.array([m[k] for m in ms], dtype=float)  # noqa: E731
        lines.append(f"| {mode} | {agg('mean').mean():.2f} | {agg('sd').mean():.2f} | "
                     f"{agg('min').min():.2f} | {agg('clearance').min():.2f} | "
                     f"{int(agg('contact').sum())}/{len(ms)} | "
                     f"{agg('camera').mean():.3f} | {agg('multibeam').mean():.3f} | "
                     f"{_ms(np.median(agg('step_median')))} | {_ms(np.max(agg('step_p95')))} |\n")
    return "".join(lines)


if __name__ == "__main__":
    main()
