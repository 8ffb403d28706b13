"""Legs: a mission's steps as the supervisor flies them, and when each one is done. Pure.

A mission step becomes one or two legs: a transit to where the step begins, then the step's
own behaviour (profile following, the nominal plan, the replanner, or an exported vehicle
mission flown by the autopilot pilot, which needs no transit: its first item is one). A leg is done by its
goal, judged only on what the vehicle knows (its estimated state, the behaviours' status, the
operator's chart of the site), or by its time budget.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

BEHAVIOURS = ("path", "follow", "replan", "autopilot", "explore")
GOALS = ("arrive", "loops", "distance", "path_end", "replanner", "autopilot", "explorer")


@dataclass(frozen=True)
class Leg:
    """One leg.

    Attributes:
        phase: name of the part of the mission it belongs to ("transit", "follow", "survey").
        step: index of the mission step it flies (-1: none).
        behaviour: which behaviour drives the tracker (`BEHAVIOURS`).
        goal: how the leg ends (`GOALS`): "arrive" within `tolerance` m of `target`; "loops"
            turns around `centre` (x, y); "distance" m along `direction` (x, y) from where the
            leg began, and shallower than `end_depth` m if given; "path_end" past the end of
            the path reference's path; "replanner" when the replanner has visited every
            waypoint; "autopilot" when the autopilot pilot has flown the file's last item;
            "explorer" when the view planner finds nothing more worth seeing.
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
        if self.behaviour not in BEHAVIOURS:
            raise ValueError(f"Leg behaviour must be one of {BEHAVIOURS}, got {self.behaviour!r}")
        if self.goal not in GOALS:
            raise ValueError(f"Leg goal must be one of {GOALS}, got {self.goal!r}")
        if not (np.isfinite(self.max_duration) and self.max_duration > 0):
            raise ValueError(f"Leg max_duration must be > 0 s, got {self.max_duration}")


PROGRESS_SIZE = 4  # [last bearing from the centre (rad), turned (rad), start x, start y]


def start_progress(leg: Leg, x: np.ndarray) -> np.ndarray:
    """The progress record of `leg` beginning at the estimated state `x`."""
    bearing = 0.0
    if leg.goal == "loops":
        bearing = float(np.arctan2(x[1] - leg.centre[1], x[0] - leg.centre[0]))
    return np.array([bearing, 0.0, x[0], x[1]])


def advance_progress(leg: Leg, progress: np.ndarray, x: np.ndarray) -> np.ndarray:
    """The progress record after the vehicle moved to `x` (the turned angle accumulates the
    bearing's wrapped increments, so it counts laps in either direction)."""
    if leg.goal != "loops":
        return progress
    bearing = float(np.arctan2(x[1] - leg.centre[1], x[0] - leg.centre[0]))
    step = float(np.angle(np.exp(1j * (bearing - progress[0]))))
    return np.array([bearing, progress[1] + step, progress[2], progress[3]])


def goal_reached(leg: Leg, index: int, t: float, x: np.ndarray, progress: np.ndarray,
                 path_status: np.ndarray, replanner_status: np.ndarray,
                 autopilot_status: np.ndarray | None = None,
                 explorer_status: np.ndarray | None = None) -> bool:
    """Whether leg number `index` has reached its goal at time `t` s, from the estimated state
    `x` (12), its progress record, the path reference's status `[leg, end_time]`, the
    replanner's `[leg, finished, next_index]`, the autopilot pilot's `[leg, finished,
    item]` and the view planner's `[leg, finished, viewpoints]`."""
    if leg.goal == "arrive":
        distance = np.linalg.norm(x[:3] - np.asarray(leg.target))
        if leg.handover is not None and path_status[0] == index and distance <= leg.handover:
            return True
        return path_status[0] == index and t >= path_status[1] and distance <= leg.tolerance
    if leg.goal == "path_end":
        return path_status[0] == index and t >= path_status[1]
    if leg.goal == "replanner":
        return replanner_status[0] == index and replanner_status[1] > 0
    if leg.goal == "autopilot":
        return (autopilot_status is not None and autopilot_status[0] == index
                and autopilot_status[1] > 0)
    if leg.goal == "explorer":
        return (explorer_status is not None and explorer_status[0] == index
                and explorer_status[1] > 0)
    if leg.goal == "loops":
        return abs(progress[1]) >= 2.0 * np.pi * leg.loops
    along = (x[0] - progress[2]) * leg.direction[0] + (x[1] - progress[3]) * leg.direction[1]
    return along >= (leg.distance or 0.0) and (leg.end_depth is None or -x[2] <= leg.end_depth)
