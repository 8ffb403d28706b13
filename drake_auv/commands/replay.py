"""`drake-auv replay LOG -o OUT`: a recorded dive through the on-line map, the point cloud,
the surface and, with the true meshes, the scores.

LOG is a ROS 1 bag, a rosbag2 folder or an MCAP file (a vehicle's own, or a dive's
`dive.mcap`) with odometry (`nav_msgs/Odometry` or `geometry_msgs/PoseStamped`), sonar
returns (`sensor_msgs/PointCloud2` or `LaserScan`) and the TF tree linking the sonars to the
vehicle. `--topics odometry=...,multibeam=...,profiler=...,dvl=...` names them (defaults:
what `run --mcap` writes). The log is read and checked whole before anything is built. Writes
`points.ply`, `map.bt` (OctoMap), `reconstruction.ply` (with Open3D), `report.json` and
`report.md` into OUT; `--world`/`--target` (meshes in the site's coordinates) score the
surface and the returns' coverage of the target.
"""

from __future__ import annotations

from pathlib import Path

from drake_auv.commands import whole_number


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser(
        "replay", help="a recorded log (ROS 1 bag, rosbag2, MCAP) through the map, the point "
                       "cloud and the surface",
        description="Reads a log's odometry, TF tree and sonar returns and builds the on-line "
                    "OctoMap, points.ply and the screened-Poisson surface, scored against "
                    "--target/--world when given.")
    parser.add_argument("log", help="a ROS 1 .bag, a rosbag2 folder or an .mcap file")
    parser.add_argument("-o", "--out", required=True, help="output folder")
    parser.add_argument("--topics", default=None, metavar="NAME=TOPIC,...",
                        help="the log's topics: odometry, multibeam, profiler, dvl (defaults "
                             "/odometry/navigation, /sonar/multibeam/points, "
                             "/sonar/profiler/points, /sonar/dvl/points)")
    parser.add_argument("--base-frame", default="base_link",
                        help="the vehicle's frame of a PoseStamped odometry (an Odometry "
                             "names its own child frame; default base_link)")
    parser.add_argument("--world", help="the true world mesh (site coordinates): accuracy")
    parser.add_argument("--target", help="the true target mesh (site coordinates): "
                                         "completeness and coverage")
    parser.add_argument("--voxel", type=float, default=None,
                        help="octree voxel, m, in (0.01, 10] (default: the log's, else 0.5)")
    parser.add_argument("--multibeam-stride", type=whole_number, default=None,
                        help="map every n-th multibeam beam (default: the log's, else 1)")
    parser.add_argument("--max-range", type=float, default=None,
                        help="the sonars' range, m (default: the log's, a LaserScan's "
                             "range_max, else 20)")
    parser.set_defaults(func=run)


def run(args) -> int:
    from drake_auv.commands.outputs import MiB, output_folder
    from drake_auv.mission.site import load_mesh
    from drake_auv.rosio.reader import open_log, parse_topics
    from drake_auv.rosio.replay import map_settings, replay, write_replay_outputs

    topics, given = parse_topics(args.topics)
    if args.voxel is not None and not 0.01 < args.voxel <= 10.0:
        raise ValueError(f"--voxel must be in (0.01, 10] m, got {args.voxel}")
    if args.multibeam_stride is not None and args.multibeam_stride < 1:
        raise ValueError(f"--multibeam-stride must be an integer >= 1, got "
                         f"{args.multibeam_stride}")
    if args.max_range is not None and not 0.0 < args.max_range < 1e4:
        raise ValueError(f"--max-range must be in (0, 10000) m, got {args.max_range}")
    if args.world and not args.target:
        raise ValueError("--world needs --target")
    world = load_mesh(Path(args.world), "--world", "replay") if args.world else None
    target = load_mesh(Path(args.target), "--target", "replay") if args.target else None
    output_folder(args.out, "-o", 100 * MiB)
    index = open_log(args.log, topics, given, args.base_frame, args.max_range)
    settings = map_settings(index, args.voxel, args.multibeam_stride)
    replayed = replay(index, settings, world, target)
    summary = write_replay_outputs(index, replayed, settings, args.out)
    m = summary["map"]
    line = (f"{args.log}: {m['batches']} sonar updates, {m['returns']} returns -> octree "
            f"{m['leaves']} leaves, {m['occupied_voxels']} occupied voxels")
    if "coverage" in summary:
        line += (f"; target coverage {100 * summary['coverage']['point_cloud']:.1f} % "
                 f"(returns within {summary['coverage']['tolerance_m']:g} m), surface "
                 f"{100 * summary['coverage']['surface']:.1f} %")
    print(line + f"; report in {Path(args.out) / 'report.md'}")
    return 0
