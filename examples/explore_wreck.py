"""Explore a wreck nobody mapped: a site given as files, a world mesh and no prior map at all.

Writes a user's site (`drake_auv.terrain.synthetic.wreck_site`: a heeled 20 m hull with a
deckhouse, settled on a rough seabed 32 m deep, in UTM-like eastings/northings) as
`world.ply` and `target.ply`, and a mission file whose only step is `explore` (the region: the
box where the one sonar contact puts the wreck, widened by a few metres; its `zmin` the
operator's bound on the seabed), with realistic sonars and navigation drift. The site has no
`prior`: the mission needs none, and a plan or follow step there is refused at load. Then flies
it with `drake-auv run`, as a user would, into `--out/run` (report, figures, recording).

    .venv/bin/python examples/explore_wreck.py [--seed 0] [--out out/explore_wreck] [--no-run]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
import yaml

from drake_auv.commands.outputs import output_folder
from drake_auv.terrain.synthetic import wreck_site

ORIGIN = (431000.0, 4071000.0)  # the sonar contact, eastings / northings, m
REGION_MARGIN = 4.0  # m around the wreck's extent in the region box


def write_wreck_mission(folder, seed: int = 0, max_time_s: float = 1800.0) -> Path:
    """Writes the wreck site's files and its explore mission into `folder`; returns the
    mission file. The region is the wreck's bounds widened by `REGION_MARGIN` (the contact's
    uncertainty), its top clipped below the surface, its floor the lowest seabed under it."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    world, target = wreck_site(seed=0, origin=ORIGIN)
    world.export(folder / "world.ply")
    target.export(folder / "target.ply")
    (x0, y0, _), (x1, y1, z1) = target.bounds
    lo = np.array([x0, y0]) - REGION_MARGIN
    hi = np.array([x1, y1]) + REGION_MARGIN
    floor = float(world.bounds[0, 2]) - 0.3
    region = [round(float(v), 1) for v in (lo[0], lo[1], floor, hi[0], hi[1],
                                           min(z1 + REGION_MARGIN, -2.0))]
    mission = dict(
        name="wreck_explore", seed=seed,
        description="a wreck on a rough seabed given as files, no prior map: explore",
        site=dict(world="world.ply", target="target.ply",
                  start=[round(float(lo[0]) - 12.0, 1), float(ORIGIN[1]), -26.0, 0.0]),
        navigation=dict(heading_bias_deg=1.0, dvl_scale_error=0.01, random_walk=0.02),
        sonar_noise="realistic",
        payload=dict(multibeam_mount="port", camera_range_m=12),
        limits=dict(max_time_s=None),
        steps=[{"explore": dict(region=region, omega=6.0, max_time_s=max_time_s,
                                clearance_m=3.0, strategy="gain")}])
    path = folder / "mission.yaml"
    path.write_text(yaml.safe_dump(mission, sort_keys=False))
    return path


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seed", type=int, default=0, help="mission seed (0)")
    parser.add_argument("--out", type=Path, default=Path("out/explore_wreck"))
    parser.add_argument("--no-run", action="store_true", help="write the site and mission only")
    args = parser.parse_args(argv)
    try:  # before anything is written
        output_folder(args.out, "--out", 0)
    except ValueError as err:
        parser.error(str(err))
    mission = write_wreck_mission(args.out / "site", args.seed)
    print(f"wrote {mission} (world.ply, target.ply beside it; no prior)")
    if not args.no_run:
        from drake_auv.cli import main as cli

        raise SystemExit(cli(["run", str(mission), "--out", str(args.out / "run"),
                              "--no-html"]))


if __name__ == "__main__":
    main()
