"""A mission step of your own: define it, register it, fly it from a mission file.

A step kind is its spec (what the mission file holds), its legs and its behaviour (the
LeafSystem that drives the tracker on those legs), all here, outside the package:

    - circle: {centre: [x, y], radius_m: 2.0, depth_m: 3.0, laps: 1, speed: 0.4}

flies `laps` laps counter-clockwise around `centre` (site coordinates) at `depth_m`, after a
transit to the circle's west point. `Circle` (a `MissionStep`) plans the two legs;
`CircleFollower` (a `Behaviour`: `estimated_state` and `leg` in, `reference` and `status`
out) gives the tracker the point moving along the circle at `speed` from the time its leg
began, and reports the leg finished after the laps. `register(Circle)` adds the kind to the
registry; the mission file below is read, planned and flown as any other, the supervisor
switching to the follower through its `circle_status` and the `PortSwitch` input `circle`.

Run:
    MPLBACKEND=Agg .venv/bin/python examples/custom_step.py [--laps 1] [--out OUT]
It writes OUT/circle.yaml (default: a temporary folder) and prints the legs' outcomes and the
radial error of the estimated track while circling.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import ClassVar

import numpy as np
import yaml

from drake_auv.behaviour import Behaviour, read_leg
from drake_auv.mission.config import load_mission
from drake_auv.mission.legs import Leg
from drake_auv.mission.runner import run_mission
from drake_auv.mission.steps import STEPS, register
from drake_auv.mission.steps.step import TIME_SLACK, TRANSIT_SPEED, MissionStep
from drake_auv.params import param, validate
from drake_auv.signals import BehaviourStatus, Reference, VehicleState


@dataclass(frozen=True)
class CircleStep:
    """Laps around a point. Attributes: centre (x, y), site coordinates, m; radius_m, m;
    depth_m, m (positive down); laps; speed, m/s."""

    KIND: ClassVar[str] = "circle"
    centre: tuple = param(kind="vector", names=("x", "y"), unit="m, site coordinates")
    radius_m: float = param(2.0, low=0.5, high=100.0, unit="m")
    depth_m: float = param(3.0, low=0.5, high=1000.0, unit="m")
    laps: float = param(1.0, low=0.0, high=20.0, low_open=True)
    speed: float = param(0.4, low=0.05, high=1.4, unit="m/s")

    def __post_init__(self):
        validate(self)


@dataclass(frozen=True)
class CircleLeg:
    """A circle leg, local frame: centre (x, y), radius m, z m, speed m/s, laps."""

    centre: tuple
    radius: float
    z: float
    speed: float
    laps: float

    def angle(self, elapsed: float) -> float:
        """The angle from the centre (rad, from the west point, counter-clockwise) after
        `elapsed` s on the leg, held at the last lap's end."""
        return np.pi + self.speed / self.radius * min(elapsed, self.duration)

    @property
    def duration(self) -> float:
        return 2.0 * np.pi * self.radius * self.laps / self.speed


class CircleFollower(Behaviour):
    """Flies its circle legs ({leg index: `CircleLeg`}); stateless, a function of the time
    since the leg began. Status progress: the laps flown."""

    def __init__(self, legs: dict[int, CircleLeg]):
        super().__init__(legs)
        self.DeclareReferenceOutput(self._calc_reference, {
            self.time_ticket(), self.input_port_ticket(self.leg_input.get_index()),
            self.input_port_ticket(self.state_input.get_index())})
        self.DeclareStatusOutput(self._status, {
            self.time_ticket(), self.input_port_ticket(self.leg_input.get_index())})

    def _elapsed(self, context) -> tuple[int, float]:
        leg, start = read_leg(self.leg_input, context)
        return leg, context.get_time() - start

    def _calc_reference(self, context, output):
        leg, elapsed = self._elapsed(context)
        reference = Reference.zeros()
        circle = self.legs.get(leg)
        if circle is None:  # not ours: hold the estimated pose
            state = VehicleState(self.state_input.Eval(context))
            reference.position, reference.yaw = state.position, state.yaw
        else:
            angle, omega = circle.angle(elapsed), circle.speed / circle.radius
            moving = elapsed < circle.duration
            reference.position = (circle.centre[0] + circle.radius * np.cos(angle),
                                  circle.centre[1] + circle.radius * np.sin(angle), circle.z)
            reference.yaw = angle + np.pi / 2  # along the circle
            if moving:
                reference.velocity = (-circle.speed * np.sin(angle),
                                      circle.speed * np.cos(angle), 0.0)
                reference.yaw_rate = omega
        output.SetFromVector(reference[:])

    def _status(self, context) -> BehaviourStatus:
        leg, elapsed = self._elapsed(context)
        status = BehaviourStatus.zeros()
        circle = self.legs.get(leg)
        status.leg = leg if circle is not None else -1.0
        if circle is not None:
            status.progress = circle.laps * min(elapsed / circle.duration, 1.0)
            status.finished = float(elapsed >= circle.duration)
        return status


class Circle(MissionStep):
    spec = CircleStep
    behaviour = "circle"

    @classmethod
    def _leg(cls, planning, step) -> CircleLeg:
        centre = planning.site.to_local(np.asarray(step.centre, dtype=float))[:2]
        return CircleLeg(tuple(centre), step.radius_m, -step.depth_m, step.speed, step.laps)

    @classmethod
    def start(cls, planning, index: int, step) -> np.ndarray:
        circle, start = cls._leg(planning, step), np.zeros(12)
        start[:3] = circle.centre[0] - circle.radius, circle.centre[1], circle.z
        start[5] = -np.pi / 2  # heading along the circle at its west point
        return start

    @classmethod
    def plan(cls, planning, k: int, step) -> None:
        circle = cls._leg(planning, step)
        west = (circle.centre[0] - circle.radius, circle.centre[1], circle.z)
        planning.add_transit(k, west, -np.pi / 2, TRANSIT_SPEED)
        planning.add(Leg("circle", k, "circle", "finished",
                         planning.margin * circle.duration + TIME_SLACK), circle)
        planning.position = np.asarray(west)

    @classmethod
    def add_behaviour(cls, wiring, legs: dict):
        return wiring.builder.AddNamedSystem("circle_follower", CircleFollower(legs))


def fly(out: Path, laps: float = 1.0) -> dict:
    """Writes the mission file (the pool, one circle step) to `out`, flies it; returns
    {outcomes, radial error (max, m) while circling, circling time s}."""
    if "circle" not in STEPS:
        register(Circle)
    out.mkdir(parents=True, exist_ok=True)
    path = out / "circle.yaml"
    path.write_text(yaml.safe_dump({
        "name": "circle", "site": {"scenario": "pool"},
        "steps": [{"circle": {"centre": [0.0, 0.0], "radius_m": 2.0, "depth_m": 3.0,
                              "laps": laps, "speed": 0.4}}]}))
    result = run_mission(load_mission(path), progress=False)
    circling = result.log.leg_at == 1
    position = VehicleState(result.log.estimated[circling]).position
    radial = np.abs(np.hypot(position[:, 0], position[:, 1]) - 2.0)
    times = result.log.times[circling]
    return dict(outcomes=result.dive.outcomes, radial_error_m=float(radial.max()),
                circling_s=float(times[-1] - times[0]))


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--laps", type=float, default=1.0)
    parser.add_argument("--out", type=Path, default=None)
    args = parser.parse_args(argv)
    if not (np.isfinite(args.laps) and 0 < args.laps <= 20):
        raise SystemExit(f"--laps must be in (0, 20], got {args.laps}")
    with tempfile.TemporaryDirectory() as folder:
        row = fly(args.out or Path(folder), args.laps)
    print(f"legs: {', '.join(row['outcomes'])}; circled {row['circling_s']:.1f} s, radial "
          f"error at most {row['radial_error_m']:.2f} m")
    return 0


if __name__ == "__main__":
    sys.exit(main())
