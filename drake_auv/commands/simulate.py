"""`drake-auv simulate`: fly a path CSV with the GIRONA 500 and record the run.

Writes `<out>/mission.html` (standalone Meshcat recording), `<out>/tracking_error.png`
(cross-track error over time) and `<out>/state.csv` (the logged true state).
`fly_path` is shared with `drake-auv lawnmower`.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from drake_auv.commands import add_recording_options, whole_number
from drake_auv.output_files import replacing
from drake_auv.signals import Reference, VehicleState

DEFAULT_OUT = "out/simulate"


@dataclass
class FlightResult:
    """Logged true state and reference of one flight, and its cross-track statistics."""

    times: np.ndarray  # (n,) s
    state: np.ndarray  # (12, n) true state
    reference: np.ndarray  # (8, n)
    cross_track: np.ndarray  # (n,) m, distance of the true position to the path polyline
    settle_time: float  # s, when the reference finishes the first segment (excluded from stats)
    wall_seconds: float

    @property
    def settled(self) -> np.ndarray:
        return self.times > self.settle_time

    @property
    def rms(self) -> float:
        return float(np.sqrt(np.mean(self.cross_track[self.settled] ** 2)))

    @property
    def max(self) -> float:
        return float(self.cross_track[self.settled].max())

    @property
    def real_time_factor(self) -> float:
        return float(self.times[-1] / self.wall_seconds)


def fly_path(path, out_dir, speed: float = 0.5, scene=None, navigation=None,
             playback_speed: float = 10.0, settle_samples: int = 1, extra_time: float = 10.0,
             progress: bool = True, realtime_rate: float = 0.0) -> FlightResult:
    """Simulates the vehicle tracking `path` at `speed`, draws it in `scene` if given, and writes
    mission.html (with a scene), tracking_error.png and state.csv into `out_dir`.

    The simulation advances once: a monitor ends it when the vehicle has settled at the end of
    the path, at most `extra_time` s after the reference got there. Statistics exclude the
    time until the reference reaches sample `settle_samples` (the end of the first lane for a
    lawnmower given by its corner points). A `realtime_rate` > 0 paces the
    simulation (e.g. 1.0 to watch it live in the Meshcat tab); 0 runs as fast as possible.
    """
    from pydrake.systems.analysis import Simulator
    from tqdm import tqdm

    from drake_auv.vehicle.control import cross_track_distance
    from drake_auv.vehicle.diagram import build_tracking_diagram

    if not (np.isfinite(speed) and 0.05 <= speed <= 1.5):
        raise ValueError(f"speed must be in [0.05, 1.5] m/s (the GIRONA 500 tops out near "
                         f"1.4 m/s), got {speed}")
    if len(path) < 2:
        raise ValueError("the path needs at least 2 samples to fly")
    check_below_surface(path)
    if not (np.isfinite(realtime_rate) and realtime_rate >= 0):
        raise ValueError(f"realtime_rate must be >= 0 (0 = as fast as possible), got {realtime_rate}")
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    if scene is not None:
        from drake_auv.visualization.legend import LegendEntry, css_colour
        from drake_auv.visualization.scene import PATH_RGBA

        scene.add_legend(LegendEntry("path", "orange line", "the path to fly",
                                     css_colour(PATH_RGBA), scene.add_path("path", path)))
    diagram, handles = build_tracking_diagram(path.resample(1.0), speed=speed,
                                              navigation=navigation, scene=scene)
    if scene is not None:
        scene.start_recording(playback_speed=playback_speed)
    simulator = Simulator(diagram)
    simulator.set_target_realtime_rate(realtime_rate)
    if scene is not None:
        print(f"live view: {scene.meshcat.web_url()}")
    end = handles.end_time + extra_time
    start = time.perf_counter()
    with tqdm(total=round(end), unit="sim s", disable=not progress, desc="simulate") as bar:
        simulator.set_monitor(_arrival_monitor(diagram, path, handles.end_time, bar))
        simulator.AdvanceTo(end)
        bar.update(bar.total - bar.n)
    wall = time.perf_counter() - start
    context = simulator.get_context()
    state_log = handles.state_log.FindLog(context)
    times, state = state_log.sample_times(), state_log.data()
    reference = handles.reference_log.FindLog(context).data()
    settle = float(path.times(speed)[min(settle_samples, len(path) - 1)])
    result = FlightResult(times, state, reference,
                          cross_track_distance(VehicleState(state.T).position, path.points),
                          settle, wall)
    if scene is not None:
        scene.write_html(out_dir / "mission.html")
    plot_tracking_error(result, out_dir / "tracking_error.png")
    with replacing(out_dir / "state.csv") as temporary:
        np.savetxt(temporary, np.column_stack([times, state.T]), delimiter=",", fmt="%.5f",
                   header=",".join(("t", *VehicleState.get_fields())), comments="")
    return result


def check_below_surface(path, source: str = "path", first_row: int | None = None) -> None:
    """Raises ValueError (one line) for the first sample of `path` above the sea surface (z > 0:
    out of the water), named `<source> sample <k>`, or `<source>:<row>` when the samples are
    a file's rows from `first_row` on."""
    above = np.flatnonzero(path.points[:, 2] > 0.0)
    if len(above):
        k = int(above[0])
        where = f"{source} sample {k}" if first_row is None else f"{source}:{first_row + k}"
        raise ValueError(f"{where}: depth {-path.points[k, 2]:g} m is {path.points[k, 2]:.2f} m "
                         "above the sea surface (out of the water); allowed: z <= 0 m (z up, "
                         "sea surface z = 0)")


SETTLED = (0.02, 0.01, 0.01)  # m from the path's end, m/s, rad of heading: the flight is over


def _arrival_monitor(diagram, path, end_time: float, bar):
    """A Simulator monitor of the tracking `diagram` that advances `bar` and ends the flight
    once the reference has reached the end of `path` (at `end_time` s) and the true state (the
    diagram's `state` output) has settled there
    (`SETTLED`); `extra_time` after `end_time` caps it when it does not settle."""
    from pydrake.systems.framework import EventStatus

    goal, heading = path.points[-1], path.unwrapped_heading()[-1]
    state_port = diagram.GetOutputPort("state")

    def monitor(root_context):
        t = root_context.get_time()
        if int(t) > bar.n:
            bar.update(int(t) - bar.n)
        if t < end_time:
            return EventStatus.DidNothing()
        x = VehicleState(state_port.Eval(root_context))
        settled = (np.linalg.norm(x.position - goal), np.linalg.norm(x.linear_velocity),
                   abs(np.angle(np.exp(1j * (x.yaw - heading)))))
        if all(value < limit for value, limit in zip(settled, SETTLED)):
            return EventStatus.ReachedTermination(diagram, "settled at the end of the path")
        return EventStatus.DidNothing()

    return monitor


def plot_tracking_error(result: FlightResult, filename) -> None:
    """PNG of the cross-track error and the distance to the moving reference over time."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    lag = np.linalg.norm(VehicleState(result.state.T).position
                         - Reference(result.reference.T).position, axis=1)
    fig, ax = plt.subplots(figsize=(9, 3.5), constrained_layout=True)
    ax.plot(result.times, result.cross_track, label="cross-track error (to the path)")
    ax.plot(result.times, lag, lw=0.8, alpha=0.7, label="distance to the moving reference")
    ax.axvline(result.settle_time, color="k", ls=":", lw=0.8, label="end of the first segment")
    ax.set_xlabel("time (s)")
    ax.set_ylabel("error (m)")
    ax.set_title(f"Tracking error: cross-track RMS {result.rms:.3f} m, max {result.max:.3f} m "
                 f"after the first segment")
    ax.grid(alpha=0.3)
    ax.legend(loc="upper right", fontsize=8)
    with replacing(filename) as temporary:
        fig.savefig(temporary, dpi=120)
    plt.close(fig)


def report(result: FlightResult, out_dir) -> None:
    print(f"flew {result.times[-1]:.0f} s in {result.wall_seconds:.1f} s wall "
          f"({result.real_time_factor:.0f}x real time); cross-track RMS {result.rms:.3f} m, "
          f"max {result.max:.3f} m after the first segment")
    print(f"wrote {out_dir}/mission.html (open it in a browser), {out_dir}/tracking_error.png, "
          f"{out_dir}/state.csv")


def run(args) -> int:
    from drake_auv.commands.outputs import MiB, output_folder
    from drake_auv.vehicle.navigation import NavigationParams
    from drake_auv.planning.path import PlannedPath
    from drake_auv.visualization import Scene

    path = PlannedPath.from_csv(args.path_csv)
    check_below_surface(path, args.path_csv, first_row=2)  # row 1: the header
    output_folder(args.out, "-o", 20 * MiB)  # mission.html, tracking_error.png, state.csv
    navigation = NavigationParams(heading_bias=np.radians(args.heading_bias_deg),
                                  random_walk=args.random_walk, seed=args.seed)
    scene = None if args.no_html else Scene()
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
