"""`drake-auv demo`: the GIRONA 500 flies a lawnmower over a synthetic seabed.

Writes `<out>/mission.html` (standalone Meshcat recording: seabed, path, vehicle and trail),
`<out>/tracking_error.png`, `<out>/path.csv` and `<out>/state.csv`. At this stage the demo
exercises the vehicle foundation (dynamics, allocation, tracking, navigation, visualisation);
the full coverage mission grows on top of it.
"""

from __future__ import annotations

import numpy as np

DEFAULT_OUT = "out/demo"


def terrain_following_lanes(bathy, lane_length: float, lane_spacing: float, lanes: int,
                            altitude: float, origin=(5.0, 5.0), sample: float = 1.0):
    """A lawnmower of `lanes` lanes along world x, `lane_spacing` apart, flown at `altitude`
    above the seabed; heading along each lane, sensor looking down, label "lawnmower".

    Returns the Path and the number of samples in its first lane.
    """
    from drake_auv.planning.path import Path

    for name, value, low in (("lane_length", lane_length, 1.0), ("lane_spacing", lane_spacing, 0.5),
                             ("altitude", altitude, 0.5), ("sample", sample, 0.05)):
        if not (np.isfinite(value) and value >= low):
            raise ValueError(f"{name} must be >= {low} m, got {value}")
    if int(lanes) != lanes or lanes < 1:
        raise ValueError(f"lanes must be an integer >= 1, got {lanes}")
    x_min, x_max, y_min, y_max = bathy.extent
    x0, y0 = origin
    if x0 < x_min or x0 + lane_length > x_max or y0 < y_min or y0 + (lanes - 1) * lane_spacing > y_max:
        raise ValueError(f"the lawnmower ({lane_length} m x {(lanes - 1) * lane_spacing} m from "
                         f"{origin}) does not fit the seabed extent {bathy.extent}")
    along = np.linspace(0.0, lane_length, int(np.ceil(lane_length / sample)) + 1)
    points, heading = [], []
    for i in range(int(lanes)):
        xs = x0 + (along if i % 2 == 0 else along[::-1])
        ys = np.full_like(xs, y0 + i * lane_spacing)
        points.append(np.column_stack([xs, ys, bathy.elevation_at(xs, ys) + altitude]))
        heading.append(np.full(len(xs), 0.0 if i % 2 == 0 else np.pi))
    points, heading = np.vstack(points), np.concatenate(heading)
    if not np.all(np.isfinite(points)):
        raise ValueError("the lawnmower crosses no-data cells of the seabed")
    return Path(points, heading, (0.0, 0.0, -1.0), "lawnmower"), len(along)


def run(args) -> int:
    from pathlib import Path as FilePath

    from drake_auv.commands.simulate import fly_path, report
    from drake_auv.terrain.synthetic import random_seabed
    from drake_auv.visualization import Scene

    lane_length, spacing, lanes = args.lane_length, args.lane_spacing, args.lanes
    margin = 5.0
    cell = 1.0
    shape = (int(np.ceil(((lanes - 1) * spacing + 2 * margin) / cell)) + 1,
             int(np.ceil((lane_length + 2 * margin) / cell)) + 1)
    seabed = random_seabed(seed=args.seed, shape=shape, cell=cell, relief=args.relief)
    path, first_lane = terrain_following_lanes(seabed, lane_length, spacing, lanes,
                                               args.altitude, origin=(margin, margin))
    out = FilePath(args.out)
    out.mkdir(parents=True, exist_ok=True)
    path.to_csv(out / "path.csv")
    scene = None
    if not args.no_html:
        scene = Scene()
        scene.add_terrain(seabed)
    print(f"lawnmower: {lanes} lanes of {lane_length:g} m, {spacing:g} m apart, "
          f"{args.altitude:g} m above a random seabed (seed {args.seed}); {path.length:.0f} m "
          f"at {args.speed:g} m/s")
    result = fly_path(path, out, args.speed, scene, playback_speed=args.playback_speed,
                      settle_samples=first_lane - 1, progress=not args.quiet,
                      realtime_rate=args.realtime_rate)
    report(result, out)
    return 0


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser(
        "demo", help="fly a lawnmower over a synthetic seabed and record it",
        description="The GIRONA 500 tracks a terrain-following lawnmower over a random smooth "
                    "seabed; writes mission.html (Meshcat recording) and tracking_error.png.")
    parser.add_argument("--out", default=DEFAULT_OUT, help=f"output folder (default {DEFAULT_OUT})")
    parser.add_argument("--seed", type=int, default=0, help="seed of the synthetic seabed")
    parser.add_argument("--speed", type=float, default=0.5, help="survey speed, m/s (default 0.5)")
    parser.add_argument("--lane-length", type=float, default=50.0, help="m (default 50)")
    parser.add_argument("--lane-spacing", type=float, default=5.0, help="m (default 5)")
    parser.add_argument("--lanes", type=int, default=6, help="number of lanes (default 6)")
    parser.add_argument("--altitude", type=float, default=3.0,
                        help="altitude above the seabed, m (default 3)")
    parser.add_argument("--relief", type=float, default=4.0,
                        help="seabed relief peak to peak, m (default 4)")
    parser.add_argument("--playback-speed", type=float, default=10.0,
                        help="the HTML animation plays this many times faster than real time")
    parser.add_argument("--realtime-rate", type=float, default=0.0,
                        help="pace the simulation to watch it live (1 = real time; default 0 = "
                             "as fast as possible)")
    parser.add_argument("--no-html", action="store_true", help="skip the Meshcat recording")
    parser.add_argument("--quiet", action="store_true", help="no progress bar")
    parser.set_defaults(func=run)
