"""Flying a path with the GIRONA 500 alone: `fly_path` builds the tracking Diagram
(`vehicle.diagram.build_tracking_diagram`), simulates until the vehicle settles at the path's
end, and writes the run's recording, tracking-error plot and state log (`drake-auv simulate`,
`drake-auv lawnmower`).
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from pydrake.systems.analysis import Simulator
from pydrake.systems.framework import EventStatus

from drake_auv.output_files import replacing
from drake_auv.progress import RunProgress
from drake_auv.signals import Reference, VehicleState
from drake_auv.vehicle.control import cross_track_distance
from drake_auv.vehicle.diagram import build_tracking_diagram


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
    """Simulates the vehicle tracking `path` at `speed`, records it in `scene` if given (a
    `visualization.Scene`, with whatever its caller drew into it), and writes
    mission.html (with a scene), tracking_error.png and state.csv into `out_dir`.

    The simulation advances once: a monitor ends it when the vehicle has settled at the end of
    the path, at most `extra_time` s after the reference got there. Statistics exclude the
    time until the reference reaches sample `settle_samples` (the end of the first lane for a
    lawnmower given by its corner points). A `realtime_rate` > 0 paces the
    simulation (e.g. 1.0 to watch it live in the Meshcat tab); 0 runs as fast as possible.
    """
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
    with RunProgress(("simulate",), enabled=progress) as display:
        display.start("simulate", end)
        simulator.set_monitor(_arrival_monitor(diagram, path, handles.end_time, display))
        simulator.AdvanceTo(end)
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


def _arrival_monitor(diagram, path, end_time: float, display):
    """A Simulator monitor of the tracking `diagram` that shows its simulated time on `display`
    (a `RunProgress`) and ends the flight
    once the reference has reached the end of `path` (at `end_time` s) and the true state (the
    diagram's `state` output) has settled there
    (`SETTLED`); `extra_time` after `end_time` caps it when it does not settle."""
    goal, heading = path.points[-1], path.unwrapped_heading()[-1]
    state_port = diagram.GetOutputPort("state")

    def monitor(root_context):
        t = root_context.get_time()
        if display.due():
            display.update(t, f"t = {t:.0f} s")
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
