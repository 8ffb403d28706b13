"""STOMP on analytic costs, without Drake."""

import numpy as np
import pytest

from drake_auv.replanning.stomp import (StompMatrices, StompParameters, accelerations,
                                      smoothness_costs, stomp)

N = 20
LINE = np.linspace([0.0, 0.0, -5.0], [10.0, 0.0, -5.0], N)
CENTRE, RADIUS, CLEARANCE = np.array([5.0, 0.3, -5.0]), 2.0, 1.0


def free_field(trajectories):
    return np.zeros(trajectories.shape[:2])


def sphere_cost(trajectories):
    """Hinge penalty on the clearance to a sphere's surface below CLEARANCE."""
    d = np.linalg.norm(trajectories - CENTRE, axis=-1) - RADIUS
    return 100.0 * np.maximum(0.0, CLEARANCE + 0.3 - d) ** 2


def test_matrices():
    m = StompMatrices(N)
    assert np.allclose(m.R, m.A.T @ m.A)
    assert np.allclose(np.diag(m.A), -2.0) and np.allclose(np.diag(m.A, 1), 1.0)
    assert np.allclose(m.smoothing.max(axis=0), 1.0 / N)
    cov = m.noise_factor @ m.noise_factor.T
    assert np.allclose(cov, np.linalg.inv(m.R) / np.linalg.inv(m.R).max())


def test_free_end_matrices_sample_the_end_and_are_regular():
    m = StompMatrices(N, free_end=True)
    assert m.A.shape == (N - 2, N - 1) and m.variables == slice(1, N)
    assert np.all(np.linalg.eigvalsh(m.R) > 0)
    cov = m.noise_factor @ m.noise_factor.T
    assert cov[-1, -1] == pytest.approx(cov.max())  # the end moves most, the start not at all
    assert np.allclose(m.smoothing.max(axis=0), 1.0 / N)


def test_a_free_end_reaches_a_goal_set_a_fixed_end_cannot():
    # Terminal cost only: the end should lie on the plane y = 3 (a goal set, any x).
    def goal_plane(trajectories):
        cost = np.zeros(trajectories.shape[:2])
        cost[:, -1] = 10.0 * (trajectories[:, -1, 1] - 3.0) ** 2
        return cost

    params = StompParameters(max_iterations=100, noise_std=1.0, patience=30)
    free = stomp(LINE, goal_plane, params, seed=0, free_end=True)
    assert free.trajectory[-1, 1] == pytest.approx(3.0, abs=0.3)
    assert np.array_equal(free.trajectory[0], LINE[0])
    assert np.abs(accelerations(free.trajectory)).max() < 0.2  # it swings, smoothly
    fixed = stomp(LINE, goal_plane, params, seed=0)
    assert np.array_equal(fixed.trajectory[-1], LINE[-1])
    with pytest.raises(ValueError, match="free_end"):
        stomp(LINE, goal_plane, params, matrices=StompMatrices(N), free_end=True)


def test_free_field_keeps_the_straight_line():
    result = stomp(LINE, free_field, StompParameters(), seed=0)
    assert np.allclose(result.trajectory, LINE, atol=1e-9)
    assert result.cost == pytest.approx(0.0, abs=1e-12)


def test_free_field_straightens_a_bent_initial_trajectory():
    bent = LINE.copy()
    bent[1:-1, 1] += 2.0 * np.sin(np.linspace(0, np.pi, N))[1:-1]
    params = StompParameters(max_iterations=200, noise_std=0.3, patience=50)
    result = stomp(bent, free_field, params, seed=1)
    assert np.abs(result.trajectory[:, 1]).max() < 0.1 * np.abs(bent[:, 1]).max()
    assert result.cost < 0.05 * result.initial_cost
    assert np.array_equal(result.trajectory[[0, -1]], LINE[[0, -1]])


def test_around_a_sphere_keeps_the_clearance():
    params = StompParameters(max_iterations=100, noise_std=1.0)
    initial_clearance = (np.linalg.norm(LINE - CENTRE, axis=1) - RADIUS).min()
    assert initial_clearance < 0  # the straight line goes through the sphere
    for seed in range(5):
        result = stomp(LINE, sphere_cost, params, seed=seed)
        clearance = np.linalg.norm(result.trajectory - CENTRE, axis=1) - RADIUS
        assert clearance.min() > CLEARANCE, seed
        assert np.array_equal(result.trajectory[[0, -1]], LINE[[0, -1]])
        # The detour stays smooth: no acceleration larger than a gentle arc needs.
        assert np.abs(accelerations(result.trajectory)).max() < 0.5


def test_cost_never_increases_from_the_initial():
    params = StompParameters(max_iterations=60, noise_std=2.0, h=1.0)
    for seed in range(5):
        result = stomp(LINE, sphere_cost, params, seed=seed)
        assert result.cost_history[0] == pytest.approx(result.initial_cost)
        assert np.all(np.diff(result.cost_history) <= 0)
        total = sphere_cost(result.trajectory[None])[0].sum() \
            + smoothness_costs(result.trajectory, params.smoothness_weight).sum()
        assert result.cost == pytest.approx(total)
        assert result.cost <= result.initial_cost


def test_same_seed_same_result():
    params = StompParameters(max_iterations=30)
    a = stomp(LINE, sphere_cost, params, seed=7)
    b = stomp(LINE, sphere_cost, params, seed=7)
    c = stomp(LINE, sphere_cost, params, seed=8)
    assert np.array_equal(a.trajectory, b.trajectory)
    assert not np.array_equal(a.trajectory, c.trajectory)


def test_bad_input_raises():
    with pytest.raises(ValueError, match="num_rollouts"):
        StompParameters(num_rollouts=1)
    with pytest.raises(ValueError, match="noise_std"):
        StompParameters(noise_std=0.0)
    with pytest.raises(ValueError, match="StompParameters.h = nan is out of range"):
        StompParameters(h=np.nan)
    with pytest.raises(ValueError, match="N >= 3"):
        stomp(LINE[:2], free_field)
    bad = LINE.copy()
    bad[3, 0] = np.nan
    with pytest.raises(ValueError, match="finite"):
        stomp(bad, free_field)
    with pytest.raises(ValueError, match="state_cost"):
        stomp(LINE, lambda t: np.zeros(3))


def test_one_cost_call_per_iteration_and_the_reported_cost_is_the_trajectorys():
    centre, radius = np.array([5.0, 0.4]), 1.5
    calls = []

    def cost(trajectories):
        calls.append(trajectories.shape[0])
        d = np.linalg.norm(trajectories - centre, axis=-1)
        return 20.0 * np.maximum(0.0, radius - d) ** 2

    initial = np.linspace([0.0, 0.0], [10.0, 0.0], 21)
    params = StompParameters(num_rollouts=8, max_iterations=30, patience=5, noise_std=0.4)
    result = stomp(initial, cost, params, seed=4)
    # The initial trajectory, then one batch per iteration and one judging the last update.
    assert len(calls) == result.iterations + 2
    assert calls[0] == 1 and calls[1] == 8 and set(calls[2:-1]) == {9} and calls[-1] in (1, 9)
    # Costs judged inside a batch are the costs of the trajectory alone.
    alone = float((cost(result.trajectory[None])
                   + smoothness_costs(result.trajectory[None], params.smoothness_weight)).sum())
    assert result.cost == pytest.approx(alone, rel=1e-12, abs=1e-12)
    assert result.cost_history[-1] == result.cost < result.initial_cost
