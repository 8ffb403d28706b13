"""Trajectory-tracking control law for a hovering 4-DOF vehicle (pure numpy, no Drake).

Position and heading are controlled independently: a hovering vehicle can look one way and move
another. The law is a computed-force PID in the world frame:

    a = kp e_p + kd (v_ref - v) + ki int(e_p)          (world, m/s^2)
    F_body = M_t R_WB^T a + D(v_body) v_body           (surge, sway, heave)
    N = I_z (kp_yaw e_yaw + kd_yaw (r_ref - r)) + D(r_ref) r_ref

where M_t and I_z are the diagonal entries of M = M_RB + M_A and D the model's damping. In
translation the damping at the current velocity is cancelled, so the error dynamics are the
chosen second-order ones and the reference velocity is tracked without lag. In yaw the linear
damping (130 N m s) is large against I_z (8 kg m^2): cancelling it on the measured rate
through thrusters that lag 0.2 s acts like a negative inertia (about 130 x 0.2 = 26 kg m^2)
and a 90 degree heading step overshot by 28 degrees. So the yaw law feeds the damping forward
on the reference rate and lets the physical damping act on the error: the error dynamics are
I_z e'' + (I_z kd_yaw + d_r) e' + I_z kp_yaw e = 0, with d_r = 130 (about 16 I_z), which the
default kp_yaw = 16 1/s^2 makes well damped (no overshoot, 4.7 s to within 5 % of a 90 degree
step). Roll and pitch are left to passive stability.
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
    """Gains of the tracking law (by default natural frequency 1 rad/s, critically damped).

    Attributes:
        kp: position stiffness, 1/s^2.  kd: velocity gain, 1/s.
        ki: integral gain, 1/s^3; 0 by default because the model's damping and net buoyancy are
            cancelled exactly and an integral adds a slow pole (~ki/kp) that drags the stop at
            the end of a path; raise it (e.g. 0.05) against unmodelled currents.
        kp_yaw: 1/s^2.  kd_yaw: 1/s, added to the vehicle's own yaw damping (see above).
        integral_limit: anti-windup bound on each component of the position integral, m s.
    """

    kp: float = param(1.0, low=0.0, high=1e3, unit="1/s^2")
    kd: float = param(2.0, low=0.0, high=1e3, unit="1/s")
    ki: float = param(0.0, low=0.0, high=1e3, unit="1/s^3")
    kp_yaw: float = param(16.0, low=0.0, high=1e3, unit="1/s^2")
    kd_yaw: float = param(0.0, low=0.0, high=1e3, unit="1/s")
    integral_limit: float = param(5.0, low=0.0, high=1e3, unit="m s")

    def __post_init__(self):
        validate(self)
        if self.ki > 0 and not self.ki < self.kp * self.kd:
            raise ValueError(f"TrackingGains.ki must be < kp * kd = {self.kp * self.kd:g} for a "
                             f"stable loop, got {self.ki}")


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

    def wrench(self, reference: np.ndarray, state: np.ndarray, integral: np.ndarray,
               dt: float) -> tuple[np.ndarray, np.ndarray]:
        """(wrench (4,), updated position integral (3,)) for one control period dt (s)."""
        g = self.gains
        state, reference = VehicleState(state), Reference(reference)
        rot = rotation_world_body(state.roll, state.pitch, state.yaw)
        v_body = state.linear_velocity
        e_p = reference.position - state.position
        integral = np.clip(integral + e_p * dt, -g.integral_limit, g.integral_limit)
        accel = g.kp * e_p + g.kd * (reference.velocity - rot @ v_body) + g.ki * integral
        force = (self.mass_t * (rot.T @ accel) + self.d_lin[:3] * v_body
                 + self.d_quad[:3] * np.abs(v_body) * v_body - self.net_up * rot[2])
        r = state.r
        e_yaw = float(wrap_angle(reference.yaw - state.yaw))
        r_ref = reference.yaw_rate
        yaw_moment = (self.inertia_z * (g.kp_yaw * e_yaw + g.kd_yaw * (r_ref - r))
                      + self.d_lin[5] * r_ref + self.d_quad[5] * abs(r_ref) * r_ref)
        return np.array([force[0], force[1], force[2], yaw_moment]), integral


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
