"""How COLA2 and ArduSub AUTO execute their mission items, as a tracker reference. Pure numpy.

The pilot (`drake_auv.autopilot.pilot`) flies one item at a time. When an item begins, its
`ItemStart` records where the leg starts (xy and z) and the vertical reference there; every
control period `item_reference` gives the tracker's 8-vector reference
`[x, y, z, yaw, vx, vy, vz, yaw_rate]` (local frame) and `item_reached` says whether the item
is done. Both read only what the vehicle knows: its estimated state and the seabed elevation
under it measured by its own DVL (`z - altitude`), never the true world.

Horizontal, both autopilots: line-of-sight cross-track control on the straight line from the
leg's start to its end at the commanded speed. The reference is the vehicle's foot on the line,
moving along it at the speed (so the cross-track error is driven to zero and the along-track
speed is the commanded one); past the end it holds the end. Heading: along the line, or the
item's yaw when the file commands one.

Vertical:
- COLA2 (`heave_in_3d` off, its default): the section's FINAL depth (depth mode) or FINAL
  altitude over the measured seabed (altitude mode) is the target from the section's first
  instant. With `heave_in_3d` the depth is interpolated from the section's initial to its final
  depth along the track (altitude is never interpolated). Altitude mode without bottom lock
  and `no_altitude_goes_up` (the exports set it): the vehicle rises at `rise_rate`.
- ArduSub AUTO: a straight 3D leg from the previous waypoint (the vehicle's position for the
  first): frame 3 (depth) interpolates the elevation along the track; frame 10 (altitude over
  the seabed, from the downward rangefinder) interpolates the altitude target along the track
  and holds it over the measured seabed. A leg from a depth waypoint to an altitude one starts
  at the altitude measured where it begins, and the reverse at the depth it begins at.
  Without bottom lock the last measured seabed is held.

Arrival: COLA2 goto, section and park end when the vehicle is within `tolerance_xy` of the
final point horizontally, or past the end along the track (a section is never flown back); a
park then holds for its time. ArduSub: within the acceptance radius of the waypoint in 3D (the
vertical error measured in the item's frame), or past its end along the track, then the hold.
"""

from __future__ import annotations

import numpy as np

from drake_auv.autopilot.items import LocalLeg, leg_target_z
from drake_auv.signals import Reference, VehicleState

RISE_RATE = 0.3  # m/s, COLA2's no_altitude_goes_up ascent without bottom lock
# The pilot's per-item record: item index, when it began (s), the leg's start (x0, y0, z0,
# m), the altitude target there (alt0, m), when its end was reached (reached_s, -1: not yet)
# and the last seabed elevation the DVL measured (seabed_z, m, NaN: none yet).
ITEM_FIELDS = ("index", "start_s", "x0", "y0", "z0", "alt0", "reached_s", "seabed_z")
INDEX, START_S, X0, Y0, Z0, ALT0, REACHED_S, SEABED_Z = range(len(ITEM_FIELDS))


def start_record(autopilot: str, legs: tuple[LocalLeg, ...], index: int, t: float,
                 x: np.ndarray, seabed_z: float) -> np.ndarray:
    """The `ITEM_FIELDS` record of item `index` beginning at `t` with the vehicle at the
    estimated state `x` over the measured seabed `seabed_z` (NaN: no measurement yet)."""
    leg, state = legs[index], VehicleState(x)
    x0, y0, z0 = state.x, state.y, state.z
    if autopilot == "cola2" and leg.start is not None:
        x0, y0 = leg.start
        if leg.start_z is not None:
            z0 = leg.start_z
    elif autopilot == "ardusub" and index > 0:
        previous = legs[index - 1]
        x0, y0 = previous.end
        z0 = leg_target_z(previous, seabed_z if np.isfinite(seabed_z) else state.z - previous.z)
    if autopilot == "ardusub" and index > 0 and legs[index - 1].z_mode == leg.z_mode == "altitude":
        alt0 = legs[index - 1].z
    else:
        alt0 = state.z - seabed_z if np.isfinite(seabed_z) else leg.z
    return np.array([index, t, x0, y0, z0, alt0, -1.0, seabed_z], float)


def _track(leg: LocalLeg, record: np.ndarray, x: np.ndarray):
    """(start xy, unit direction, length, the vehicle's along-track position s in [0, L])."""
    a = record[X0:Y0 + 1]
    d = np.asarray(leg.end, float) - a
    length = float(np.hypot(*d))
    if length < 1e-9:
        return a, np.zeros(2), 0.0, 0.0
    u = d / length
    s = float(np.clip((VehicleState(x).xy - a) @ u, 0.0, length))
    return a, u, length, s


def item_reference(autopilot: str, leg: LocalLeg, record: np.ndarray, x: np.ndarray,
                   seabed_z: float, speed: float, heave_in_3d: bool = False) -> np.ndarray:
    """The tracker's 8-vector reference flying `leg` (see the module docstring).

    Args:
        record: the item's `ITEM_FIELDS` record. x: (12,) estimated state.
        seabed_z: the seabed's elevation under the vehicle as the DVL measures it now, m
            (NaN: no bottom lock).
        speed: commanded speed along the track, m/s.
    """
    a, u, length, s = _track(leg, record, x)
    state = VehicleState(x)
    holding = record[REACHED_S] >= 0  # reached: held there for the item's hold time
    v = 0.0 if (holding or s >= length) else speed
    foot = np.asarray(leg.end, float) if holding else a + s * u
    fraction = s / length if length > 0 and not holding else 1.0
    dz_ds = 0.0
    measured = np.isfinite(seabed_z)
    if autopilot == "cola2":
        if leg.z_mode == "depth":
            z = -leg.z
            if heave_in_3d and leg.kind == "section" and leg.start_z is not None:
                z = record[Z0] + fraction * (-leg.z - record[Z0])
                dz_ds = (-leg.z - record[Z0]) / length if length > 0 else 0.0
        elif measured:
            z = seabed_z + leg.z
        else:  # no_altitude_goes_up
            z = state.z + RISE_RATE
    else:
        if leg.z_mode == "depth":
            z = record[Z0] + fraction * (-leg.z - record[Z0])
            dz_ds = (-leg.z - record[Z0]) / length if length > 0 else 0.0
        else:
            seabed = seabed_z if measured else record[SEABED_Z]
            altitude = record[ALT0] + fraction * (leg.z - record[ALT0])
            z = seabed + altitude if np.isfinite(seabed) else state.z
    if leg.yaw is not None:
        yaw = leg.yaw
    elif length > 0:
        yaw = float(np.arctan2(u[1], u[0]))
    else:
        yaw = float(state.yaw)
    reference = Reference.zeros()
    reference.position, reference.yaw = [foot[0], foot[1], z], yaw
    reference.velocity = [v * u[0], v * u[1], v * dz_ds]
    return reference[:]


def item_reached(autopilot: str, leg: LocalLeg, record: np.ndarray, x: np.ndarray,
                 seabed_z: float) -> bool:
    """Whether the vehicle at `x` has reached `leg`'s end (before any hold)."""
    _, _, length, s = _track(leg, record, x)
    state = VehicleState(x)
    horizontal = float(np.hypot(*(state.xy - np.asarray(leg.end, float))))
    passed = length > 0 and s >= length
    if autopilot == "cola2":
        return horizontal <= leg.tolerance or passed
    if leg.z_mode == "depth":
        dz = state.z + leg.z
    else:
        seabed = seabed_z if np.isfinite(seabed_z) else record[SEABED_Z]
        dz = (state.z - seabed - leg.z) if np.isfinite(seabed) else 0.0
    return float(np.hypot(horizontal, dz)) <= leg.tolerance or passed


def mission_duration(legs: tuple[LocalLeg, ...], start_xy, default_speed: float) -> float:
    """Nominal time to fly `legs` from `start_xy`, s: their horizontal lengths at their
    speeds, plus the holds."""
    position = np.asarray(start_xy, float)[:2]
    total = 0.0
    for leg in legs:
        a = np.asarray(leg.start, float) if leg.start is not None else position
        end = np.asarray(leg.end, float)
        total += (np.hypot(*(a - position)) + np.hypot(*(end - a))) / (leg.speed or default_speed)
        total += leg.hold_s
        position = end
    return total
