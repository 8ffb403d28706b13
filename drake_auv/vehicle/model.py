"""GIRONA 500 model: parameters, YAML loader, thruster geometry, and the 6-DOF Fossen model.

Pure numpy (no Drake), so it is unit-tested on its own; `drake_auv.vehicle.dynamics` wraps it.
Frames: world z up; body FLU (x forward, y left, z up), origin at the centre of
buoyancy (CB). The YAML file gives positions in its source's NED/FRD body frame; `load_girona500`
converts them to FLU once, here, by flipping y and z.

Model (Fossen 2011, relative-velocity form for a vehicle in moving water):

    M_RB nu_dot + C_RB(nu) nu + M_A nu_r_dot + C_A(nu_r) nu_r + D(nu_r) nu_r + g(eta)
        = tau + tau_FK,

nu the absolute body velocity, nu_r = nu - nu_c the velocity through the water with
nu_c = [R^T v_c; 0] (v_c the world-frame water velocity at the vehicle), so
nu_r_dot = nu_dot - [R^T a_c - omega x R^T v_c; 0] (a_c the water's acceleration), and
tau_FK = [rho V R^T a_c; 0] the Froude-Krylov force of the fluid's pressure gradient on the
displaced volume (acting at the CB, the origin, so no moment). C_RB and C_A from Fossen's
Theorem 3.2, D(nu_r) = D_lin + D_quad |nu_r|, restoring forces from weight at the CG and
buoyancy at the CB, and tau = B f where B is the thruster configuration matrix and f the thrusts,
each following its command with a first-order lag. Kinematics use the absolute nu. In still
water (v_c = a_c = 0) this is M nu_dot + C(nu) nu + D(nu) nu + g(eta) = tau with M = M_RB + M_A.
State x = [x, y, z, roll, pitch, yaw, u, v, w, p, q, r, f_1 .. f_5] (the first 12 are the
`state` signal of docs/architecture.md).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import yaml

from drake_auv.signals import THRUSTER_NAMES

DEFAULT_MODEL = Path(__file__).resolve().parents[2] / "models" / "girona500.yaml"
FRD_TO_FLU = np.diag([1.0, -1.0, -1.0])  # the same matrix takes FLU back to FRD
WRENCH_ROWS = (0, 1, 2, 5)  # surge X, sway Y, heave Z, yaw N rows of a 6-DOF wrench
STATE_SIZE = 12
NUM_THRUSTERS = len(THRUSTER_NAMES)


@dataclass(frozen=True)
class Girona500Params:
    """Physical parameters in SI units, body frame FLU, origin at the CB.

    Attributes:
        mass: rigid-body mass, kg.
        inertia: (3,) principal moments about the body axes at the origin, kg m^2.
        centre_of_gravity: (3,) CG position from the CB, m (z < 0: CG below CB).
        gravity: m/s^2.
        buoyancy_ratio: buoyancy / weight (1 = neutral).
        added_mass: (6,) diagonal added mass, kg and kg m^2 (positive magnitudes).
        linear_damping: (6,) N s/m and N m s/rad.
        quadratic_damping: (6,) kg/m and kg m^2.
        max_thrust: per-thruster thrust limit, N (symmetric).
        thruster_time_constant: first-order thruster lag, s.
        thruster_positions: (5, 3) m, FLU, in the order of THRUSTER_NAMES.
        thruster_directions: (5, 3) unit directions of positive thrust, FLU.
    """

    mass: float = 98.0
    inertia: tuple = (8.0, 8.0, 8.0)
    centre_of_gravity: tuple = (0.0, 0.0, -0.05)
    gravity: float = 9.81
    buoyancy_ratio: float = 1.0
    added_mass: tuple = (49.0, 49.0, 49.0, 0.0, 0.0, 0.0)
    linear_damping: tuple = (0.0, 0.0, 0.0, 130.0, 130.0, 130.0)
    quadratic_damping: tuple = (148.0, 148.0, 148.0, 180.0, 180.0, 180.0)
    max_thrust: float = 153.8
    thruster_time_constant: float = 0.2
    thruster_positions: tuple = ((-0.330, 0.259, 0.021), (-0.330, -0.259, 0.021),
                                 (0.535, 0.0, 0.314), (-0.583, 0.0, 0.314),
                                 (-0.063, -0.031, 0.021))
    thruster_directions: tuple = ((1.0, 0.0, 0.0), (1.0, 0.0, 0.0), (0.0, 0.0, 1.0),
                                  (0.0, 0.0, 1.0), (0.0, 1.0, 0.0))

    def __post_init__(self):
        _check_scalar("mass", self.mass, 1e-3, 1e5, "kg")
        _check_scalar("gravity", self.gravity, 1e-3, 100.0, "m/s^2")
        _check_scalar("buoyancy_ratio", self.buoyancy_ratio, 0.5, 1.5, "")
        _check_scalar("max_thrust", self.max_thrust, 1e-3, 1e5, "N")
        _check_scalar("thruster_time_constant", self.thruster_time_constant, 1e-3, 10.0, "s")
        for name, size, low in (("inertia", 3, 1e-6), ("added_mass", 6, 0.0),
                                ("linear_damping", 6, 0.0), ("quadratic_damping", 6, 0.0)):
            _check_vector(name, getattr(self, name), size, low, 1e6)
        _check_vector("centre_of_gravity", self.centre_of_gravity, 3, -10.0, 10.0)
        positions = np.asarray(self.thruster_positions, dtype=float)
        directions = np.asarray(self.thruster_directions, dtype=float)
        if positions.shape != (NUM_THRUSTERS, 3) or not np.all(np.isfinite(positions)):
            raise ValueError(f"thruster_positions must be {NUM_THRUSTERS} finite (x, y, z) "
                             f"rows in m, got {positions.tolist()}")
        norms = np.linalg.norm(directions, axis=1) if directions.ndim == 2 else None
        if (directions.shape != (NUM_THRUSTERS, 3) or not np.all(np.isfinite(directions))
                or np.any(norms < 1e-9)):
            raise ValueError(f"thruster_directions must be {NUM_THRUSTERS} finite non-zero "
                             f"(x, y, z) rows, got {directions.tolist()}")
        object.__setattr__(self, "thruster_directions",
                           tuple(map(tuple, directions / norms[:, None])))

    @property
    def weight(self) -> float:
        """W = m g, N."""
        return self.mass * self.gravity

    @property
    def buoyancy(self) -> float:
        """B, N."""
        return self.buoyancy_ratio * self.weight

    def rigid_body_mass_matrix(self) -> np.ndarray:
        """(6, 6) M_RB about the CB with the CG offset r_g (Fossen eq. 3.44)."""
        m = self.mass
        s_g = _skew(self.centre_of_gravity)
        mrb = np.zeros((6, 6))
        mrb[:3, :3] = m * np.eye(3)
        mrb[:3, 3:] = -m * s_g
        mrb[3:, :3] = m * s_g
        mrb[3:, 3:] = np.diag(self.inertia)
        return mrb

    def mass_matrix(self) -> np.ndarray:
        """(6, 6) M = M_RB + M_A."""
        return self.rigid_body_mass_matrix() + np.diag(self.added_mass)

    def thruster_configuration_matrix(self) -> np.ndarray:
        """(6, 5) B: body wrench [X, Y, Z, K, M, N] = B @ thrusts (columns [d; r x d])."""
        d = np.asarray(self.thruster_directions)
        r = np.asarray(self.thruster_positions)
        return np.vstack([d.T, np.cross(r, d).T])

    def allocation_matrix(self) -> np.ndarray:
        """(5, 4) minimum-norm pseudo-inverse of the [X, Y, Z, N] rows of B."""
        return np.linalg.pinv(self.thruster_configuration_matrix()[list(WRENCH_ROWS)])


def _skew(a) -> np.ndarray:
    return np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])


def _check_scalar(name, value, low, high, unit):
    try:
        ok = low <= float(value) <= high
    except (TypeError, ValueError):
        ok = False
    if not ok:
        raise ValueError(f"{name} must be a number in [{low:g}, {high:g}] {unit}, got {value!r}")


def _check_vector(name, value, size, low, high):
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        arr = None
    if arr is None or arr.shape != (size,) or not np.all((arr >= low) & (arr <= high)):
        raise ValueError(f"{name} must be {size} numbers in [{low:g}, {high:g}], got {value!r}")


def _get(tree, dotted: str, filename):
    node = tree
    for key in dotted.split("."):
        if not isinstance(node, dict) or key not in node:
            raise ValueError(f"{filename}: missing field '{dotted}'")
        node = node[key]
    return node


def load_girona500(filename=None) -> Girona500Params:
    """Reads a vehicle YAML file (default `models/girona500.yaml`) into FLU parameters.

    Raises FileNotFoundError for a missing file and ValueError naming the field for a
    malformed file, a missing field or a value out of its range.
    """
    filename = Path(filename) if filename is not None else DEFAULT_MODEL
    if not filename.is_file():
        raise FileNotFoundError(f"vehicle model file not found: {filename}")
    try:
        tree = yaml.safe_load(filename.read_text())
    except yaml.YAMLError as err:
        raise ValueError(f"{filename}: not valid YAML: {err}") from None
    if not isinstance(tree, dict):
        raise ValueError(f"{filename}: expected a mapping with 'rigid_body', 'hydrodynamics' "
                         f"and 'thrusters', got {type(tree).__name__}")
    frame = _get(tree, "frame", filename)
    if frame not in ("FRD", "FLU"):
        raise ValueError(f"{filename}: field 'frame' must be 'FRD' or 'FLU', got {frame!r}")
    # The one conversion of source coordinates to the body frame FLU.
    to_flu = FRD_TO_FLU if frame == "FRD" else np.eye(3)

    units = _get(tree, "thrusters.units", filename)
    if not isinstance(units, list) or len(units) != NUM_THRUSTERS:
        raise ValueError(f"{filename}: field 'thrusters.units' must list {NUM_THRUSTERS} "
                         f"thrusters {THRUSTER_NAMES}")
    names = tuple(u.get("name") if isinstance(u, dict) else None for u in units)
    if names != THRUSTER_NAMES:
        raise ValueError(f"{filename}: field 'thrusters.units' names must be {THRUSTER_NAMES} "
                         f"in that order, got {names}")
    positions, directions = [], []
    for i, unit in enumerate(units):
        for key, out in (("position", positions), ("direction", directions)):
            field_name = f"thrusters.units[{i}].{key}"
            value = unit.get(key)
            try:
                vec = np.asarray(value, dtype=float)
            except (TypeError, ValueError):
                vec = None
            if vec is None or vec.shape != (3,) or not np.all(np.isfinite(vec)):
                raise ValueError(f"{filename}: field '{field_name}' must be 3 finite numbers, "
                                 f"got {value!r}")
            out.append(tuple(to_flu @ vec))

    fields = {
        "mass": "rigid_body.mass", "inertia": "rigid_body.inertia",
        "gravity": "rigid_body.gravity", "buoyancy_ratio": "rigid_body.buoyancy_ratio",
        "added_mass": "hydrodynamics.added_mass",
        "linear_damping": "hydrodynamics.linear_damping",
        "quadratic_damping": "hydrodynamics.quadratic_damping",
        "max_thrust": "thrusters.max_thrust", "thruster_time_constant": "thrusters.time_constant",
    }
    errors_of = {**fields, "centre_of_gravity": "rigid_body.centre_of_gravity"}
    kwargs = {}
    for attr, dotted in fields.items():
        value = _get(tree, dotted, filename)
        kwargs[attr] = tuple(value) if isinstance(value, list) else value
    cg = _get(tree, "rigid_body.centre_of_gravity", filename)
    try:
        kwargs["centre_of_gravity"] = tuple(to_flu @ np.asarray(cg, dtype=float))
    except (TypeError, ValueError):
        raise ValueError(f"{filename}: field 'rigid_body.centre_of_gravity' must be 3 numbers, "
                         f"got {cg!r}") from None
    try:
        return Girona500Params(thruster_positions=tuple(positions),
                               thruster_directions=tuple(directions), **kwargs)
    except ValueError as err:
        attr = str(err).split(" ", 1)[0]
        raise ValueError(f"{filename}: field '{errors_of.get(attr, attr)}': {err}") from None


def allocate_thrust(allocation: np.ndarray, wrench, max_thrust: float) -> np.ndarray:
    """Thrusts (5,) for a desired [X, Y, Z, N] wrench, scaled as a whole to the thrust limit.

    `allocation` is `Girona500Params.allocation_matrix()`. When some thruster would exceed
    `max_thrust`, all thrusts are scaled by the same factor, so the wrench produced keeps the
    direction of the wrench asked for (only its magnitude shrinks).
    """
    thrust = allocation @ np.asarray(wrench, dtype=float)
    peak = np.max(np.abs(thrust))
    if peak > max_thrust:
        thrust *= max_thrust / peak
    return thrust


WATER_SIZE = 6  # the `water` signal: world-frame velocity (m/s) then acceleration (m/s^2)


class Girona500Model:
    """The 6-DOF Fossen model with thruster lag, integrated with fixed-step RK4.

    Matrices are precomputed once; `derivative` uses scalar math on the 17-vector
    [eta (6), nu (6), thrusts (5)] because numpy call overhead dominates at this size.
    """

    def __init__(self, params: Girona500Params | None = None):
        self.params = params if params is not None else Girona500Params()
        p = self.params
        self.M = p.mass_matrix()
        self.M_inv = np.linalg.inv(self.M)
        self.B = p.thruster_configuration_matrix()
        # The thrust term of nu_dot, M^-1 B f, with M^-1 B precomputed.
        self.M_inv_B = self.M_inv @ self.B
        self.d_lin = tuple(float(d) for d in p.linear_damping)
        self.d_quad = tuple(float(d) for d in p.quadratic_damping)
        self.added_mass = tuple(float(a) for a in p.added_mass[:3])  # translational M_A, kg
        self.displaced_mass = p.buoyancy / p.gravity  # rho V, kg (Froude-Krylov)
        self.r_g = tuple(float(c) for c in p.centre_of_gravity)
        self.net_up = p.buoyancy - p.weight  # N, along world +z
        self.weight = p.weight
        self.inv_tau = 1.0 / p.thruster_time_constant
        self.max_thrust = p.max_thrust

    def derivative(self, x: np.ndarray, thrust_command: np.ndarray,
                   water: np.ndarray | None = None) -> np.ndarray:
        """d/dt of the 17-vector state, given commanded thrusts (N, within the limit) and the
        `water` at the vehicle (6: world velocity, m/s, then acceleration, m/s^2; None: still).

        Scalar math on Python floats: at this size numpy's per-call overhead dominates.
        """
        _, _, _, roll, pitch, yaw, u, v, w, p, q, r = x[:12].tolist()
        cr, sr = math.cos(roll), math.sin(roll)
        cp, sp = math.cos(pitch), math.sin(pitch)
        cy, sy = math.cos(yaw), math.sin(yaw)
        # R_WB = Rz(yaw) Ry(pitch) Rx(roll); world position rate = R_WB v.
        r00, r01, r02 = cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr
        r10, r11, r12 = sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr
        r20, r21, r22 = -sp, cp * sr, cp * cr
        # Coriolis and centripetal terms, Fossen Thm 3.2 for the symmetric M = M_RB + M_A:
        # C(nu) nu = [w x h1; w x h2 + v x h1] with h = M nu = (h1, h2). In moving water the
        # added-mass part acts on nu_r instead: `water_terms` returns the difference.
        h0, h1, h2, h3, h4, h5 = (self.M @ x[6:12]).tolist()
        if water is None:
            ur, vr, wr = u, v, w
            e0 = e1 = e2 = e3 = e4 = e5 = 0.0
        else:
            ur, vr, wr, e0, e1, e2, e3, e4, e5 = self.water_terms(
                (r00, r01, r02, r10, r11, r12, r20, r21, r22), u, v, w, p, q, r, water)
        # Restoring: weight at the CG, buoyancy at the CB (the origin); world +z in body = row 2.
        W = self.weight
        gx, gy, gz = -W * r20, -W * r21, -W * r22
        xg, yg, zg = self.r_g
        nb = self.net_up
        dl, dq = self.d_lin, self.d_quad
        rhs = np.array([
            -(q * h2 - r * h1) + nb * r20 - (dl[0] + dq[0] * abs(ur)) * ur + e0,
            -(r * h0 - p * h2) + nb * r21 - (dl[1] + dq[1] * abs(vr)) * vr + e1,
            -(p * h1 - q * h0) + nb * r22 - (dl[2] + dq[2] * abs(wr)) * wr + e2,
            -(q * h5 - r * h4) - (v * h2 - w * h1) + yg * gz - zg * gy - (dl[3] + dq[3] * abs(p)) * p + e3,
            -(r * h3 - p * h5) - (w * h0 - u * h2) + zg * gx - xg * gz - (dl[4] + dq[4] * abs(q)) * q + e4,
            -(p * h4 - q * h3) - (u * h1 - v * h0) + xg * gy - yg * gx - (dl[5] + dq[5] * abs(r)) * r + e5,
        ])
        thrust = x[12:17]
        out = np.empty(17)
        out[0] = r00 * u + r01 * v + r02 * w
        out[1] = r10 * u + r11 * v + r12 * w
        out[2] = r20 * u + r21 * v + r22 * w
        # Euler-angle rates from body rates (singular at pitch = +/-90 deg, never reached by a
        # passively stable hovering vehicle).
        t = (q * sr + r * cr) / cp
        out[3] = p + t * sp
        out[4] = q * cr - r * sr
        out[5] = t
        out[6:12] = self.M_inv @ rhs + self.M_inv_B @ thrust
        out[12:17] = (thrust_command - thrust) * self.inv_tau
        return out

    def water_terms(self, rot, u, v, w, p, q, r, water):
        """(u_r, v_r, w_r, e_0 .. e_5): the velocity through the water (body, m/s) and what
        moving water adds to the right-hand side of M nu_dot = ... (N, N m), all in the body
        frame: M_A nu_c_dot + tau_FK - (C_A(nu_r) nu_r - C_A(nu) nu).

        With nu_c = [c; 0], c = R^T v_c, delta = M_A c and h_r = M_A (v - c) (M_A diagonal):
        C_A(nu_r) nu_r - C_A(nu) nu = [-(omega x delta); -(v x delta) - c x h_r], and
        nu_c_dot = [R^T a_c - omega x c; 0]. Every term is exactly 0.0 in still water.
        """
        r00, r01, r02, r10, r11, r12, r20, r21, r22 = rot
        vx, vy, vz, ax, ay, az = water.tolist() if isinstance(water, np.ndarray) else water
        c0 = r00 * vx + r10 * vy + r20 * vz  # R^T v_c
        c1 = r01 * vx + r11 * vy + r21 * vz
        c2 = r02 * vx + r12 * vy + r22 * vz
        a0 = r00 * ax + r10 * ay + r20 * az  # R^T a_c
        a1 = r01 * ax + r11 * ay + r21 * az
        a2 = r02 * ax + r12 * ay + r22 * az
        ur, vr, wr = u - c0, v - c1, w - c2
        m0, m1, m2 = self.added_mass
        d0, d1, d2 = m0 * c0, m1 * c1, m2 * c2
        k0, k1, k2 = m0 * ur, m1 * vr, m2 * wr
        rho_v = self.displaced_mass
        return (ur, vr, wr,
                (q * d2 - r * d1) + m0 * (a0 - (q * c2 - r * c1)) + rho_v * a0,
                (r * d0 - p * d2) + m1 * (a1 - (r * c0 - p * c2)) + rho_v * a1,
                (p * d1 - q * d0) + m2 * (a2 - (p * c1 - q * c0)) + rho_v * a2,
                (v * d2 - w * d1) + (c1 * k2 - c2 * k1),
                (w * d0 - u * d2) + (c2 * k0 - c0 * k2),
                (u * d1 - v * d0) + (c0 * k1 - c1 * k0))

    def step(self, x: np.ndarray, thrust_command: np.ndarray, dt: float,
             water: np.ndarray | None = None,
             previous_acceleration: np.ndarray | None = None) -> np.ndarray:
        """One classical RK4 step of length dt (s), the command (clipped to the thrust limit)
        held over the step.

        `water` (6: world velocity, m/s, and acceleration, m/s^2, at the step's start; None:
        still water). Within the step the water's acceleration is extrapolated linearly from
        `previous_acceleration` (3, the previous step's, m/s^2; None: held constant) and its
        velocity follows it. Holding it constant would integrate it by the rectangle rule,
        whose error a_c(0) dt / 2 stays as a velocity offset the vehicle then drifts with (a
        wave of 0.4 m/s orbital velocity and 8 s period: 8 mm/s); extrapolated, the integral
        is a trapezoid's, second order, and the offset is gone.
        """
        cmd = np.clip(thrust_command, -self.max_thrust, self.max_thrust)
        if water is None:
            w1 = w2 = w4 = None
        else:
            vx, vy, vz, ax, ay, az = np.asarray(water, dtype=float).tolist()
            jx = jy = jz = 0.0  # the water's jerk, m/s^3
            if previous_acceleration is not None:
                px, py, pz = np.asarray(previous_acceleration, dtype=float).tolist()
                jx, jy, jz = (ax - px) / dt, (ay - py) / dt, (az - pz) / dt
            h = 0.5 * dt
            w1 = (vx, vy, vz, ax, ay, az)
            w2 = (vx + (ax + 0.5 * h * jx) * h, vy + (ay + 0.5 * h * jy) * h,
                  vz + (az + 0.5 * h * jz) * h, ax + jx * h, ay + jy * h, az + jz * h)
            w4 = (vx + (ax + 0.5 * dt * jx) * dt, vy + (ay + 0.5 * dt * jy) * dt,
                  vz + (az + 0.5 * dt * jz) * dt, ax + jx * dt, ay + jy * dt, az + jz * dt)
        k1 = self.derivative(x, cmd, w1)
        k2 = self.derivative(x + (0.5 * dt) * k1, cmd, w2)
        k3 = self.derivative(x + (0.5 * dt) * k2, cmd, w2)
        k4 = self.derivative(x + dt * k3, cmd, w4)
        return x + (dt / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
