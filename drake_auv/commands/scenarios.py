"""`drake-auv scenarios`: list the named sites, show one, export its prior map or world mesh.

    drake-auv scenarios                       one line per site
    drake-auv scenarios boulder               details: faces, target area, start, parameters
    drake-auv scenarios boulder --prior out/boulder_prior.tif --error 3 --seed 1
    drake-auv scenarios pool --world out/pool.ply
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from drake_auv.commands import whole_number
from drake_auv.output_files import open_replacing, replacing


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser("scenarios", help="list the named sites, or show/export one",
                                   description=__doc__.split("\n")[0])
    parser.add_argument("name", nargs="?", help="a site to show (default: list them all)")
    parser.add_argument("--prior", metavar="FILE",
                        help="write the site's prior map: .npz keeps the world frame; a .tif "
                             "GeoTIFF is re-based to its corner when read back")
    parser.add_argument("--error", type=float, default=0.0,
                        help="horizontal prior-map error, m, in [0, 5] (default 0)")
    parser.add_argument("--seed", type=whole_number, default=0, help="seed of the error's direction")
    parser.add_argument("--world", metavar="FILE",
                        help="write the true world mesh (.ply, .stl, .obj, .glb)")
    parser.set_defaults(func=run)


def run(args) -> int:
    from drake_auv.scenarios import get_scenario, list_scenarios

    if args.name is None:
        if args.prior or args.world:
            raise ValueError("--prior and --world need a site name")
        width = max(len(name) for name, _ in list_scenarios())
        for name, text in list_scenarios():
            print(f"{name:<{width}}  {text}")
        return 0
    if args.prior and Path(args.prior).suffix.lower() not in (".tif", ".tiff", ".npz"):
        raise ValueError(f"--prior: file must end in .tif or .npz, got {args.prior}")
    if args.world and Path(args.world).suffix.lower() not in (".ply", ".stl", ".obj", ".glb"):
        raise ValueError(f"--world: file must end in .ply, .stl, .obj or .glb, got {args.world}")
    sc = get_scenario(args.name)
    lo, hi = sc.world.bounds
    x, y, z, yaw = sc.start
    print(f"{sc.name}: {sc.description}")
    print(f"  world: {len(sc.world.faces)} faces, x [{lo[0]:.1f}, {hi[0]:.1f}] "
          f"y [{lo[1]:.1f}, {hi[1]:.1f}] z [{lo[2]:.1f}, {hi[2]:.1f}] m")
    print(f"  target: {int(sc.target_faces.sum())} faces, {sc.target_area:.1f} m^2")
    print(f"  start: ({x:.1f}, {y:.1f}, {z:.1f}) m, yaw {yaw:.0f} deg")
    print("  params: " + ", ".join(f"{k}={v}" for k, v in sc.params.items()))
    if args.prior:  # the prior a mission at this site holds, loaded as the mission loads it
        from drake_auv.mission.config import SiteSpec
        from drake_auv.mission.site import load_site

        site = load_site(SiteSpec(scenario=args.name, prior_error_m=args.error), args.seed,
                         label=f"scenarios {args.name}")
        _write_prior(site.prior, Path(args.prior))
        print(f"  wrote prior map to {args.prior}")
    if args.world:
        out = Path(args.world)
        out.parent.mkdir(parents=True, exist_ok=True)
        with replacing(out) as temporary:
            sc.world.export(temporary)
        print(f"  wrote world mesh to {out}")
    return 0


def _write_prior(bathy, out: Path) -> None:
    out.parent.mkdir(parents=True, exist_ok=True)
    if out.suffix.lower() == ".npz":
        with open_replacing(out, "wb") as f:
            np.savez(f, z=bathy.z, spacing=np.array(bathy.spacing),
                     origin=np.array(bathy.origin))
    else:
        from drake_auv.terrain.readers import write_geotiff
        write_geotiff(bathy, out)
