"""STOMP: Stochastic Trajectory Optimization for Motion Planning (Kalakrishnan et al. 2011).

A trajectory is N points in D dimensions (rows are timesteps) with its first point fixed and
its last one fixed or free (a goal set: the state cost prices where it ends); the other points
are optimised. Pure numpy; the cost is a callable so the
same optimiser serves any map. Checked against the description in REFERENCE-NOTES (ros-industrial
implementation): finite-difference acceleration matrix A (rows 1, -2, 1), R = A^T A, rollout
noise from N(0, R^-1), per-timestep probabilities with sensitivity h, update smoothed by
M = R^-1 with columns scaled to a maximum of 1/N.

Choices the paper leaves open (see docs/replanning.md):
- the noise covariance R^-1 is normalised to a maximum entry of 1, so `noise_std` is the largest
  per-point standard deviation in metres;
- the smoothness cost of a timestep is 0.5 * w * |acceleration|^2 of that timestep, with the
  fixed end points entering the differences, so a straight evenly spaced line costs 0;
- the trajectory with the lowest total cost seen is returned, so the result never costs more
  than the initial trajectory;
- a free end (`StompMatrices(N, free_end=True)`): the last point becomes a variable, the
  acceleration rows are the same (no acceleration at the end), and R = A^T A, singular along
  the straight-line swing of the trajectory about its start, gets a ridge mu I with mu the
  smallest eigenvalue of the fixed-end R, so that mode is sampled like the smoothest bend.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from drake_auv.params import param, validate


@dataclass(frozen=True)
class StompParameters:
    """Parameters of `stomp`.

    Attributes:
        num_rollouts: noisy rollouts per iteration, >= 2.
        max_iterations: iteration cap, >= 1.
        noise_std: largest standard deviation of the rollout noise of one point, m (> 0);
            a scalar or one value per dimension.
        h: sensitivity of the exponentiated cost, > 0 (10 in the paper).
        smoothness_weight: weight w of the smoothness cost 0.5 * w * sum |A theta|^2, >= 0.
        tolerance: relative improvement of the best cost below which an iteration counts as
            stalled, >= 0.
        patience: stalled iterations in a row that end the optimisation, >= 1.
    """

    num_rollouts: int = param(10, low=2, high=100, integer=True, key="rollouts")
    max_iterations: int = param(50, low=1, high=500, integer=True, key="iterations")
    noise_std: float | tuple = param(0.5, low=0.0, low_open=True, unit="m")
    h: float = param(10.0, low=0.0, low_open=True)
    smoothness_weight: float = param(1.0, low=0.0)
    tolerance: float = param(1e-4, low=0.0)
    patience: int = param(10, low=1, integer=True)

    def __post_init__(self):
        validate(self)


@dataclass(frozen=True)
class StompResult:
    """What `stomp` returns.

    Attributes:
        trajectory: (N, D) the lowest-cost trajectory found (fixed points equal to the
            input's).
        cost: its total cost (state costs plus smoothness).
        initial_cost: total cost of the initial trajectory.
        cost_history: (iterations + 1,) best total cost after each iteration, starting with
            the initial cost; never increases.
        iterations: iterations run.
    """

    trajectory: np.ndarray
    cost: float
    initial_cost: float
    cost_history: np.ndarray
    iterations: int


class StompMatrices:
    """The fixed matrices of STOMP for `num_points` trajectory points (ends included).

    Built once per trajectory length and reused: the variables are the points `variables`
    (1 .. N-2, or 1 .. N-1 with `free_end`); `A` ((N-2) x n) maps them to accelerations at the
    interior timesteps; `R = A^T A` (plus the free end's ridge, see the module); `noise_factor`
    is a Cholesky factor of R^-1 normalised to a maximum entry of 1; `smoothing` is STOMP's M
    (R^-1 with each column scaled so its largest entry is 1/num_points).
    """

    def __init__(self, num_points: int, free_end: bool = False):
        if int(num_points) != num_points or num_points < 3:
            raise ValueError(f"a STOMP trajectory needs num_points >= 3, got {num_points}")
        m = num_points - 2
        self.num_points, self.free_end = num_points, bool(free_end)
        interior = (np.diag(np.full(m, -2.0)) + np.diag(np.ones(m - 1), 1)
                    + np.diag(np.ones(m - 1), -1))
        if self.free_end:
            last = np.zeros((m, 1))
            last[-1] = 1.0
            self.A = np.hstack([interior, last])
            self.R = self.A.T @ self.A + np.linalg.eigvalsh(interior.T @ interior)[0] * np.eye(
                m + 1)
        else:
            self.A = interior
            self.R = self.A.T @ self.A
        self.variables = slice(1, num_points if self.free_end else num_points - 1)
        R_inv = np.linalg.inv(self.R)
        R_inv = 0.5 * (R_inv + R_inv.T)
        self.noise_factor = np.linalg.cholesky(R_inv / R_inv.max())
        self.smoothing = R_inv / (R_inv.max(axis=0, keepdims=True) * num_points)


def accelerations(trajectories: np.ndarray) -> np.ndarray:
    """(..., N, D) -> (..., N, D) second differences at the interior points, 0 at the ends."""
    acc = np.zeros_like(trajectories)
    acc[..., 1:-1, :] = trajectories[..., :-2, :] - 2.0 * trajectories[..., 1:-1, :] \
        + trajectories[..., 2:, :]
    return acc


def _interior_smoothness(trajectories: np.ndarray, weight: float) -> np.ndarray:
    """(..., N, D) -> (..., N - 2) `smoothness_costs` at the interior timesteps."""
    a = trajectories[..., :-2, :] - 2.0 * trajectories[..., 1:-1, :]
    a += trajectories[..., 2:, :]
    return 0.5 * weight * np.einsum("...d,...d->...", a, a)


def smoothness_costs(trajectories: np.ndarray, weight: float) -> np.ndarray:
    """(..., N, D) -> (..., N) per-timestep smoothness cost 0.5 * weight * |acceleration|^2."""
    out = np.zeros(trajectories.shape[:-1])
    out[..., 1:-1] = _interior_smoothness(trajectories, weight)
    return out


def stomp(initial: np.ndarray, state_cost: Callable[[np.ndarray], np.ndarray],
          params: StompParameters = StompParameters(),
          seed: int | np.random.SeedSequence = 0,
          matrices: StompMatrices | None = None, free_end: bool = False) -> StompResult:
    """Optimises `initial` (N, D) against `state_cost`, keeping its first point (and its last
    unless `free_end`).

    Args:
        initial: (N, D) initial trajectory, N >= 3, finite.
        state_cost: maps a batch of trajectories (K, N, D) to per-timestep costs (K, N), >= 0
            and finite, each trajectory's independent of the others in the batch; it is
            called once per iteration on all rollouts together (plus the trajectory the
            previous iteration produced, appended as row K), and once on the initial one.
        params: `StompParameters`.
        seed: seed of the rollout noise (an int or a `numpy.random.SeedSequence`); the same
            seed gives the same result.
        matrices: `StompMatrices(N, free_end)` to reuse across calls (built here when None).
        free_end: the last point is optimised too (its cost is the state cost's last column).
    """
    theta = np.array(initial, dtype=float)
    if theta.ndim != 2 or theta.shape[0] < 3:
        raise ValueError(f"initial trajectory must have shape (N >= 3, D), got {theta.shape}")
    if not np.all(np.isfinite(theta)):
        raise ValueError("initial trajectory must be finite (no NaN or inf)")
    num_points, dim = theta.shape
    if matrices is None:
        matrices = StompMatrices(num_points, free_end)
    elif matrices.num_points != num_points or matrices.free_end != bool(free_end):
        raise ValueError(f"matrices were built for {matrices.num_points} points "
                         f"(free_end={matrices.free_end}), the trajectory has {num_points} "
                         f"(free_end={bool(free_end)})")
    var = matrices.variables
    std = np.broadcast_to(np.asarray(params.noise_std, dtype=float), (dim,))
    rng = np.random.default_rng(seed)
    K, w = params.num_rollouts, params.smoothness_weight

    def costs_of(trajectories):
        costs = np.array(state_cost(trajectories), dtype=float)  # a copy: added to below
        if costs.shape != trajectories.shape[:2] or not np.isfinite(costs).all():
            raise ValueError(f"state_cost must return finite costs of shape (K, N) = "
                             f"{trajectories.shape[:2]}, got {costs.shape}")
        costs[:, 1:-1] += _interior_smoothness(trajectories, w)  # `smoothness_costs`' sum
        return costs

    def total_cost(traj):
        return float(costs_of(traj[None]).sum())

    best = theta.copy()
    best_cost = total_cost(theta)
    history = [best_cost]
    stalled = 0
    iterations = 0
    # The cost of the updated theta is evaluated with the next iteration's rollouts, in the
    # same call (one cost query per iteration instead of two; costs are per trajectory, so
    # the numbers are the ones a separate call would give).
    pending = False
    eps = np.zeros((K, num_points, dim))  # zero at the fixed points throughout
    batch = np.empty((K + 1, num_points, dim))  # the rollouts, then theta
    for iterations in range(1, params.max_iterations + 2):
        batch[K] = theta
        if iterations <= params.max_iterations:
            # Rollout noise eps[k] ~ N(0, R^-1) per dimension.
            z = rng.standard_normal((K, len(matrices.R), dim))
            np.multiply(matrices.noise_factor @ z, std, out=eps[:, var, :])
            np.add(theta, eps, out=batch[:K])
            batch_costs = costs_of(batch if pending else batch[:K])
        else:
            batch_costs = costs_of(batch[K:])
        if pending:  # the previous iteration's update, judged
            cost = float(batch_costs[-1].sum())
            if cost < best_cost:
                improved = (best_cost - cost) > params.tolerance * max(abs(best_cost), 1e-12)
                best, best_cost = theta.copy(), cost
                stalled = 0 if improved else stalled + 1
            else:
                stalled += 1
            history.append(best_cost)
            if stalled >= params.patience or iterations > params.max_iterations:
                iterations -= 1
                break
        costs = batch_costs[:K]  # (K, N)
        lo = costs.min(axis=0)
        spread = costs.max(axis=0) - lo
        spread[spread <= 0] = 1.0
        prob = np.exp(-params.h * (costs - lo) / spread)
        prob /= prob.sum(axis=0, keepdims=True)
        dtheta = np.einsum("ki,kid->id", prob, eps)[var]
        theta[var] += matrices.smoothing @ dtheta
        pending = True
    return StompResult(best, best_cost, history[0], np.array(history), iterations)
