"""Trajectory-tracking control law for a hovering 4-DOF vehicle (pure numpy, no Drake).

Position and heading are controlled independently: a hovering vehicle can look one way and move
another. The law is a computed-force PID in the world frame:

    a = kp e_p + kd e_v + ki int(e_p + (kd / kp) e_v)  (world, m/s^2; e_v = v_ref - v)
    F_body = M_t R_WB^T a + D(v_body) v_body           (surge, sway, heave)
    N = I_z (kp_yaw e_yaw + kd_yaw (r_ref - r)) + D(r_ref) r_ref

where M_t and I_z are the diagonal entries of M = M_RB + M_A and D the model's damping. In
translation the damping at the vehicle's velocity is cancelled, so in still water the error
dynamics are the chosen third-order ones and the reference velocity is tracked without lag. In
a current the damping acts on the velocity through the water, which the controller does not
know: the integral supplies the difference (D(v_c) v_c to hold station), so a steady current
leaves no steady error. It integrates the PD's own command over kp (the series PID form), not
the position error alone: a behaviour that re-anchors its reference on the vehicle at every
update (profile following) keeps the position error near zero, and there only the velocity
error shows what the current takes away (and undoes what a transient wound up). Anti-windup:
the integral's contribution is clamped per world axis to the acceleration the thrusters can
give along the weakest body axis that serves it (horizontal: sway, one thruster; vertical:
heave, two), and while the thrusters saturate the integral does not grow (conditional
integration: a component only integrates what shrinks it).

In yaw the linear damping (130 N m s) is large against I_z (8 kg m^2): cancelling it on the
measured rate through thrusters that lag 0.2 s acts like a negative inertia (about 130 x 0.2 =
26 kg m^2) and a 90 degree heading step overshot by 28 degrees. So the yaw law feeds the damping
forward on the reference rate and lets the physical damping act on the error: the error
dynamics are I_z e'' + (I_z kd_yaw + d_r) e' + I_z kp_yaw e = 0, with d_r = 130 (about 16 I_z),
which the default kp_yaw = 16 1/s^2 makes well damped (no overshoot, 4.7 s to within 5 % of a
90 degree step). A current puts no yaw moment on the model (its damping acts at the centre of
buoyancy and its translational added masses are equal), so the heading needs no integral. Roll
and pitch are left to passive stability.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from drake_auv.params import param, validate
from drake_auv.signals import Reference, VehicleState
from drake_auv.vehicle.model import Girona500Params


@dataclass(frozen=True)
class TrackingGains:
    """Gains of the tracking law (docs/vehicle.md justifies the defaults).

    Attributes:
        kp: position stiffness, 1/s^2.  kd: velocity gain, 1/s.
        ki: integral gain, 1/s^3 (0: no integral action). The integral is of the PD's own
            command over kp, e_p + (kd / kp) e_v (the series PID form): it sees a steady
            position error, and also the velocity a behaviour asks for but does not get when
            it re-anchors its reference on the vehicle every update. The default 0.2 puts the
            poles of s^3 + kd s^2 + (kp + ki kd / kp) s + ki at -0.91 +- 0.49j and -0.19 1/s:
            a steady current's error decays with a 5.3 s time constant.
        kp_yaw: 1/s^2.  kd_yaw: 1/s, added to the vehicle's own yaw damping (see above).
    """

    kp: float = param(1.0, low=0.0, high=1e3, unit="1/s^2")
    kd: float = param(2.0, low=0.0, high=1e3, unit="1/s")
    ki: float = param(0.2, low=0.0, high=1e3, unit="1/s^3")
    kp_yaw: float = param(16.0, low=0.0, high=1e3, unit="1/s^2")
    kd_yaw: float = param(0.0, low=0.0, high=1e3, unit="1/s")

    def __post_init__(self):
        validate(self)
        if self.ki > 0 and not self.ki < self.ki_bound:
            raise ValueError(f"TrackingGains.ki must be < {self.ki_bound:g} for a stable loop with "
                             f"kp = {self.kp:g} and kd = {self.kd:g}, got {self.ki}")

    @property
    def ki_bound(self) -> float:
        """The largest stable ki, 1/s^3: Routh on s^3 + kd s^2 + (kp + ki kd / kp) s + ki
        asks kd kp^2 > ki (kp - kd^2) (any ki when kd^2 >= kp), with kp, kd > 0."""
        if self.kp <= 0 or self.kd <= 0:
            return 0.0
        margin = self.kp - self.kd ** 2
        return math.inf if margin <= 0 else self.kd * self.kp ** 2 / margin


def wrap_angle(a):
    """Angle(s) wrapped to [-pi, pi)."""
    return (np.asarray(a) + np.pi) % (2.0 * np.pi) - np.pi


def rotation_world_body(roll: float, pitch: float, yaw: float) -> np.ndarray:
    """R_WB = Rz(yaw) Ry(pitch) Rx(roll)."""
    cr, sr = math.cos(roll), math.sin(roll)
    cp, sp = math.cos(pitch), math.sin(pitch)
    cy, sy = math.cos(yaw), math.sin(yaw)
    return np.array([[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
                     [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
                     [-sp, cp * sr, cp * cr]])


def axis_force_limits(params: Girona500Params) -> np.ndarray:
    """(3,) the largest force (N) the thrusters give along body x, y and z alone: the thrust
    limit over the largest thrust the allocation asks per newton on that axis."""
    allocation = params.allocation_matrix()[:, :3]
    return params.max_thrust / np.abs(allocation).max(axis=0)


class TrackingController:
    """Computes the body wrench [X, Y, Z, N] that tracks an 8-vector reference."""

    def __init__(self, params: Girona500Params | None = None, gains: TrackingGains | None = None):
        params = params if params is not None else Girona500Params()
        self.gains = gains if gains is not None else TrackingGains()
        mass = params.mass_matrix()
        self.mass_t = np.diag(mass)[:3].copy()
        self.inertia_z = float(mass[5, 5])
        self.d_lin = np.asarray(params.linear_damping, dtype=float)
        self.d_quad = np.asarray(params.quadratic_damping, dtype=float)
        # Net buoyancy is compensated by feed-forward (world +z force, N).
        self.net_up = params.buoyancy - params.weight
        self.allocation = params.allocation_matrix()
        self.max_thrust = params.max_thrust
        # Anti-windup bound of the integral per world axis, m s: ki int(e_p) at most the
        # acceleration of the weakest body axis serving it (x, y: surge or sway; z: heave).
        accel = axis_force_limits(params) / self.mass_t
        accel = np.array([accel[:2].min(), accel[:2].min(), accel[2]])
        self.integral_limit = accel / self.gains.ki if self.gains.ki > 0 else np.zeros(3)
        self.lead = self.gains.kd / self.gains.kp if self.gains.kp > 0 else 0.0  # s

    def wrench(self, reference: np.ndarray, state: np.ndarray, integral: np.ndarray,
               dt: float) -> tuple[np.ndarray, np.ndarray]:
        """(wrench (4,), updated position integral (3,), m s) for one control period dt (s)."""
        g = self.gains
        state, reference = VehicleState(state), Reference(reference)
        rot = rotation_world_body(state.roll, state.pitch, state.yaw)
        v_body = state.linear_velocity
        e_p = reference.position - state.position
        e_v = reference.velocity - rot @ v_body
        accel = g.kp * e_p + g.kd * e_v
        damping = self.d_lin[:3] * v_body
        quadratic = self.d_quad[:3] * np.abs(v_body) * v_body
        up = self.net_up * rot[2]
        r = state.r
        e_yaw = float(wrap_angle(reference.yaw - state.yaw))
        r_ref = reference.yaw_rate
        yaw_moment = (self.inertia_z * (g.kp_yaw * e_yaw + g.kd_yaw * (r_ref - r))
                      + self.d_lin[5] * r_ref + self.d_quad[5] * abs(r_ref) * r_ref)
        wrench = np.empty(4)
        wrench[3] = yaw_moment
        integral = np.asarray(integral, dtype=float)
        grow = (e_p + self.lead * e_v) * dt  # the PD's own command over kp, integrated
        if g.ki > 0:
            wrench[:3] = self.mass_t * (rot.T @ (accel + g.ki * integral))
            wrench[:3] += damping + quadratic - up
            if np.abs(self.allocation @ wrench).max() > self.max_thrust:
                grow = np.where(grow * integral >= 0.0, 0.0, grow)  # only unwind while saturated
        integral = np.clip(integral + grow, -self.integral_limit, self.integral_limit)
        wrench[:3] = self.mass_t * (rot.T @ (accel + g.ki * integral)) + damping + quadratic - up
        return wrench, integral


def cross_track_distance(points, polyline, chunk: int = 2048) -> np.ndarray:
    """(n,) distance of each point (n, 3) to the nearest segment of a polyline (m, 3), m.

    Vectorised over segments; points are processed in chunks to bound memory.
    """
    points = np.atleast_2d(np.asarray(points, dtype=float))
    polyline = np.atleast_2d(np.asarray(polyline, dtype=float))
    if len(polyline) == 1:
        return np.linalg.norm(points - polyline[0], axis=1)
    a, b = polyline[:-1], polyline[1:]
    ab = b - a
    denom = np.maximum(np.einsum("ij,ij->i", ab, ab), 1e-18)
    out = np.empty(len(points))
    for start in range(0, len(points), chunk):
        p = points[start:start + chunk, None, :]
        t = np.clip(np.einsum("nmj,mj->nm", p - a, ab) / denom, 0.0, 1.0)
        d = p - (a + t[..., None] * ab)
        out[start:start + chunk] = np.sqrt(np.einsum("nmj,nmj->nm", d, d).min(axis=1))
    return out
