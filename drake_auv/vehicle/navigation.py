"""Dead-reckoning navigation error model (DVL + compass), pure numpy.

The estimated state is the true state plus an error: a position drift that grows with the
distance travelled, as in DVL dead reckoning, and white measurement noise.

Per navigation update, with dp the true horizontal displacement since the last update and dm
the displacement the DVL measures:
    drift += (1 + scale_error) Rz(heading_bias) dm - dp + random_walk sqrt(|dm|) n,  n ~ N(0, I2)
While the seabed is within the DVL's range it tracks the bottom, dm = dp, and the drift is
((1 + scale_error) Rz(heading_bias) - I) dp: the systematic drift of a compass bias and a DVL
scale-factor error (linear in distance) and a random walk in distance (growing as
sqrt(distance)). Above its range it tracks the water: dm = dp - v_c dt, the displacement
through the water (v_c the water's horizontal velocity, dt the update period), so dead
reckoning misses what the unknown current carried the vehicle and the drift gains -v_c dt;
that part is also accumulated on its own (`current_drift`). The estimated yaw carries the
compass bias. White noise (position, depth, heading) is redrawn every update. Update n draws
from the run's `navigation` stream, child n (`drake_auv.random_streams`), so a run is
reproducible and its error state fits in a plain vector. All parameters zero (the default):
estimate == truth.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from drake_auv.params import param, validate
from drake_auv.random_streams import MAX_SEED, SEED_RANGE, generator
from drake_auv.signals import NavigationError, VehicleState, Water

ERROR_SIZE = NavigationError.size()  # the error vector kept by the Navigation system


@dataclass(frozen=True)
class NavigationParams:
    """Attributes (1-sigma where random; `key`: the field's name in a mission file):
        heading_bias: compass bias, rad, in [-pi/4, pi/4].
        scale_error: DVL scale-factor error (fraction), in [-0.5, 0.5].
        random_walk: drift random walk, m per sqrt(m travelled), in [0, 1].
        position_noise: horizontal white noise, m, in [0, 10].
        depth_noise: depth-sensor white noise, m, in [0, 10].
        heading_noise: compass white noise, rad, in [0, 1].
        period: navigation update period, s, in [0.01, 10].
        seed: the run's seed (its `navigation` stream, `drake_auv.random_streams`).
    """

    heading_bias: float = param(0.0, low=-math.pi / 4, high=math.pi / 4, unit="rad",
                                key="heading_bias_deg", scale=math.pi / 180, file_unit="deg")
    scale_error: float = param(0.0, low=-0.5, high=0.5, key="dvl_scale_error")
    random_walk: float = param(0.0, low=0.0, high=1.0, unit="m/sqrt(m)", key="random_walk")
    position_noise: float = param(0.0, low=0.0, high=10.0, unit="m")
    depth_noise: float = param(0.0, low=0.0, high=10.0, unit="m")
    heading_noise: float = param(0.0, low=0.0, high=1.0, unit="rad")
    period: float = param(0.1, low=0.01, high=10.0, unit="s")
    seed: int = param(0, low=0, high=MAX_SEED, integer=True, note=SEED_RANGE)

    def __post_init__(self):
        validate(self)

    @property
    def exact(self) -> bool:
        """True when every error source is zero (the estimate is the true state)."""
        return not any((self.heading_bias, self.scale_error, self.random_walk,
                        self.position_noise, self.depth_noise, self.heading_noise))


def update_error(params: NavigationParams, error: np.ndarray, true_state: np.ndarray,
                 water: np.ndarray | None = None, bottom_lock: bool = True) -> np.ndarray:
    """The error vector (`signals.NavigationError`) after one navigation update at
    `true_state` (`VehicleState`). `water` (`signals.Water`, world frame; None: still water)
    is the water at the vehicle; `bottom_lock` False: the DVL tracks the water."""
    error = NavigationError(np.array(error, dtype=float))
    state = VehicleState(true_state)
    x, y = state.x, state.y
    index = int(error.index)
    rng = generator(params.seed, "navigation", index)
    n = rng.standard_normal(6)
    if error.started:
        dx, dy = x - error.last_x, y - error.last_y
        mx, my = dx, dy  # what the DVL measures
        if not bottom_lock and water is not None:
            water = Water(water)
            carried_x, carried_y = water.vx * params.period, water.vy * params.period
            mx, my = dx - carried_x, dy - carried_y
            error.current_drift_x -= carried_x
            error.current_drift_y -= carried_y
        c, s = math.cos(params.heading_bias), math.sin(params.heading_bias)
        k = 1.0 + params.scale_error
        walk = params.random_walk * math.sqrt(math.hypot(mx, my))
        error.drift_x += k * (c * mx - s * my) - dx + walk * n[0]
        error.drift_y += k * (s * mx + c * my) - dy + walk * n[1]
    error.noise = n[2:6] * (params.position_noise, params.position_noise, params.depth_noise,
                            params.heading_noise)
    error.last_x, error.last_y, error.index, error.started = x, y, index + 1, 1.0
    error.water_tracking = 0.0 if bottom_lock else 1.0
    return error[:]


def estimate(params: NavigationParams, error: np.ndarray, true_state: np.ndarray) -> np.ndarray:
    """The estimated state (`VehicleState`): the true state with the position drift, noise and
    compass error (`NavigationError`)."""
    est, error = VehicleState(np.array(true_state, dtype=float)), NavigationError(error)
    est.x += error.drift_x + error.noise_x
    est.y += error.drift_y + error.noise_y
    est.z += error.noise_z
    est.yaw += params.heading_bias + error.noise_yaw
    return est[:]
