"""`drake-auv run MISSION_FILE_OR_NAME -o OUT`: fly a mission in one dive and report it.

Writes `report.md`, `report.json`, the figures, `mission.html`, `trajectory.csv` and
`diagram.dot` into OUT. `--set KEY=VALUE` overrides the file's values by dotted keys into its
sections (`--set replanner.optimizer=none`, `--set sonar_noise=clean`,
`--set steps.2.survey.replanning=false`).
"""

from __future__ import annotations

import time
from pathlib import Path as FilePath

from drake_auv.commands import add_recording_options
from drake_auv.commands.outputs import MiB, output_folder


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser(
        "run", help="fly a mission file (or a built-in mission) in one dive",
        description="Loads a mission file (YAML: site, navigation, sonar noise, replanner, "
                    "payload, limits, steps) or a built-in mission (boulder, breakwater, "
                    "pool, c_object), plans it, flies every step in one simulated dive and "
                    "writes the report, figures, recording, trajectory and Diagram.")
    parser.add_argument("mission", help="a mission YAML file or a built-in mission's name")
    parser.add_argument("-o", "--out", required=True, help="output folder")
    add_mission_options(parser)
    add_recording_options(parser, playback_speed=20.0, realtime=False)
    parser.set_defaults(func=run)


def add_mission_options(parser) -> None:
    """`--seed` and `--set`, shared with `drake-auv demo`."""
    parser.add_argument("--seed", type=int, default=None,
                        help="seed of the prior-map error, navigation drift, sonar noise and "
                             "STOMP (default: the file's)")
    parser.add_argument("--set", dest="overrides", action="append", default=[],
                        metavar="KEY=VALUE",
                        help="override a value of the mission file by its dotted key "
                             "(repeatable), e.g. replanner.optimizer=none")


def fly(mission: str, out, seed=None, overrides=(), html: bool = True,
        playback_speed: float = 20.0, progress: bool = True) -> dict:
    """Loads, flies and reports `mission` into `out`; returns the report's summary. The
    mission and its site are checked before the simulation's modules (Drake, matplotlib) are
    imported, so a bad file is reported at once. The report's `timing` has the end-to-end
    figures: `setup_s` is everything of this call before the outputs but the simulation."""
    start = time.perf_counter()
    from drake_auv.mission.config import load_mission
    from drake_auv.mission.site import check_against_site, load_site

    spec = load_mission(mission, seed=seed, overrides=overrides)
    site = load_site(spec.site, spec.seed, label=spec.name)
    check_against_site(spec, site)
    _note_missing_reconstruction()
    from drake_auv.mission.plan import plan_mission
    from drake_auv.mission.recording import finish_recording, prepare_scene
    from drake_auv.mission.report import write_outputs
    from drake_auv.mission.runner import run_mission

    plan = plan_mission(spec, site)
    scene = None
    if html:
        from drake_auv.visualization import Scene

        scene = Scene()
        prepare_scene(scene, site, plan)
        scene.start_recording(playback_speed=playback_speed, live=False)
    result = run_mission(spec, site, scene=scene, progress=progress, plan=plan)
    setup_s = time.perf_counter() - start - result.wall_s

    def finish(out):
        finish_recording(result, scene, out / "mission.html")

    return write_outputs(result, out, setup_s=setup_s,
                         finish=finish if scene is not None else None)


RUN_NEEDS_BYTES = 300 * MiB  # a dive's outputs: the boulder demo writes 135 MB (points.ply 76)


def run(args) -> int:
    output_folder(args.out, "-o", RUN_NEEDS_BYTES)
    summary = fly(args.mission, args.out, args.seed, args.overrides, not args.no_html,
                  args.playback_speed, not args.quiet)
    c = summary["coverage"]
    print(f"{summary['mission']['name']}: multibeam coverage {100 * c['multibeam']:.1f} %, "
          f"camera {100 * c['camera']:.1f} %, minimum clearance "
          f"{summary['min_clearance_m']:.2f} m"
          + (" (contact)" if summary["contact"] else "")
          + f"; report in {FilePath(args.out) / 'report.md'}")
    t = summary["timing"]
    print(f"end to end {t['total_s']:.1f} s: setup {t['setup_s']:.1f} s, simulation "
          f"{t['simulation_s']:.1f} s ({t['real_time_factor']:.0f}x real time), outputs "
          f"{t['outputs_s']:.1f} s; peak memory {t['peak_rss_mb']:.0f} MiB")
    return 0


def _note_missing_reconstruction() -> None:
    """A one-line warning before the dive when Open3D is unusable (the report will say that
    no surface was built, with the same reason)."""
    import warnings

    from drake_auv.reconstruction.surface import open3d_error

    reason = open3d_error()
    if reason is not None:
        warnings.warn(f"no reconstruction.ply will be built: {reason}", stacklevel=2)
