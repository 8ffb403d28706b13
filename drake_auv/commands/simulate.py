"""`drake-auv simulate`: fly a path CSV with the GIRONA 500 and record the run.

Writes `<out>/mission.html` (standalone Meshcat recording), `<out>/tracking_error.png`
(cross-track error over time) and `<out>/state.csv` (the logged true state), by
`vehicle.flight.fly_path`; `draw_path` and `report` are shared with `drake-auv lawnmower`.
"""

from __future__ import annotations

import numpy as np

from drake_auv.commands import add_recording_options, whole_number

DEFAULT_OUT = "out/simulate"


def draw_path(scene, path) -> None:
    """Draws the `path` to fly into `scene`, named in its legend (a path too short to draw is
    left to `fly_path` to refuse)."""
    from drake_auv.visualization.legend import LegendEntry, css_colour
    from drake_auv.visualization.scene import PATH_RGBA

    if len(path) >= 2:
        scene.add_legend(LegendEntry("path", "orange line", "the path to fly",
                                     css_colour(PATH_RGBA), scene.add_path("path", path)))


def report(result, out_dir) -> None:
    """Prints a `vehicle.flight.FlightResult`'s statistics and the files written."""
    print(f"flew {result.times[-1]:.0f} s in {result.wall_seconds:.1f} s wall "
          f"({result.real_time_factor:.0f}x real time); cross-track RMS {result.rms:.3f} m, "
          f"max {result.max:.3f} m after the first segment")
    print(f"wrote {out_dir}/mission.html (open it in a browser), {out_dir}/tracking_error.png, "
          f"{out_dir}/state.csv")


def run(args) -> int:
    from drake_auv.commands.outputs import MiB, output_folder
    from drake_auv.vehicle.navigation import NavigationParams
    from drake_auv.planning.path import PlannedPath
    from drake_auv.vehicle.flight import check_below_surface, fly_path
    from drake_auv.visualization import Scene

    path = PlannedPath.from_csv(args.path_csv)
    check_below_surface(path, args.path_csv, first_row=2)  # row 1: the header
    output_folder(args.out, "-o", 20 * MiB)  # mission.html, tracking_error.png, state.csv
    navigation = NavigationParams(heading_bias=np.radians(args.heading_bias_deg),
                                  random_walk=args.random_walk, seed=args.seed)
    scene = None
    if not args.no_html:
        scene = Scene()
        draw_path(scene, path)
    result = fly_path(path, args.out, args.speed, scene, navigation, args.playback_speed,
                      progress=not args.quiet, realtime_rate=args.realtime_rate)
    report(result, args.out)
    return 0


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser(
        "simulate", help="fly a path CSV with the GIRONA 500 and record it",
        description="Flies a path (CSV from `drake-auv plan` or PlannedPath.to_csv) with the simulated "
                    "GIRONA 500 and writes a Meshcat HTML recording and a tracking-error plot.")
    parser.add_argument("path_csv", help="path CSV: x,y,z,heading,sensor_x,sensor_y,sensor_z,label")
    parser.add_argument("-o", "--out", default=DEFAULT_OUT,
                        help=f"output folder (default {DEFAULT_OUT})")
    parser.add_argument("--speed", type=float, default=0.5, help="survey speed, m/s (default 0.5)")
    parser.add_argument("--heading-bias-deg", type=float, default=0.0,
                        help="compass bias of the dead-reckoning navigation, degrees (default 0)")
    parser.add_argument("--random-walk", type=float, default=0.0,
                        help="navigation drift random walk, m per sqrt(m travelled) (default 0)")
    parser.add_argument("--seed", type=whole_number, default=0, help="seed of the navigation noise")
    add_recording_options(parser, playback_speed=10.0)
    parser.set_defaults(func=run)
