"""`drake-auv run MISSION_FILE_OR_NAME -o OUT`: fly a mission in one dive and report it.

Writes `report.md`, `report.json`, the figures, `mission.html`, `trajectory.csv` and
`diagram.dot` into OUT. `--set KEY=VALUE` overrides the file's values by dotted keys into its
sections (`--set replanner.optimizer=none`, `--set sonar_noise=clean`,
`--set steps.2.survey.replanning=false`). `--meshcat` serves the scene on localhost while the
mission flies (the leg, the replanner's section and the reference drawn as they change), paced
by `--realtime R` (1 = real time, 0 = as fast as possible); the outputs are the same.
`--mcap` (or the mission key `outputs.mcap`) also writes `dive.mcap`, the dive as ROS 2
messages (`drake_auv.rosio`, docs/ros.md), as it flies. One display on standard error shows the
run's phases (`drake_auv.progress`: setup, dive, results, outputs); `--quiet` hides it.
"""

from __future__ import annotations

import math
import time
from pathlib import Path

from drake_auv.commands import add_recording_options, whole_number
from drake_auv.commands.outputs import MiB, output_folder
from drake_auv.mission.config import builtin_missions


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser(
        "run", help="fly a mission file (or a built-in mission) in one dive",
        description="Loads a mission file (YAML: site, navigation, sonar noise, replanner, "
                    "payload, limits, steps) or a built-in mission ("
                    + ", ".join(builtin_missions()) + "), plans it, flies every step in one "
                    "simulated dive and writes the report, figures, recording, trajectory and "
                    "Diagram.")
    parser.add_argument("mission", help="a mission YAML file or a built-in mission's name")
    parser.add_argument("-o", "--out", required=True, help="output folder")
    add_mission_options(parser)
    add_recording_options(parser, playback_speed=20.0, realtime=False)
    parser.set_defaults(func=run)


def add_mission_options(parser) -> None:
    """`--seed`, `--set`, `--meshcat`, `--realtime` and `--mcap`, shared with `drake-auv
    demo`."""
    parser.add_argument("--seed", type=whole_number, default=None,
                        help="seed of the prior-map error, navigation drift, sonar noise and "
                             "STOMP (default: the file's)")
    parser.add_argument("--set", dest="overrides", action="append", default=[],
                        metavar="KEY=VALUE",
                        help="override a value of the mission file by its dotted key "
                             "(repeatable), e.g. replanner.optimizer=none")
    parser.add_argument("--meshcat", action="store_true",
                        help="serve the scene on localhost while the mission flies (the URL is "
                             "printed first): the vehicle, the map, the leg and the replanner's "
                             "section as they change")
    parser.add_argument("--realtime", type=float, default=None, metavar="R",
                        help="with --meshcat, fly at R times real time (default 1; 0 = as fast "
                             "as possible)")
    parser.add_argument("--meshcat-port", type=whole_number, default=None, metavar="PORT",
                        help="with --meshcat, serve the live view on this port of localhost "
                             f"({MESHCAT_PORTS[0]}-{MESHCAT_PORTS[1]}; default: the first free "
                             "one from 7000)")
    parser.add_argument("--no-reconstruction", action="store_true",
                        help="skip the surface reconstruction after the dive (the mission key "
                             "outputs.reconstruction: false); points.ply is still written")
    parser.add_argument("--mcap", action="store_true",
                        help="also write dive.mcap: the dive as ROS 2 messages (TF, odometry, "
                             "sonar point clouds, plan, map) for Foxglove and ros2 bag")


MESHCAT_PORTS = (1024, 65535)


def check_live_options(meshcat: bool, realtime, port) -> float:
    """The live view's options, checked before any work; returns the pacing rate (1 by
    default with --meshcat, 0 without)."""
    if not meshcat:
        for flag, value in (("--realtime", realtime), ("--meshcat-port", port)):
            if value is not None:
                raise ValueError(f"{flag} paces or serves the live view; allowed: with "
                                 "--meshcat only")
        return 0.0
    if port is not None and not MESHCAT_PORTS[0] <= port <= MESHCAT_PORTS[1]:
        raise ValueError(f"--meshcat-port must be in [{MESHCAT_PORTS[0]}, {MESHCAT_PORTS[1]}], "
                         f"got {port}")
    realtime = 1.0 if realtime is None else realtime
    if not (math.isfinite(realtime) and realtime >= 0):
        raise ValueError(f"--realtime must be >= 0 (0 = as fast as possible), got {realtime}")
    return realtime


def fly(mission: str, out, seed=None, overrides=(), html: bool = True,
        playback_speed: float = 20.0, progress: bool = True, meshcat: bool = False,
        realtime: float | None = None, meshcat_port: int | None = None,
        mcap: bool = False, reconstruction: bool = True) -> dict:
    """Loads, flies and reports `mission` into `out`; returns the report's summary. The
    mission and its site are checked before the simulation's modules (Drake, matplotlib) are
    imported, so a bad file is reported at once. With `meshcat` the scene is served on
    localhost during the dive, which flies at `realtime` times real time (0: at full speed).
    The report's `timing` has the end-to-end figures: `setup_s` is everything of this call
    before the outputs but the simulation. With `mcap` (or the mission's `outputs.mcap`) the
    dive is also written to `out`/dive.mcap as it flies."""
    start = time.perf_counter()
    realtime = check_live_options(meshcat, realtime, meshcat_port)
    from drake_auv.mission.config import load_mission
    from drake_auv.mission.plan import check_against_site
    from drake_auv.mission.site import load_site

    overrides = [*overrides, *([] if reconstruction else ["outputs.reconstruction=false"])]
    spec = load_mission(mission, seed=seed, overrides=overrides)
    site = load_site(spec.site, spec.seed, label=spec.name)
    check_against_site(spec, site)
    if spec.outputs.reconstruction:
        _note_missing_reconstruction()
    from drake_auv.mission.plan import plan_mission
    from drake_auv.mission.recording import finish_recording, prepare_scene
    from drake_auv.mission.report.outputs import write_outputs
    from drake_auv.mission.runner import run_mission
    from drake_auv.progress import RUN_PHASES, RunProgress

    # the plan is the input's last check: the display begins after it, so that bad input
    # gets its one line alone
    plan = plan_mission(spec, site)
    with RunProgress(RUN_PHASES, enabled=progress) as display:
        log_file = mcap or spec.outputs.mcap
        # the scene, the MCAP log and run_mission's Diagram
        display.start("setup", total=1 + bool(html or meshcat) + bool(log_file),
                      note="scene" if html or meshcat else "Diagram")
        scene = None
        if html or meshcat:
            from drake_auv.visualization import Scene

            with display.step("scene"):
                scene = Scene(live=meshcat, port=meshcat_port)
                if meshcat:
                    display.write(f"live view: {scene.meshcat.web_url()}")
                prepare_scene(scene, site, plan)
                if html:
                    scene.start_recording(playback_speed=playback_speed, live=meshcat)
        log = None
        if log_file:
            from drake_auv.rosio.writer import dive_log

            with display.step("dive.mcap"):
                Path(out).mkdir(parents=True, exist_ok=True)
                log = dive_log(Path(out) / "dive.mcap", spec, site)
        result = run_mission(spec, site, scene=scene, progress=display, plan=plan,
                             realtime_rate=realtime, mcap=log)
        setup_s = time.perf_counter() - start - result.run.wall_s

        def finish(out):
            finish_recording(result, scene, out / "mission.html")

        return write_outputs(result, Path(out), setup_s=setup_s,
                             finish=finish if html else None, progress=display)


RUN_NEEDS_BYTES = 300 * MiB  # a dive's outputs: the boulder demo writes 135 MB (points.ply 76)


def run(args) -> int:
    output_folder(args.out, "-o", RUN_NEEDS_BYTES)
    summary = fly(args.mission, args.out, args.seed, args.overrides, not args.no_html,
                  args.playback_speed, not args.quiet, args.meshcat, args.realtime,
                  args.meshcat_port, args.mcap, not args.no_reconstruction)
    c = summary["coverage"]
    print(f"{summary['mission']['name']}: multibeam coverage {100 * c['multibeam']:.1f} %, "
          f"camera {100 * c['camera']:.1f} %, minimum clearance "
          f"{summary['min_clearance_m']:.2f} m"
          + (" (contact)" if summary["contact"] else "")
          + f"; report in {Path(args.out) / 'report.md'}")
    t = summary["timing"]
    print(f"end to end {t['total_s']:.1f} s: setup {t['setup_s']:.1f} s, simulation "
          f"{t['simulation_s']:.1f} s ({t['real_time_factor']:.0f}x real time), outputs "
          f"{t['outputs_s']:.1f} s; peak memory {t['peak_rss_mb']:.0f} MiB")
    if args.meshcat and not args.no_html:
        print(f"the live view ends with this process; replay the dive any time from "
              f"{Path(args.out) / 'mission.html'}")
    return 0


def _note_missing_reconstruction() -> None:
    """A one-line warning before the dive when Open3D is unusable (the report will say that
    no surface was built, with the same reason)."""
    import warnings

    from drake_auv.reconstruction.surface import open3d_error

    reason = open3d_error()
    if reason is not None:
        warnings.warn(f"no reconstruction.ply will be built: {reason}", stacklevel=2)
