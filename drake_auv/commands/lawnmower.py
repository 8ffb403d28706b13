"""`drake-auv lawnmower`: the GIRONA 500 flies a lawnmower over a synthetic seabed.

The lawnmower comes from the off-line planner (`drake_auv.planning.lawnmower.plan_lawnmower`):
lanes spaced by the down-looking footprint at altitude Omega, following the terrain.

Writes `<out>/mission.html` (standalone Meshcat recording: seabed, path, vehicle and trail),
`<out>/tracking_error.png`, `<out>/path.csv` and `<out>/state.csv`: the vehicle foundation
(dynamics, allocation, tracking, navigation, visualisation) on its own.
"""

from __future__ import annotations

import numpy as np

from drake_auv.commands import add_recording_options, check_plan_options, whole_number

DEFAULT_OUT = "out/lawnmower"


def first_turn_index(path, angle_deg: float = 45.0) -> int:
    """Index of the sample where the horizontal direction of travel first turns by more than
    `angle_deg` from the first segment's (the end of the first lane); the last index if never."""
    d = np.diff(path.points[:, :2], axis=0)
    moving = np.linalg.norm(d, axis=1) > 1e-9
    if not moving.any():
        return len(path) - 1
    d = d / np.maximum(np.linalg.norm(d, axis=1, keepdims=True), 1e-12)
    first = d[np.argmax(moving)]
    turned = moving & (d @ first < np.cos(np.radians(angle_deg)))
    return int(np.argmax(turned)) if turned.any() else len(path) - 1


MAX_RELIEF_M = 40.0  # m: the synthetic seabed lies 50 m deep, its top at most 10 m deep


def check_options(args) -> None:
    """ValueError naming the option and its range, before any work: the altitude, aperture,
    overlap and speed in the mission plan step's ranges, the relief in [0, MAX_RELIEF_M] m."""
    check_plan_options([("--altitude", args.altitude, "omega"),
                        ("--aperture-deg", args.aperture_deg, "aperture_deg"),
                        ("--overlap", args.overlap, "overlap"), ("--speed", args.speed, "speed")])
    if not 0.0 <= args.relief <= MAX_RELIEF_M:
        raise ValueError(f"--relief {args.relief:g} is out of range; allowed: [0, "
                         f"{MAX_RELIEF_M:g}] m (the seabed lies 50 m deep)")


def run(args) -> int:
    from pathlib import Path

    from drake_auv.commands.outputs import MiB, output_folder
    from drake_auv.commands.simulate import draw_path, report
    from drake_auv.planning.lawnmower import lane_spacing, plan_lawnmower
    from drake_auv.planning.parameters import CoverageParameters
    from drake_auv.terrain.synthetic import random_seabed
    from drake_auv.vehicle.flight import fly_path
    from drake_auv.visualization import Scene

    width, length = args.extent
    if not (5.0 <= width <= 2000.0 and 5.0 <= length <= 2000.0):
        raise ValueError(f"--extent must be two sizes in [5, 2000] m, got {args.extent}")
    check_options(args)
    output_folder(args.out, "-o", 20 * MiB)  # mission.html, tracking_error.png, the CSVs
    cell = 1.0
    shape = (int(round(length / cell)) + 1, int(round(width / cell)) + 1)
    seabed = random_seabed(seed=args.seed, shape=shape, cell=cell, relief=args.relief)
    path = plan_lawnmower(seabed, CoverageParameters(
        omega=args.altitude, aperture_deg=args.aperture_deg, overlap=args.overlap))
    spacing = lane_spacing(args.altitude, args.aperture_deg, args.overlap)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    path.to_csv(out / "path.csv")
    scene = None
    if not args.no_html:
        scene = Scene()
        scene.add_terrain(seabed)
        draw_path(scene, path)
    print(f"lawnmower over a {width:g} m x {length:g} m random seabed (seed {args.seed}): "
          f"lanes {spacing:.2f} m apart, {args.altitude:g} m above the seabed; "
          f"{path.length:.0f} m at {args.speed:g} m/s")
    result = fly_path(path, out, args.speed, scene, playback_speed=args.playback_speed,
                      settle_samples=first_turn_index(path), progress=not args.quiet,
                      realtime_rate=args.realtime_rate)
    report(result, out)
    return 0


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser(
        "lawnmower", help="fly a lawnmower over a synthetic seabed and record it",
        description="The GIRONA 500 tracks a constant-altitude lawnmower (the planner's "
                    "plan_lawnmower) over a random smooth seabed; writes mission.html (Meshcat "
                    "recording) and tracking_error.png.")
    parser.add_argument("-o", "--out", default=DEFAULT_OUT,
                        help=f"output folder (default {DEFAULT_OUT})")
    parser.add_argument("--seed", type=whole_number, default=0, help="seed of the synthetic seabed")
    parser.add_argument("--speed", type=float, default=0.5, help="survey speed, m/s, in [0.05, 1.4] (default 0.5)")
    parser.add_argument("--extent", type=float, nargs=2, default=(50.0, 30.0),
                        metavar=("WIDTH", "LENGTH"),
                        help="seabed size along x and y, m (default 50 30)")
    parser.add_argument("--altitude", type=float, default=5.0,
                        help="survey altitude Omega above the seabed, m, in [0.5, 100] (default 5: "
                             "5.2 m lanes)")
    parser.add_argument("--aperture-deg", type=float, default=60.0,
                        help="down-looking sensor aperture, degrees in [5, 170] (default 60)")
    parser.add_argument("--overlap", type=float, default=0.1,
                        help="lane overlap fraction, in [0, 0.9] (default 0.1)")
    parser.add_argument("--relief", type=float, default=4.0,
                        help="seabed relief peak to peak, m, in [0, 40] (default 4)")
    add_recording_options(parser, playback_speed=10.0)
    parser.set_defaults(func=run)
