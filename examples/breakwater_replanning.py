"""The breakwater mission of the reference (Section 5.5.3): realtime replanning on and off.

The right-most concrete block of the `breakwater` scenario is targeted by a single contour at
5 m depth with offset Omega = 6 m: an open semicircle around its three free faces, since the
0.5 m gaps between blocks leave no room to pass. The nominal contour is planned on a prior
map shifted by up to 5 m (seeded); the vehicle carries a port-looking multibeam and a
horizontal pencil-beam profiler, both at 20 m range. The same mission is flown twice per seed:
with the replanner (octree map + STOMP at 1 Hz) and nominal-only. Written to `--out`:
`breakwater_replanning.md` (the table), `breakwater_replanning.png` (like the reference's
Figure 88) and `breakwater_replanning.html` (Meshcat recording of the first replanning run).

    .venv/bin/python examples/breakwater_replanning.py --seeds 10 --out out/breakwater
"""

from __future__ import annotations

import argparse
import time
from dataclasses import replace
from pathlib import Path as FilePath

import contourpy
import matplotlib
import numpy as np
import trimesh
from pydrake.systems.analysis import Simulator
from scipy import ndimage
from tqdm import tqdm

from drake_auv.diagrams.replanning import build_replanning_diagram
from drake_auv.geometry.distance import mesh_distance
from drake_auv.vehicle.navigation import NavigationParams
from drake_auv.planning.path import Path
from drake_auv.planning.polyline import motion_heading, resample
from drake_auv.replanning.section import ReplanningParameters
from drake_auv.scenarios import get_scenario
from drake_auv.visualization.octree import depth_colours, draw_octree
from drake_auv.visualization.scene import Scene

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402 (after the backend is chosen)
from matplotlib.collections import LineCollection  # noqa: E402

CAMERA_APERTURE = np.radians(60.0)  # the reference's payload camera
VEHICLE_RADIUS = 1.0  # m, GIRONA 500 half-length, the contact threshold


def nominal_contour(prior, depth: float, omega: float, block_size: float, start,
                    spacing: float = 1.0, overrun: float = 7.0) -> Path:
    """The nominal path planned on the prior map: the offset-Omega contour, at `depth`, of the
    cross-section of the structure, kept around the right-most block (x beyond its west face
    less `overrun`, m: the largest expected map error plus 2 m, so both side faces are flown
    past their ends wherever the error puts the block), flown counter-clockwise (structure to
    port), with `start` prepended (the transit from the start)."""
    solid = np.nan_to_num(prior.z, nan=-np.inf) > -depth
    if not solid.any():
        raise ValueError(f"the prior map has no structure above {depth} m depth")
    cell = prior.spacing[0]
    dist = ndimage.distance_transform_edt(~solid, sampling=(prior.spacing[1], cell))
    # Solid cell centres lie up to half a cell inside the face: the level compensates.
    lines = contourpy.contour_generator(prior.x, prior.y, dist).lines(omega + 0.5 * cell)
    line = max(lines, key=len)
    xs = prior.x[np.nonzero(solid.any(axis=0))[0]]
    west = xs.max() + 0.5 * cell - block_size  # the right-most block's west face
    keep = line[:, 0] >= west - overrun
    # The kept part is one arc of the loop: roll the loop so it is contiguous.
    if np.allclose(line[0], line[-1]):
        line = line[:-1]
        keep = keep[:-1]
        first = np.flatnonzero(keep & ~np.roll(keep, 1))
        if first.size:
            line, keep = np.roll(line, -first[0], axis=0), np.roll(keep, -first[0])
    arc = line[keep]
    # Counter-clockwise around the block: the structure (centre of the arc's chord side) to port.
    centre = np.array([xs.max() + 0.5 * cell - 0.5 * block_size, arc[:, 1].mean()])
    rel = arc - centre
    if np.sum(rel[:-1, 0] * rel[1:, 1] - rel[:-1, 1] * rel[1:, 0]) < 0:
        arc = arc[::-1]
    arc = resample(arc, spacing)
    points = np.column_stack([arc, np.full(len(arc), -depth)])
    points = np.vstack([np.asarray(start, dtype=float)[:3], points])
    heading = motion_heading(points)
    sensor = np.column_stack([-np.sin(heading), np.cos(heading), np.zeros(len(heading))])
    return Path(points, heading, sensor, "slice")



def surface_distance(world, faces: np.ndarray):
    """A function giving the exact distance (m) from points to some faces of the world."""
    sub = world.submesh([np.flatnonzero(faces)], append=True)
    return lambda points: mesh_distance(sub, points)


def mission_faces(scenario):
    """(targeted, structure, near): the faces to cover, the breakwater's faces above the
    seabed, and every face within 30 m of the target.

    The block's west face looks into the 0.5 m gap to its neighbour: no path sees it, so the
    targeted faces are the three others (the reference's "three of the four vertical faces").
    """
    world = scenario.world
    centres = world.triangles_center
    targeted = scenario.target_faces & (world.face_normals[:, 0] > -0.5)
    near = np.all(np.abs(centres[:, :2]) < 30.0, axis=1)
    seabed = -10.0  # the breakwater scenario's flat seabed
    structure = near & (centres[:, 2] > seabed + 0.05)
    return targeted, structure, near


def run_mission(scenario, nominal: Path, seed: int, replanning: bool, speed: float,
                navigation: NavigationParams | None, params: ReplanningParameters,
                resolution: float = 0.5, scene: Scene | None = None) -> dict:
    """Flies one mission (octree voxels of `resolution` m); returns the diagram handles, the
    root context and timings."""
    targeted, _, _ = mission_faces(scenario)
    diagram, handles = build_replanning_diagram(
        scenario.world, nominal, scenario.start_state, replanning=replanning, params=params,
        speed=speed, navigation=navigation, resolution=resolution,
        max_range=scenario.params["max_range"], seed=seed, scene=scene, target_faces=targeted)
    simulator = Simulator(diagram)
    duration = 1.25 * nominal.times(speed)[-1] + 20.0
    start = time.perf_counter()
    simulator.AdvanceTo(duration)
    return dict(handles=handles, context=simulator.get_context(), duration=duration,
                wall=time.perf_counter() - start)


def mission_metrics(run: dict, nominal: Path, speed: float, omega: float,
                    to_target, to_structure, to_world) -> dict:
    """True distance to the structure (the breakwater's blocks) over the survey (from the
    first approach within Omega + 2 m of the target block to the end of the plan), minimum
    clearance to anything (seabed included) over the whole run, coverage and step times."""
    h, context = run["handles"], run["context"]
    log = h.state_log.FindLog(context)
    t, xyz = log.sample_times(), log.data()[:3].T
    d = to_structure(xyz)
    if h.replanner is not None:
        done = [s.time for s in h.replanner.log if s.plan is None]
        end = done[0] if done else run["duration"]
    else:
        end = nominal.times(speed)[-1]
    approached = np.flatnonzero(to_target(xyz) < omega + 2.0)
    begin = t[approached[0]] if approached.size else t[-1]
    survey = (t >= begin) & (t <= end)
    steps = np.array([s.wall_time for s in h.replanner.log]) * 1e3 if h.replanner else None

    def coverage(recorder):
        return float(recorder.coverage_output.Eval(recorder.GetMyContextFromRoot(context))[0])

    return dict(mean=d[survey].mean(), sd=d[survey].std(), min=d[survey].min(),
                clearance=to_world(xyz).min(), camera=coverage(h.camera_coverage),
                multibeam=coverage(h.multibeam_coverage),
                step_median=np.median(steps) if steps is not None else np.nan,
                step_p95=np.percentile(steps, 95) if steps is not None else np.nan,
                rtf=run["duration"] / run["wall"], xyz=xyz, survey=survey)


def figure(scenario, runs: list[tuple[str, dict, dict]], nominal: Path, filename) -> None:
    """Top views like the reference's Figure 88: nominal path (blue dotted), executed
    trajectory (black, with arrows), the last optimised section (red dotted), occupied voxels
    of the on-line map (coloured by depth), the true structure at the survey depth (grey)."""
    depth = scenario.params["depth"]
    segments = trimesh.intersections.mesh_plane(scenario.world, [0, 0, 1], [0, 0, -depth])
    fig, axes = plt.subplots(1, len(runs), figsize=(7 * len(runs), 6.5), squeeze=False)
    for ax, (title, run, m) in zip(axes[0], runs):
        ax.add_collection(LineCollection(segments[:, :, :2], colors="0.35", linewidths=2.5,
                                         zorder=1, label=f"true structure at {depth:g} m"))
        occ = run["handles"].mapper.octree_map.occupied_points()
        occ = occ[np.all(np.abs(occ[:, :2]) < 25.0, axis=1) & (np.abs(occ[:, 2] + depth) < 3.0)]
        order = np.argsort(occ[:, 2])
        ax.scatter(occ[order, 0], occ[order, 1], s=4, marker="s", zorder=2,
                   c=depth_colours(occ[order, 2]) / 255.0,
                   label="occupied voxels within 3 m of the depth")
        ax.plot(nominal.points[:, 0], nominal.points[:, 1], ":", color="tab:blue", lw=2,
                zorder=3, label="nominal path (prior map)")
        xyz = m["xyz"]
        ax.plot(xyz[:, 0], xyz[:, 1], "-", color="k", lw=1.2, zorder=4,
                label="executed trajectory (true)")
        idx = np.arange(0, len(xyz) - 1, max(len(xyz) // 25, 1))
        ax.quiver(xyz[idx, 0], xyz[idx, 1], xyz[idx + 1, 0] - xyz[idx, 0],
                  xyz[idx + 1, 1] - xyz[idx, 1], angles="xy", zorder=4, width=0.004)
        replanner = run["handles"].replanner
        if replanner is not None:
            last = [s.plan for s in replanner.log if s.plan is not None]
            if last:
                tr = last[-1].trajectory
                ax.plot(tr[:, 0], tr[:, 1], ":", color="tab:red", lw=2.5, zorder=5,
                        label="last optimised section")
        ax.set_title(f"{title}: true distance {m['mean']:.2f} m (sd {m['sd']:.2f}), "
                     f"min {m['min']:.2f} m", fontsize=10)
        ax.set_xlim(-22, 16)
        ax.set_ylim(-16, 16)
        ax.set_aspect("equal")
        ax.set_xlabel("x (m)")
        ax.set_ylabel("y (m)")
        ax.legend(loc="lower left", fontsize=7)
    fig.tight_layout()
    fig.savefig(filename, dpi=130)
    plt.close(fig)


def write_html(scenario, nominal: Path, seed: int, speed: float, navigation, params,
               resolution: float, filename) -> None:
    """Meshcat recording of one replanning run: world, nominal path, vehicle, octree."""
    _, _, near = mission_faces(scenario)
    scene = Scene()
    scene.add_mesh("world", scenario.world.submesh([np.flatnonzero(near)], append=True),
                   rgba=(0.6, 0.6, 0.6, 1.0))
    scene.add_path("nominal", nominal, rgba=(0.1, 0.3, 1.0, 1.0))
    scene.start_recording(playback_speed=10.0)
    run = run_mission(scenario, nominal, seed, True, speed, navigation, params, resolution,
                      scene)
    draw_octree(scene.meshcat, scene.path_of("octree"), run["handles"].mapper.octree_map)
    xyz = run["handles"].state_log.FindLog(run["context"]).data()[:3].T
    scene.add_path("executed", xyz, rgba=(1.0, 1.0, 1.0, 1.0))
    scene.write_html(filename)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=10, help="prior-map error seeds (10)")
    parser.add_argument("--error", type=float, default=5.0,
                        help="prior-map horizontal error, m, in [0, 5] (5)")
    parser.add_argument("--no-drift", action="store_true",
                        help="exact navigation (default: DVL-like drift)")
    parser.add_argument("--no-html", action="store_true", help="skip the Meshcat recording")
    parser.add_argument("--radius", type=float, default=None,
                        help="replanning range R, m (default: the scenario's, 5)")
    parser.add_argument("--max-waypoints", type=int, default=10, help="K (10)")
    parser.add_argument("--rollouts", type=int, default=10, help="STOMP rollouts (10)")
    parser.add_argument("--iterations", type=int, default=40, help="STOMP iteration cap (40)")
    parser.add_argument("--voxel", type=float, default=0.5, help="octree voxel edge, m (0.5)")
    parser.add_argument("--out", type=FilePath, default=FilePath("out/breakwater"))
    args = parser.parse_args(argv)
    if args.seeds < 1:
        raise ValueError(f"--seeds must be >= 1, got {args.seeds}")
    args.out.mkdir(parents=True, exist_ok=True)
    scenario = get_scenario("breakwater")
    p = scenario.params
    speed, omega = p["speed"], p["omega"]
    stomp = ReplanningParameters().stomp
    params = ReplanningParameters(
        radius=p["replan_radius"] if args.radius is None else args.radius,
        max_waypoints=args.max_waypoints, omega=omega,
        stomp=replace(stomp, num_rollouts=args.rollouts, max_iterations=args.iterations))
    _, structure, near = mission_faces(scenario)
    to_target = surface_distance(scenario.world, scenario.target_faces)
    to_structure = surface_distance(scenario.world, structure)
    to_world = surface_distance(scenario.world, near)
    rows, figure_runs = [], []
    for seed in tqdm(range(args.seeds), desc="seeds"):
        navigation = None if args.no_drift else NavigationParams(
            heading_bias=np.radians(1.0), scale_error=0.01, random_walk=0.02, seed=seed)
        prior = scenario.prior_map(error_m=args.error, seed=seed)
        nominal = nominal_contour(prior, p["depth"], omega, p["block_size"],
                                  scenario.start_state[:3])
        for mode, replanning in (("replanning", True), ("nominal only", False)):
            run = run_mission(scenario, nominal, seed, replanning, speed, navigation, params,
                              args.voxel)
            m = mission_metrics(run, nominal, speed, omega, to_target, to_structure, to_world)
            rows.append((mode, seed, m))
            if seed == 0:
                figure_runs.append((mode, run, m))
        if seed == 0:
            figure(scenario, figure_runs, nominal, args.out / "breakwater_replanning.png")
            if not args.no_html:
                write_html(scenario, nominal, seed, speed, navigation, params, args.voxel,
                           args.out / "breakwater_replanning.html")
    table = report(rows, args, omega)
    (args.out / "breakwater_replanning.md").write_text(table)
    print(table)


def _ms(value: float) -> str:
    return "-" if np.isnan(value) else f"{value:.1f}"


def report(rows, args, omega: float) -> str:
    """The table: per run, then per mode over all seeds."""
    head = ("| mode | seed | mean d (m) | sd d (m) | min d (m) | min clearance (m) | contact | "
            "camera cov. | multibeam cov. | step median (ms) | step p95 (ms) | RTF |\n"
            "|---|---|---|---|---|---|---|---|---|---|---|---|\n")
    lines = [f"# Breakwater replanning: {args.seeds} seeds, prior-map error {args.error} m, "
             f"navigation drift {'off' if args.no_drift else 'on'}, Omega {omega} m, "
             f"K {args.max_waypoints}, {args.rollouts} rollouts, {args.iterations} iterations, "
             f"voxel {args.voxel} m\n",
             "d: true distance to the breakwater (its blocks) over the survey; clearance: to any "
             f"structure or the seabed over the whole run; contact: clearance <= "
             f"{VEHICLE_RADIUS} m (vehicle radius); coverage: share of the three targeted "
             "faces' area seen by the side-looking camera (60 deg, 8 m) and multibeam.\n",
             head]
    for mode, seed, m in rows:
        lines.append(f"| {mode} | {seed} | {m['mean']:.2f} | {m['sd']:.2f} | {m['min']:.2f} | "
                     f"{m['clearance']:.2f} | {'YES' if m['clearance'] <= VEHICLE_RADIUS else 'no'}"
                     f" | {m['camera']:.3f} | {m['multibeam']:.3f} | {_ms(m['step_median'])} | "
                     f"{_ms(m['step_p95'])} | {m['rtf']:.1f} |\n")
    lines.append("\n## Over all seeds\n\n| mode | mean d (m) | mean sd (m) | worst min d (m) "
                 "| worst clearance (m) | contacts | camera cov. | multibeam cov. | step median "
                 "(ms) | step p95 (ms) |\n|---|---|---|---|---|---|---|---|---|---|\n")
    for mode in ("replanning", "nominal only"):
        ms = [m for md, _, m in rows if md == mode]
        agg = lambda k: np.array([m[k] for m in ms])  # noqa: E731
        lines.append(f"| {mode} | {agg('mean').mean():.2f} | {agg('sd').mean():.2f} | "
                     f"{agg('min').min():.2f} | {agg('clearance').min():.2f} | "
                     f"{int((agg('clearance') <= VEHICLE_RADIUS).sum())}/{len(ms)} | "
                     f"{agg('camera').mean():.3f} | {agg('multibeam').mean():.3f} | "
                     f"{_ms(np.median(agg('step_median')))} | {_ms(np.max(agg('step_p95')))} |\n")
    return "".join(lines)


if __name__ == "__main__":
    main()
