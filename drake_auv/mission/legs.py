"""Legs: a mission's steps as the supervisor flies them, and when each one is done. Pure.

A mission step becomes one or two legs (`drake_auv.mission.steps`): a transit to where the
step begins, then the step's own behaviour (profile following, the nominal plan, the
replanner, or an exported vehicle mission flown by the autopilot pilot, which needs no
transit: its first item is one). A leg is done by its goal, judged only on what the vehicle
knows (its estimated state, its behaviour's status, the operator's chart of the site), or by
its time budget.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from drake_auv.signals import BehaviourStatus, LegProgress, VehicleState

GOALS = ("arrive", "loops", "distance", "finished")


@dataclass(frozen=True)
class Leg:
    """One leg.

    Attributes:
        phase: name of the part of the mission it belongs to ("transit", "follow", "survey").
        step: index of the mission step it flies (-1: none).
        behaviour: the name of the behaviour that drives the tracker ("path", "follow",
            "replan", "autopilot", "explore" or a step's own: `drake_auv.mission.steps`).
        goal: how the leg ends (`GOALS`): "arrive" within `tolerance` m of `target` once the
            behaviour has finished its path; "loops" turns around `centre` (x, y); "distance"
            m along `direction` (x, y) from where the leg began, and shallower than
            `end_depth` m if given; "finished" when the behaviour reports the leg finished
            (`leg_finished`: the path flown, every waypoint replanned, the
            file's last item flown, nothing more worth seeing).
        max_duration: the leg ends anyway after this, s (a timed-out leg is reported).
        handover: an "arrive" leg ends as soon as the vehicle is within this distance of
            `target`, m (the next behaviour flies the rest; None: it ends on arrival).
    """

    phase: str
    step: int
    behaviour: str
    goal: str
    max_duration: float
    target: tuple | None = None
    tolerance: float = 1.0
    centre: tuple | None = None
    loops: float = 1.0
    direction: tuple | None = None
    distance: float | None = None
    end_depth: float | None = None
    handover: float | None = None

    def __post_init__(self):
        if not (isinstance(self.behaviour, str) and self.behaviour.isidentifier()):
            raise ValueError(f"Leg behaviour must be a name (an identifier), got "
                             f"{self.behaviour!r}")
        if self.goal not in GOALS:
            raise ValueError(f"Leg goal must be one of {GOALS}, got {self.goal!r}")
        if not (np.isfinite(self.max_duration) and self.max_duration > 0):
            raise ValueError(f"Leg max_duration must be > 0 s, got {self.max_duration}")


def _bearing(leg: Leg, state) -> float:
    """Bearing of the vehicle's `state` (a `VehicleState`) from the loops' centre, rad."""
    return float(np.arctan2(state.y - leg.centre[1], state.x - leg.centre[0]))


def start_progress(leg: Leg, x: np.ndarray) -> np.ndarray:
    """The progress record (`signals.LegProgress`) of `leg` beginning at the estimated state
    `x`."""
    state = VehicleState(x)
    progress = LegProgress.zeros()
    progress.bearing = _bearing(leg, state) if leg.goal == "loops" else 0.0
    progress.start = [state.x, state.y]
    return progress[:]


def advance_progress(leg: Leg, progress: np.ndarray, x: np.ndarray) -> np.ndarray:
    """The progress record after the vehicle moved to `x` (the turned angle accumulates the
    bearing's wrapped increments, so it counts laps in either direction)."""
    if leg.goal != "loops":
        return progress
    advanced = LegProgress(np.array(progress, dtype=float))
    bearing = _bearing(leg, VehicleState(x))
    advanced.turned += float(np.angle(np.exp(1j * (bearing - advanced.bearing))))
    advanced.bearing = bearing
    return advanced[:]


def leg_finished(status: np.ndarray, index: int) -> bool:
    """The one rule: whether a behaviour's `status` (`BehaviourStatus`) reports leg `index`
    finished."""
    status = BehaviourStatus(status)
    return bool(status.leg == index and status.finished > 0)


def goal_reached(leg: Leg, index: int, t: float, x: np.ndarray, progress: np.ndarray,
                 status: np.ndarray) -> bool:
    """Whether leg number `index` has reached its goal at time `t` s, from the estimated state
    `x` (`signals.VehicleState`), its progress record (`LegProgress`) and its behaviour's
    status (`BehaviourStatus`, every field -1 while unknown)."""
    state, progress = VehicleState(x), LegProgress(progress)
    if leg.goal == "finished":
        return leg_finished(status, index)
    if leg.goal == "arrive":
        distance = np.linalg.norm(state.position - np.asarray(leg.target))
        if (leg.handover is not None and BehaviourStatus(status).leg == index
                and distance <= leg.handover):
            return True
        return leg_finished(status, index) and distance <= leg.tolerance
    if leg.goal == "loops":
        return abs(progress.turned) >= 2.0 * np.pi * leg.loops
    along = ((state.x - progress.start_x) * leg.direction[0]
             + (state.y - progress.start_y) * leg.direction[1])
    return along >= (leg.distance or 0.0) and (leg.end_depth is None or -state.z <= leg.end_depth)


def leg_share(leg: Leg, elapsed_s: float, x: np.ndarray, progress: np.ndarray,
              behaviour_share: float | None) -> float:
    """How much of `leg` is flown, in [0, 1], `elapsed_s` s after it began with the vehicle at
    the estimated state `x` and its progress record `progress` (`LegProgress`): the laps
    turned or the distance made good for those goals, else its behaviour's own share
    (`behaviour_share`, None when it cannot tell), else the share of its time budget elapsed
    (a lower bound: the budget ends the leg at the latest)."""
    state, record = VehicleState(x), LegProgress(progress)
    if leg.goal == "loops":
        share = abs(record.turned) / (2.0 * np.pi * leg.loops)
    elif leg.goal == "distance" and leg.distance:
        share = ((state.x - record.start_x) * leg.direction[0]
                 + (state.y - record.start_y) * leg.direction[1]) / leg.distance
    elif behaviour_share is not None:
        share = behaviour_share
    else:
        share = elapsed_s / leg.max_duration
    return float(np.clip(share, 0.0, 1.0))
