"""Plan a real Monterey tile, export it for COLA2 and ArduSub, fly both files, compare.

    python examples/export_and_fly.py [--size 300] [--omega 10] [--seed 0] [-o out/export_and_fly]

The site is a `--size` m square of a canyon wall of a shipped Monterey tile
(`drake_auv.terrain.site_files`: a 1 m bicubic world, its target, the 10 m survey as the
prior, in UTM zone 10N), flown with a 2 m prior-map error, navigation drift and realistic
sonars. Three missions on the same site and seed:

- `internal`: the off-line plan flown as the project's own `Path` (`survey`, no replanning);
- `cola2`: the plan's `mission.xml` flown as COLA2 executes it (`fly`);
- `ardusub`: its `mission.plan` flown as ArduSub AUTO executes it (`fly`).

Writes the exports, each mission's report (unless `--no-reports`), `comparison.md` /
`comparison.json` (clearance, contact, the supervisor's safety responses, coverage, duration)
and `comparison.png` (tracks from above, clearance against time).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import yaml  # noqa: E402

from drake_auv.formats.outputs import write_outputs  # noqa: E402
from drake_auv.mission.config import load_mission  # noqa: E402
from drake_auv.mission.plan import plan_mission  # noqa: E402
from drake_auv.mission.report.outputs import write_outputs as write_report  # noqa: E402
from drake_auv.mission.report.summary import summarise  # noqa: E402
from drake_auv.mission.runner import run_mission  # noqa: E402
from drake_auv.mission.site import load_site  # noqa: E402
from drake_auv.scenarios import DATA_DIR  # noqa: E402
from drake_auv.signals import VehicleState  # noqa: E402
from drake_auv.terrain.readers import read_bathymetry  # noqa: E402
from drake_auv.terrain.site_files import write_site_files  # noqa: E402

TILE = DATA_DIR / "monterey" / "MontereyBay.R_-121.815_-121.805_36.790_36.800.epsg3857.tif"
CORNER = (150.0, 840.0)  # south-west corner of the region, the tile's world frame (m): the wall


def plan_files(folder: Path) -> list[str]:
    """The ArduSub export: mission.plan, or mission_1.plan, mission_2.plan, ... in order."""
    if (folder / "mission.plan").exists():
        return ["mission.plan"]
    return sorted((p.name for p in folder.glob("mission_*.plan")),
                  key=lambda name: int(name[8:-5]))


def mission_file(folder: Path, name: str, seed: int, steps) -> Path:
    path = folder / f"{name}.yaml"
    path.write_text(yaml.safe_dump({
        "name": name, "seed": seed,
        "site": {"world": "world.ply", "target": "target.ply", "prior": "prior.tif",
                 "prior_error_m": 2.0},
        "navigation": {"heading_bias_deg": 1.0, "dvl_scale_error": 0.01, "random_walk": 0.02},
        "payload": {"multibeam_mount": "down"}, "steps": steps}))
    return path


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--size", type=float, default=300.0, help="side of the region, m")
    parser.add_argument("--omega", type=float, default=10.0, help="offset Omega, m")
    parser.add_argument("--speed", type=float, default=1.0, help="survey speed, m/s")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--no-reports", action="store_true",
                        help="skip each mission's report folder (its surface reconstruction "
                             "of a large seabed takes minutes); the comparison is still written")
    parser.add_argument("-o", "--out", default="out/export_and_fly")
    args = parser.parse_args()
    out = Path(args.out)
    x0, y0 = CORNER
    write_site_files(read_bathymetry(TILE), (x0, y0, x0 + args.size, y0 + args.size), out,
                     margin=30.0)
    internal = load_mission(mission_file(out, "internal", args.seed, [
        {"plan": {"omega": args.omega, "speed": args.speed}}, {"survey": {"replanning": False}}]))
    site = load_site(internal.site, internal.seed)
    plan = plan_mission(internal, site)
    write_outputs(plan.coverage, out, figures=False, exports=("cola2", "qgc"),
                  surge_velocity=args.speed, metrics_3d=False)
    missions = {"internal": None, "cola2": ["mission.xml"], "ardusub": plan_files(out)}
    results, rows = {}, {}
    for name, files in missions.items():
        if files is None:
            result = run_mission(internal, site=site, plan=plan)
        else:  # a split ArduSub mission flies its files one after the other, in one dive
            result = run_mission(load_mission(mission_file(out, name, args.seed, [
                {"fly": {"file": file, "speed": args.speed}} for file in files])))
        if not args.no_reports:
            write_report(result, out / name)
        summary = summarise(result)
        results[name] = result
        rows[name] = dict(min_clearance_m=summary["min_clearance_m"],
                          contact=summary["contact"],
                          multibeam_coverage=summary["coverage"]["multibeam"],
                          duration_s=result.log.duration_s, outcomes=result.dive.outcomes,
                          safety_responses=result.dive.responses,
                          files=files or [],
                          distance_mean_m=summary["distance_to_target"]["mean_m"])
    (out / "comparison.json").write_text(json.dumps(rows, indent=2))
    lines = [f"# Export and fly: {args.size:g} m x {args.size:g} m of {TILE.name}, Omega "
             f"{args.omega:g} m, seed {args.seed}", "",
             "| mission | min clearance (m) | contact | safety responses | multibeam coverage "
             "| mean distance (m) | duration (s) |",
             "| --- | ---: | --- | ---: | ---: | ---: | ---: |"]
    for name, r in rows.items():
        lines.append(f"| {name} | {r['min_clearance_m']:.2f} | {'yes' if r['contact'] else 'no'} "
                     f"| {len(r['safety_responses'])} | {100 * r['multibeam_coverage']:.1f} % "
                     f"| {r['distance_mean_m']:.2f} | {r['duration_s']:.0f} |")
    (out / "comparison.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))
    fig, (top, clear) = plt.subplots(1, 2, figsize=(13, 5.5))
    for name, result in results.items():
        xy = result.site.to_site(VehicleState(result.log.state).position)
        top.plot(xy[:, 0], xy[:, 1], lw=0.8, label=name)
        clear.plot(result.log.times, result.log.clearance, lw=0.8, label=name)
    top.set(aspect="equal", xlabel="easting (m, UTM 10N)", ylabel="northing (m)",
            title="true tracks")
    clear.axhline(0.5 * args.omega, color="k", ls="--", lw=0.8, label="0.5 Omega")
    clear.set(xlabel="time (s)", ylabel="true clearance (m)", title="clearance to the seabed")
    for ax in (top, clear):
        ax.legend()
    fig.tight_layout()
    fig.savefig(out / "comparison.png", dpi=110)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
