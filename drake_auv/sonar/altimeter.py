"""`DvlAltimeter`: the altitude over the seabed as the vehicle's DVL measures it.

A Doppler velocity log (the GIRONA 500's Teledyne RDI Explorer class) sends four beams in a
Janus configuration, `beam_deg` from the body's -z axis, at 45, 135, 225 and 315 deg about it.
Each beam's first hit on the true world gives a slant range; the DVL reports the altitude as
the mean of the beams' vertical ranges (slant range times the cosine of the beam's angle to the
world vertical, so roll and pitch are accounted for) and has bottom lock with at least
`min_beams` valid beams. Noise: each beam's range gets a Gaussian error of
`range_sigma_fraction` of the range plus `range_sigma_m`, and is lost with `dropout_prob`.
Without bottom lock the altitude is NaN. Measurement n draws from the run's `dvl` stream,
child n (`drake_auv.random_streams`). The altimeter is a `sonar.sensor.Sensor` (its mount: the
body frame; its beams are fixed in it).

This is what an autopilot holding altitude reads (COLA2 altitude mode, ArduSub's frame 10 via
its downward rangefinder); the true world reaches the mission only through this ray casting.

The four beams' ranges are also returns (`returns`, a `SonarReturns` placed with the
estimated state, as the multibeam's are): the octree mapper inserts them, so the seabed or a
structure's flat top under the vehicle is mapped where neither the side-looking multibeam nor
the horizontal profiler sees it (a beam grazing a flat top returns nothing to them).

Bottom lock is also what the navigation needs: with it the DVL measures the velocity over
ground; without it (the seabed beyond `max_range`, or too few beams) it tracks the water and
dead reckoning drifts with the current (`drake_auv.vehicle.navigation`).

Ports: inputs `true_state` (12), `estimated_state` (12); outputs `altitude` (1, m, NaN
without bottom lock), `bottom_lock` (1: 1 with bottom lock at the last measurement, else 0:
the `Navigation`'s input of the same name), `seabed_elevation` (1: the measured seabed under
the vehicle, `z_est - altitude`: the elevation in the navigation frame, NaN without lock) and
`returns` (`SonarReturns` of the four beams, navigation frame).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.systems.framework import BasicVector, LeafSystem

from drake_auv.geometry.raycast import RayCaster
from drake_auv.params import param, validate
from drake_auv.random_streams import generator, stream as random_stream
from drake_auv.signals import DvlBeams, DvlMeasurement, VehicleState
from drake_auv.sonar.beams import SonarMount
from drake_auv.sonar.returns import SonarReturns
from drake_auv.vehicle.control import rotation_world_body
from drake_auv.vehicle.model import STATE_SIZE


@dataclass(frozen=True)
class DvlParams:
    """A DVL's beams and errors (defaults: a 600 kHz RDI Explorer).

    Attributes:
        beam_deg: angle of each beam from the body's -z axis, deg, in [0, 60].
        max_range: bottom-track range, m, > 0 (the Explorer's 600 kHz: about 80 m; beyond
            it the DVL tracks the water).
        rate: measurements per second, in (0, 50].
        range_sigma_fraction, range_sigma_m: range noise, a fraction of the range and m, >= 0.
        dropout_prob: probability that a beam is lost, in [0, 1].
        min_beams: valid beams needed for bottom lock, in 1..4.
        blanking_m: a beam's range below this is no measurement (the transducer's ringing),
            m, >= 0 (a noisy range there could even be negative).
    """

    beam_deg: float = param(30.0, low=0.0, high=60.0, unit="deg")
    max_range: float = param(80.0, low=0.0, low_open=True, unit="m")
    rate: float = param(5.0, low=0.0, high=50.0, low_open=True, unit="Hz")
    range_sigma_fraction: float = param(0.01, low=0.0)
    range_sigma_m: float = param(0.02, low=0.0, unit="m")
    dropout_prob: float = param(0.02, low=0.0, high=1.0)
    min_beams: int = param(3, low=1, high=4, integer=True)
    blanking_m: float = param(0.5, low=0.0, unit="m")

    def __post_init__(self):
        validate(self)

    @functools.cached_property
    def beams_body(self) -> np.ndarray:
        """(4, 3) unit beam directions in the body frame (x forward, y left, z up), built
        once per parameter set (read at every measurement)."""
        b = np.radians(self.beam_deg)
        azimuth = np.radians([45.0, 135.0, 225.0, 315.0])
        return np.column_stack([np.sin(b) * np.cos(azimuth), np.sin(b) * np.sin(azimuth),
                                np.full(4, -np.cos(b))])


def beam_directions(params: DvlParams, state) -> np.ndarray:
    """(4, 3) unit beam directions in the world (or navigation) frame at `state` (12)."""
    state = VehicleState(np.asarray(state, dtype=float))
    return params.beams_body @ rotation_world_body(state.roll, state.pitch, state.yaw).T


def measure_ranges(caster: RayCaster, params: DvlParams, state: np.ndarray,
                   rng: np.random.Generator | None = None) -> np.ndarray:
    """(4,) the beams' slant ranges at the true `state` (12), m, NaN where a beam is lost,
    finds nothing within range or returns within the blanking distance. `rng` None: no
    noise."""
    ranges, _ = caster.cast_unit(VehicleState(np.asarray(state, dtype=float)).position,
                                 beam_directions(params, state), params.max_range)
    if rng is not None:
        sigma = params.range_sigma_fraction * np.nan_to_num(ranges) + params.range_sigma_m
        ranges = ranges + sigma * rng.standard_normal(4)
        ranges[rng.random(4) < params.dropout_prob] = np.nan
    ranges[ranges < params.blanking_m] = np.nan
    return ranges


def altitude_of(params: DvlParams, state, ranges) -> float:
    """The altitude the DVL reports from its beams' `ranges` (4,) at `state` (12), m: the
    mean vertical range of the valid beams, NaN without bottom lock."""
    vertical = np.asarray(ranges, float) * -beam_directions(params, state)[:, 2]
    valid = np.isfinite(vertical) & (vertical > 0)
    return float(vertical[valid].mean()) if valid.sum() >= params.min_beams else float("nan")


def measure_altitude(caster: RayCaster, params: DvlParams, state: np.ndarray,
                     rng: np.random.Generator | None = None) -> float:
    """The DVL's altitude at the true `state` (12), m; NaN without bottom lock. `rng` None:
    no noise."""
    return altitude_of(params, state, measure_ranges(caster, params, state, rng))


class DvlAltimeter(LeafSystem):
    """The DVL's altitude, measured at `params.rate` (see the module docstring).

    Args:
        world: the true world's `RayCaster`.
        params: the DVL (default `DvlParams()`); noise: False for a perfect DVL.
        seed: the run's seed, drawn through `stream` (`drake_auv.random_streams`).
        stream: the noise's random stream: a name of `drake_auv.random_streams.STREAMS` or
            (name, *keys).
    """

    def __init__(self, world: RayCaster, params: DvlParams | None = None, noise: bool = True,
                 seed: int = 0, stream: str | tuple = "dvl"):
        super().__init__()
        self.caster, self.params = world, params if params is not None else DvlParams()
        self.noise, self.seed = bool(noise), int(seed)
        self.stream = (stream,) if isinstance(stream, str) else tuple(stream)
        random_stream(self.seed, *self.stream)  # checks the seed and the stream
        self.true_state_input = self.DeclareVectorInputPort("true_state", STATE_SIZE)
        self.estimated_state_input = self.DeclareVectorInputPort("estimated_state", STATE_SIZE)
        measurement, beams = DvlMeasurement.zeros(), DvlBeams.zeros()
        measurement.altitude, beams.ranges = np.nan, np.nan
        self._measurement = self.DeclareDiscreteState(measurement[:])
        self._beams = self.DeclareDiscreteState(beams[:])
        self.DeclarePeriodicDiscreteUpdateEvent(1.0 / self.params.rate, 0.0,
                                                self._update_measurement)
        self.altitude_output = self.DeclareVectorOutputPort(
            "altitude", 1, self._calc_altitude,
            prerequisites_of_calc={self.discrete_state_ticket(self._measurement)})
        self.bottom_lock_output = self.DeclareVectorOutputPort(
            "bottom_lock", 1, self._calc_bottom_lock,
            prerequisites_of_calc={self.discrete_state_ticket(self._measurement)})
        self.seabed_output = self.DeclareVectorOutputPort(
            "seabed_elevation", 1, self._calc_seabed_elevation,
            prerequisites_of_calc={self.discrete_state_ticket(self._measurement),
                                   self.input_port_ticket(
                                       self.estimated_state_input.get_index())})
        self.returns_output = self.DeclareAbstractOutputPort(
            "returns", lambda: AbstractValue.Make(SonarReturns.empty(self.params.max_range)),
            self._calc_returns,
            prerequisites_of_calc={self.discrete_state_ticket(self._measurement),
                                   self.discrete_state_ticket(self._beams),
                                   self.input_port_ticket(
                                       self.estimated_state_input.get_index())})

    @property
    def mount(self) -> SonarMount:
        """The body frame (the beams are given in it)."""
        return SonarMount()

    @property
    def period(self) -> float:
        return 1.0 / self.params.rate

    @property
    def max_range(self) -> float:
        return self.params.max_range

    def _measurement_of(self, context) -> DvlMeasurement:
        return DvlMeasurement(context.get_discrete_state(self._measurement).get_value())

    def _update_measurement(self, context, discrete_state):
        n = int(self._measurement_of(context).count)
        rng = generator(self.seed, *self.stream, n) if self.noise else None
        true = self.true_state_input.Eval(context)
        measurement, beams = DvlMeasurement.zeros(), DvlBeams.zeros()
        beams.ranges = measure_ranges(self.caster, self.params, true, rng)
        measurement.altitude = altitude_of(self.params, true, beams.ranges)
        measurement.count, beams.time = n + 1, context.get_time()
        discrete_state.set_value(self._measurement, measurement[:])
        discrete_state.set_value(self._beams, beams[:])

    def _calc_altitude(self, context, output: BasicVector):
        output.SetAtIndex(0, self._measurement_of(context).altitude)

    def _calc_bottom_lock(self, context, output: BasicVector):
        output.SetAtIndex(0, float(np.isfinite(self._measurement_of(context).altitude)))

    def _calc_seabed_elevation(self, context, output: BasicVector):
        altitude = self._measurement_of(context).altitude
        output.SetAtIndex(0, VehicleState(self.estimated_state_input.Eval(context)).z - altitude)

    def _calc_returns(self, context, output):
        """The last measurement's beams at the estimated pose (empty before the first)."""
        n = int(self._measurement_of(context).count)
        if n == 0:
            output.set_value(SonarReturns.empty(self.params.max_range))
            return
        beams = DvlBeams(context.get_discrete_state(self._beams).get_value())
        ranges = np.array(beams.ranges)
        estimated = self.estimated_state_input.Eval(context)
        origin = VehicleState(estimated).position
        directions = beam_directions(self.params, estimated)
        output.set_value(SonarReturns(float(beams.time), origin, np.zeros(4), ranges,
                                      directions, origin + directions * ranges[:, None],
                                      self.params.beams_body * ranges[:, None],
                                      self.params.max_range, n))
