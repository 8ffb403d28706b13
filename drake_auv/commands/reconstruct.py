"""`drake-auv reconstruct POINTS -o MESH.ply`: a screened-Poisson surface from recorded returns.

POINTS is a point cloud (`points.ply` of a mission, or any PLY with x, y, z; LAS/LAZ with
laspy): normals from `--k` nearest neighbours, oriented towards each point's recorded sensor
origin (by neighbour propagation when the file has none), screened Poisson at `--depth`, the
lowest `--trim` share of density removed (after the points whose neighbours lie `--outliers`
times farther than usual), then every face farther than `--support` local
spacings from the nearest point (the surface Poisson closes where nothing was seen). With
`--target MESH` (same frame) the whole surface and the cloud are scored (accuracy of every
vertex to `--world`, default the target; completeness of the target's area, all and seen) and
the mesh is coloured by its error; `--crop M` keeps only the points in the target's box grown
by M m; `--figure` draws the surface coloured by its distance to the points (and to the truth,
with `--target`). Needs Open3D (`pip install 'drake_auv[reconstruct]'`). The output locations and Open3D are checked
first.
"""

from __future__ import annotations

from pathlib import Path

from drake_auv.commands import whole_number
from drake_auv.output_files import replacing
from drake_auv.reconstruction.surface import (DEPTH_RANGE, K_RANGE, OUTLIERS, OUTLIERS_RANGE,
                                              SUPPORT, SUPPORT_RANGE, TRIM_RANGE)


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser(
        "reconstruct", help="screened-Poisson surface from a recorded point cloud",
        description="Reconstructs a triangle mesh from a point cloud (a mission's points.ply): "
                    "Hoppe normals from k neighbours oriented towards the sensor, screened "
                    "Poisson (Open3D), low-density trimming; optionally scored against a "
                    "true mesh.")
    parser.add_argument("points", help="point cloud: .ply (x, y, z; origin_x/y/z, time, source "
                                       "when present), .las or .laz")
    parser.add_argument("-o", "--out", required=True, help="output mesh (.ply, .obj, .stl)")
    parser.add_argument("--depth", type=whole_number, default=9,
                        help=f"Poisson octree depth, {DEPTH_RANGE[0]} to {DEPTH_RANGE[1]} "
                             "(default 9)")
    parser.add_argument("--trim", type=float, default=0.05,
                        help=f"share of the lowest-density vertices removed, in "
                             f"[{TRIM_RANGE[0]:g}, {TRIM_RANGE[1]:g}) (default 0.05)")
    parser.add_argument("--k", type=whole_number, default=200,
                        help=f"neighbours per normal, {K_RANGE[0]} to {K_RANGE[1]} (default 200, "
                             "as the reference)")
    parser.add_argument("--support", type=float, default=SUPPORT,
                        help=f"remove faces farther than this many local point spacings from "
                             f"every point, in [{SUPPORT_RANGE[0]:g}, {SUPPORT_RANGE[1]:g}]; 0 "
                             f"keeps them (default {SUPPORT:g})")
    parser.add_argument("--outliers", type=float, default=OUTLIERS,
                        help="first drop every point whose 8 nearest neighbours lie farther "
                             "than this many times the cloud's median (water-column clutter, "
                             f"sea-surface ghosts): 0 (off) or in [1, {OUTLIERS_RANGE[1]:g}] "
                             f"(default {OUTLIERS:g})")
    parser.add_argument("--target", help="true mesh (same frame) to score the result against")
    parser.add_argument("--world", help="with --target: the whole true world (same frame), to "
                                        "which every vertex's accuracy is measured (default: "
                                        "the target)")
    parser.add_argument("--crop", type=float, default=None, metavar="MARGIN",
                        help="with --target: keep only the points inside the target's bounding "
                             "box grown by MARGIN m")
    parser.add_argument("--figure", help="a PNG of the surface coloured by its distance to the "
                                         "points (and to the truth, with --target)")
    parser.add_argument("--quiet", action="store_true", help="no progress bar")
    parser.set_defaults(func=run)


MESH_SUFFIXES = (".ply", ".obj", ".stl")
FIGURE_SUFFIXES = (".png", ".pdf", ".svg")


def run(args) -> int:
    import numpy as np
    import trimesh

    from drake_auv.commands.outputs import MiB, output_file
    from drake_auv.mission.site import load_mesh
    from drake_auv.reconstruction.pointcloud import read_point_cloud
    from drake_auv.reconstruction.figures import colour_scale
    from drake_auv.reconstruction.products import SUPPORT_LABEL, error_colours
    from drake_auv.reconstruction.scoring import score
    from drake_auv.reconstruction.surface import (check_parameters, check_spread, load_open3d,
                                                  reconstruct)

    output_file(args.out, "-o", MESH_SUFFIXES, 100 * MiB)  # the demo's depth-9 mesh: 52 MB
    if args.figure:
        output_file(args.figure, "--figure", FIGURE_SUFFIXES, 5 * MiB)
    if (args.world or args.crop is not None) and not args.target:
        raise ValueError("--world and --crop need --target")
    if args.crop is not None and not args.crop >= 0:
        raise ValueError(f"--crop must be >= 0 m, got {args.crop}")
    check_parameters(10 ** 9, args.depth, args.k, args.trim, args.support, args.outliers)  # before any work
    cloud = read_point_cloud(args.points)
    target = load_mesh(Path(args.target), "--target", "reconstruct") if args.target \
        else None
    world = load_mesh(Path(args.world), "--world", "reconstruct") if args.world else None
    if args.crop is not None:
        cloud = cloud.crop(*target.bounds, args.crop)
    try:  # what the cloud itself allows, named by its file
        check_parameters(len(cloud), args.depth, args.k, args.trim)
        check_spread(cloud.points)
    except ValueError as err:
        raise ValueError(f"{args.points}: {err}") from None
    load_open3d()  # its real import error, before any work
    surface = reconstruct(cloud, depth=args.depth, trim=args.trim, k=args.k,
                          support=args.support, progress=not args.quiet,
                          outliers=args.outliers)
    mesh = surface.mesh
    line = (f"{args.out}: {len(mesh.vertices)} vertices, {len(mesh.faces)} faces from "
            f"{len(cloud)} points, median distance to a point "
            f"{np.median(surface.support_m):.3f} m (support trim "
            f"{f'{args.support:g} local spacings' if args.support else 'off'})")
    panels = [(Path(args.points).name, mesh, surface.support_m, SUPPORT_LABEL)]
    if target is not None:
        summary, errors = score(target, mesh, cloud.points, world=world)
        mesh = trimesh.Trimesh(mesh.vertices, mesh.faces, process=False,
                               vertex_colors=(255 * error_colours(errors, colour_scale(errors)))
                               .astype(np.uint8))
        s, p = summary["surface"], summary["point_cloud"]
        line += (f"; every vertex to the {summary['accuracy_to']}: accuracy median "
                 f"{s['accuracy_median_m']:.3f} m (mean {s['accuracy_mean_m']:.3f} m, p95 "
                 f"{s['accuracy_p95_m']:.3f} m), completeness {100 * s['completeness']:.1f} % "
                 f"({100 * s['completeness_seen']:.1f} % of the seen target) (points: median "
                 f"{p['accuracy_median_m']:.3f} m, {100 * p['completeness']:.1f} %)")
        panels.insert(0, (Path(args.points).name, surface.mesh, errors))
    if args.figure:
        from drake_auv.reconstruction.figures import fig_reconstruction

        with replacing(args.figure) as temporary:
            fig_reconstruction(panels).savefig(temporary, dpi=110, bbox_inches="tight")
    with replacing(args.out) as temporary:
        mesh.export(temporary)
    print(line)
    return 0
