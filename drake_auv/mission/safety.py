"""The mission supervisor's safety rules: detecting a fault from what the vehicle knows, and
the answer. Pure (numpy); `MissionSupervisor` applies them every period.

Detection (never from the true world or the injected fault itself):
- sonar silent: the sonar a leg relies on (`relied_sensors`: a follow leg the profiler, a
  replanning survey the multibeam, which builds most of the map) has delivered no beams for
  `silence_s` s. Beams without an echo are data (open water, a side-looking fan over a flat
  seabed), not silence.
- thruster failure: the estimated position is more than `tracking_error_m` from the reference
  being tracked for `tracking_s` s (a failed thruster makes the others saturate and the error
  grow; the allocation is not told which one failed), and the error did not shrink over those
  `tracking_s` s at `closing_speed` or faster. A reference the flown autopilot moves in a step
  (COLA2 holds a section's final depth from its first instant: a 9 m step on a steep wall) is
  an error the healthy vehicle closes at its own speed: the window starts again, no fault. A
  failed thruster or a current the thrusters cannot hold leaves the error standing or growing.
  A reference that starts again from the vehicle (the replanner's sections, once a second,
  and the other behaviours that plan from the estimated pose) keeps that error small however
  far the vehicle is carried, so the supervisor also sums the motion the reference did not
  command (`uncommanded`: the estimated displacement less what the reference's velocity
  commands, forwards at up to its speed, and less any part towards the reference, which its
  position commands, up to the distance to it) over windows of `tracking_s`: more than
  `tracking_error_m` in `DRIFT_WINDOWS` windows in a row, while the error to the reference
  did not shrink at `closing_speed`, is the same fault (0.4 m/s of uncommanded motion held
  for 10 s: the vehicle is being swept, not flying its leg; one window is a transient, such
  as a turn onto a new track).
- navigation jump: the estimated position moved more than `jump_m` in one supervisor period
  (the vehicle flies at most ~0.5 m/s: 0.25 m a period).

Answers (`RESPONSES`), each a straight-line reference from the estimated pose where it began:
- hold: hold that pose. On a silent sonar: until it returns again (then the leg resumes) or
  `hold_max_s` s have passed (then abort).
- back_off: `backoff_m` m horizontally away from the nearest occupied voxel of the on-line map
  (at the same depth), then abort; straight to abort when nothing is mapped within
  `backoff_range_m`. The answer to a thruster failure: leave the structure first.
- abort: straight up to `surface_z` (the vehicle rises to the surface where it is, which
  needs neither the map nor the estimate's absolute position); the dive ends on reaching it
  (within `surface_tolerance_m`) or after `abort_max_s` s. The answer to a navigation jump
  (the on-line map no longer agrees with the estimate), to a hold that lasts too long and
  after a back-off.
Responses move at `speed` m/s and never go back to a leg, except a hold on a silent sonar
(the leg's behaviour keeps running meanwhile, unselected, and its time budget runs on).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from drake_auv.params import param, validate
from drake_auv.signals import Reference, Response, VehicleState

RESPONSES = ("none", "hold", "back_off", "abort")
CAUSES = ("none", "sonar_silent", "tracking_error", "navigation_jump")
DRIFT_WINDOWS = 2  # windows in a row of uncommanded motion that make a tracking fault


_POSITIVE = dict(low=0.0, low_open=True)


@dataclass(frozen=True)
class SafetyRules:
    """Thresholds of the detection and the answers (m, s, m/s); see the module docstring."""

    silence_s: float = param(5.0, **_POSITIVE)
    hold_max_s: float = param(60.0, **_POSITIVE)
    tracking_error_m: float = param(2.0, **_POSITIVE)
    tracking_s: float = param(5.0, **_POSITIVE)
    closing_speed: float = param(0.1, **_POSITIVE, unit="m/s")
    jump_m: float = param(1.5, **_POSITIVE)
    backoff_m: float = param(5.0, **_POSITIVE)
    backoff_range_m: float = param(15.0, **_POSITIVE)
    backoff_max_s: float = param(60.0, **_POSITIVE)
    surface_z: float = param(-1.0, unit="m")
    surface_tolerance_m: float = param(0.5, **_POSITIVE)
    abort_max_s: float = param(300.0, **_POSITIVE)
    speed: float = param(0.3, **_POSITIVE)

    def __post_init__(self):
        validate(self)


def closing(rules: SafetyRules, error0: float, error: float, elapsed: float) -> bool:
    """Whether a tracking error of `error0` m `elapsed` s ago, `error` m now, shrank at
    `closing_speed` or faster (the vehicle flying to a reference that stepped away)."""
    return error0 - error >= rules.closing_speed * elapsed


def uncommanded(moved, velocity, dt: float, towards) -> np.ndarray:
    """The part (3,) m of a displacement `moved` (3,) over `dt` s that the reference did not
    command. Along its velocity (3,) m/s only what is backwards or beyond the velocity times
    `dt` counts (a vehicle slower than its reference, accelerating or turning to its track,
    is flying it); of the rest, the part along `towards` (3,), the vector from where the
    vehicle was to the reference, up to its length, is commanded too (a reference moved
    ahead of the vehicle commands the motion towards it)."""
    rest = np.asarray(moved, dtype=float)
    speed = float(np.linalg.norm(velocity))
    if speed > 0.0:
        direction = np.asarray(velocity, dtype=float) / speed
        along = float(rest @ direction)
        rest = rest - min(max(along, 0.0), speed * dt) * direction
    distance = float(np.linalg.norm(towards))
    if distance > 0.0:
        along = float(rest @ towards) / distance
        rest = rest - min(max(along, 0.0), distance) / distance * np.asarray(towards)
    return rest


def drifting(rules: SafetyRules, drift, error0: float, error: float, elapsed: float) -> bool:
    """Whether a window of `elapsed` s (at least `tracking_s`) whose uncommanded motion was
    `drift` (3,) m, the tracking error `error0` m at its start and `error` m now, is a
    tracking fault: the vehicle carried more than `tracking_error_m` where its reference did
    not send it, without closing on that reference."""
    return (float(np.linalg.norm(drift)) > rules.tracking_error_m
            and not closing(rules, error0, error, elapsed))


def relied_sensors(behaviour: str) -> tuple[str, ...]:
    """The sonars (by name) a leg flown by `behaviour` relies on."""
    return {"follow": ("profiler",), "replan": ("multibeam",)}.get(behaviour, ())


def response_record(mode: str, cause: str, t: float, x: np.ndarray, target) -> np.ndarray:
    """The `response` group's value (`signals.Response`) of `mode` for `cause`, begun at `t`
    from the estimated state `x` (12) towards `target` (3,)."""
    state, record = VehicleState(x), Response.zeros()
    record.mode, record.cause, record.start_s = RESPONSES.index(mode), CAUSES.index(cause), t
    record.start, record.yaw0 = state.position, state.yaw
    record.target = np.asarray(target, dtype=float)
    return record[:]


def back_off_target(rules: SafetyRules, x: np.ndarray, occupied: np.ndarray):
    """(3,) `backoff_m` away from the nearest occupied voxel (horizontally, same depth), or
    None when no voxel lies within `backoff_range_m` of the estimated position."""
    if len(occupied) == 0:
        return None
    state = VehicleState(x)
    d = np.linalg.norm(occupied - state.position, axis=1)
    nearest = occupied[int(np.argmin(d))]
    if d.min() > rules.backoff_range_m:
        return None
    here = np.array([state.x, state.y])
    away = here - nearest[:2]
    norm = np.linalg.norm(away)
    behind = state.yaw + np.pi
    away = away / norm if norm > 1e-6 else np.array([np.cos(behind), np.sin(behind)])
    return np.array([*(here + rules.backoff_m * away), state.z])


def abort_target(rules: SafetyRules, x: np.ndarray) -> np.ndarray:
    """(3,) straight above the estimated position, at `surface_z`."""
    state = VehicleState(x)
    return np.array([state.x, state.y, max(rules.surface_z, state.z)])


def response_reference(rules: SafetyRules, record: np.ndarray, t: float) -> np.ndarray:
    """The reference (`signals.Reference`) of a response `record` at `t` s: from its start
    position to its target at `speed`, then held; yaw held."""
    record = Response(record)
    reference = Reference.zeros()
    reference.yaw = record.yaw0
    step = record.target - record.start
    length = float(np.linalg.norm(step))
    travelled = rules.speed * max(t - record.start_s, 0.0)
    if length < 1e-9 or travelled >= length:
        reference.position = record.target
        return reference[:]
    direction = step / length
    reference.position = record.start + travelled * direction
    reference.velocity = rules.speed * direction
    return reference[:]
