"""The GIRONA 500 model without Drake: parameters, loader, thruster geometry, Fossen dynamics."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from drake_auv.vehicle.model import (DEFAULT_MODEL, WRENCH_ROWS, Girona500Model, Girona500Params,
                               allocate_thrust, load_girona500)

DT = 0.05


def simulate(model, x0, command, seconds, dt=DT):
    x = np.array(x0, dtype=float)
    if x.shape == (12,):
        x = np.concatenate([x, np.zeros(5)])
    for _ in range(int(round(seconds / dt))):
        x = model.step(x, np.asarray(command, dtype=float), dt)
    return x


def test_yaml_loads_and_converts_frd_to_flu():
    params = load_girona500()
    assert params == Girona500Params()  # the dataclass defaults are the file's values in FLU
    pos = np.array(params.thruster_positions)
    # Port surge thruster: FRD y = -0.259 (port) is FLU y = +0.259 (left).
    np.testing.assert_allclose(pos[0], [-0.330, 0.259, 0.021])
    # Heave thrusters sit 0.314 m above the CB (FRD z = -0.314).
    np.testing.assert_allclose(pos[2:4, 2], [0.314, 0.314])
    np.testing.assert_allclose(params.centre_of_gravity, [0.0, 0.0, -0.05])


def test_thruster_configuration_matrix_signs():
    B = Girona500Params().thruster_configuration_matrix()
    assert B.shape == (6, 5)
    # Port surge forward yaws to starboard (negative yaw in FLU), starboard surge the other way.
    assert B[5, 0] == pytest.approx(-0.259) and B[5, 1] == pytest.approx(0.259)
    # Bow heave thruster up pitches the nose up: negative pitch about FLU y.
    assert B[4, 2] == pytest.approx(-0.535) and B[4, 3] == pytest.approx(0.583)
    np.testing.assert_allclose(B[:3].sum(axis=1), [2.0, 1.0, 2.0])
    assert np.linalg.matrix_rank(B[list(WRENCH_ROWS)]) == 4


def test_mass_matrix_has_cg_coupling_and_added_mass():
    M = Girona500Params().mass_matrix()
    np.testing.assert_allclose(M, M.T)
    np.testing.assert_allclose(np.diag(M), [147, 147, 147, 8, 8, 8])
    # m * z_g with the CG 0.05 m below the CB: surge couples to pitch (UWSim's Mrb, FLU signs).
    assert M[0, 4] == pytest.approx(-98 * 0.05)
    assert np.all(np.linalg.eigvalsh(M) > 0)


def test_neutral_buoyancy_zero_thrust_stays_put():
    x0 = np.zeros(12)
    x0[:3] = [3.0, -2.0, -20.0]
    x0[5] = 0.7
    x = simulate(Girona500Model(), x0, np.zeros(5), 60.0)
    np.testing.assert_allclose(x[:12], x0, atol=1e-9)


def test_heavier_than_water_sinks():
    params = Girona500Params(buoyancy_ratio=0.99)
    x = simulate(Girona500Model(params), np.zeros(12), np.zeros(5), 30.0)
    # Terminal heave speed from net weight = quadratic damping: w = sqrt(0.01 W / 148).
    expected = math.sqrt(0.01 * params.weight / 148.0)
    assert x[8] == pytest.approx(-expected, rel=0.05)
    assert x[2] < -10 * expected


@pytest.mark.parametrize("thrust", [40.0, 150.0])
def test_terminal_surge_speed_matches_thrust_damping_balance(thrust):
    model = Girona500Model()
    x = simulate(model, np.zeros(12), [thrust, thrust, 0, 0, 0], 60.0)
    expected = math.sqrt(2 * thrust / 148.0)
    assert x[6] == pytest.approx(expected, rel=0.02)
    assert abs(x[7]) < 0.01 * expected and abs(x[11]) < 1e-6
    assert x[0] > 0.8 * expected * 60.0 - 20.0  # it actually travelled


def test_thrust_is_saturated_and_lagged():
    model = Girona500Model()
    x = np.zeros(17)
    tau = 0.2
    x = simulate(model, x, [1000.0, 0, 0, 0, 0], tau)
    # One time constant after a step to the (saturated) limit: 1 - 1/e of 153.8 N.
    assert x[12] == pytest.approx(153.8 * (1 - math.exp(-1)), rel=0.01)
    x = simulate(model, x, [1000.0, 0, 0, 0, 0], 5.0)
    assert x[12] == pytest.approx(153.8, rel=1e-3)


@pytest.mark.parametrize("axis", [3, 4])
def test_roll_and_pitch_disturbances_decay(axis):
    x0 = np.zeros(12)
    x0[axis] = 0.3
    model = Girona500Model()
    x = np.concatenate([x0, np.zeros(5)])
    peaks = []
    for _ in range(6):
        x = simulate(model, x, np.zeros(5), 5.0)
        peaks.append(abs(x[axis]))
    assert np.all(np.diff(peaks) < 0)
    assert peaks[-1] < 0.01 * 0.3  # restoring moment m g 0.05 against 130 N m s damping
    assert np.all(np.abs(x[6:12]) < 1e-3)


def test_rk4_step_converges():
    model = Girona500Model()
    x0 = np.zeros(12)
    x0[3] = 0.2
    command = [120.0, 60.0, 50.0, -30.0, 80.0]
    coarse = simulate(model, x0, command, 10.0, dt=0.05)
    fine = simulate(model, x0, command, 10.0, dt=0.005)
    np.testing.assert_allclose(coarse[:12], fine[:12], atol=2e-3)
    assert np.linalg.norm(fine[:3]) > 5.0


@settings(max_examples=50, deadline=None)
@given(st.lists(st.floats(-1.0, 1.0), min_size=4, max_size=4))
def test_allocation_reproduces_achievable_wrenches(direction):
    params = Girona500Params()
    B4 = params.thruster_configuration_matrix()[list(WRENCH_ROWS)]
    wrench = np.array(direction) * [100.0, 50.0, 100.0, 20.0]
    thrust = allocate_thrust(params.allocation_matrix(), wrench, params.max_thrust)
    assert np.all(np.abs(thrust) <= params.max_thrust + 1e-9)
    np.testing.assert_allclose(B4 @ thrust, wrench, atol=1e-9)


def test_allocation_saturates_in_the_same_direction():
    params = Girona500Params()
    B4 = params.thruster_configuration_matrix()[list(WRENCH_ROWS)]
    rng = np.random.default_rng(2)
    for _ in range(50):
        wrench = rng.normal(size=4) * [800.0, 400.0, 800.0, 200.0]
        thrust = allocate_thrust(params.allocation_matrix(), wrench, params.max_thrust)
        achieved = B4 @ thrust
        if np.max(np.abs(params.allocation_matrix() @ wrench)) <= params.max_thrust:
            continue
        assert np.max(np.abs(thrust)) == pytest.approx(params.max_thrust)
        cos = achieved @ wrench / (np.linalg.norm(achieved) * np.linalg.norm(wrench))
        assert cos == pytest.approx(1.0, abs=1e-12)
        assert np.linalg.norm(achieved) < np.linalg.norm(wrench)


def _write(tmp_path, text):
    f = tmp_path / "g500.yaml"
    f.write_text(text)
    return f


def test_missing_model_file(tmp_path):
    with pytest.raises(FileNotFoundError, match="nope.yaml"):
        load_girona500(tmp_path / "nope.yaml")


def test_malformed_yaml_names_the_file(tmp_path):
    f = _write(tmp_path, "rigid_body: [mass: 98\n  inertia: {")
    with pytest.raises(ValueError, match="not valid YAML"):
        load_girona500(f)


@pytest.mark.parametrize("old,new,field", [
    ("mass: 98.0", "mass: -98.0", "rigid_body.mass"),
    ("mass: 98.0", "mass: heavy", "rigid_body.mass"),
    ("buoyancy_ratio: 1.0", "buoyancy_ratio: 3.0", "rigid_body.buoyancy_ratio"),
    ("time_constant: 0.2", "time_constant: 0.0", "thrusters.time_constant"),
    ("max_thrust: 153.8", "max_thrust: .nan", "thrusters.max_thrust"),
    ("quadratic_damping: [148.0, 148.0, 148.0, 180.0, 180.0, 180.0]",
     "quadratic_damping: [148.0, -148.0, 148.0, 180.0, 180.0, 180.0]",
     "hydrodynamics.quadratic_damping"),
    ("inertia: [8.0, 8.0, 8.0]", "inertia: [8.0, 8.0]", "rigid_body.inertia"),
    ("position: [ 0.535,  0.000, -0.314]", "position: [0.535, 0.0]",
     r"thrusters.units\[2\].position"),
    ("name: sway", "name: lateral", "thrusters.units"),
    ("centre_of_gravity: [0.0, 0.0, 0.05]", "centre_of_gravity: [0.0, 0.0, 50.0]",
     "rigid_body.centre_of_gravity"),
    ("frame: FRD", "frame: NWU", "'frame'"),
    ("  mass: 98.0", "  weight: 98.0", "rigid_body.mass"),
])
def test_bad_field_is_named(tmp_path, old, new, field):
    text = DEFAULT_MODEL.read_text()
    assert old in text
    with pytest.raises(ValueError, match=field):
        load_girona500(_write(tmp_path, text.replace(old, new, 1)))
