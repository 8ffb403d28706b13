"""`RangeSonar`: the LeafSystem adapter shared by the profiler and the multibeam.

Inputs `true_state` (12, to cast against the true world) and `estimated_state` (12, to place
the returns in the navigation frame); output `returns` (`SonarReturns`, the abstract state
written by a periodic unrestricted update, so the beams are cast at the sensor's rate and not
at every integrator step). Update n (n = 0, 1, ...) fires at t = n * period; its noise draws
come from the sonar's stream of the run (`stream`, a name in `drake_auv.random_streams` or
(name, *keys): `sonar.sensor.stream_of`), child n, so the same seed gives the same returns.
A `RangeSonar` is a `sonar.sensor.Sensor`. With `axis_hits`, a second output
`axis_hits` (`AxisHits`, true world, for scoring only) holds the faces the beams' axes hit in
the same update, so a coverage recorder of the same beams need not cast them again.
"""

from __future__ import annotations

import numpy as np
import trimesh
from pydrake.common.value import AbstractValue
from pydrake.systems.framework import LeafSystem

from drake_auv.geometry.raycast import RayCaster
from drake_auv.random_streams import generator, stream as random_stream
from drake_auv.sonar.returns import SonarReturns
from drake_auv.sonar.beams import (AxisHits, BeamGeometry, SonarModel, beam_geometry,
                                   scan_with_hits)
from drake_auv.vehicle.model import STATE_SIZE


def as_caster(world) -> RayCaster:
    """A RayCaster for `world` (a trimesh, built here) or `world` itself if it is one."""
    if isinstance(world, RayCaster):
        return world
    if isinstance(world, trimesh.Trimesh):
        return RayCaster(world)
    raise ValueError(f"world must be a trimesh.Trimesh or a RayCaster, got {type(world).__name__}")


class RangeSonar(LeafSystem):
    """Base of the sonar systems; subclasses give the beam angles of each update."""

    def __init__(self, world, model: SonarModel, period: float, seed: int = 0,
                 axis_hits: bool = False, stream: str | tuple = "multibeam"):
        super().__init__()
        if not (np.isfinite(period) and period > 0):
            raise ValueError(f"sonar update period must be > 0 s, got {period}")
        self.caster = as_caster(world)
        self.model = model
        self.period = float(period)
        self.seed = int(seed)
        self.stream = (stream,) if isinstance(stream, str) else tuple(stream)
        random_stream(self.seed, *self.stream)  # checks the seed and the stream
        self.true_state_input = self.DeclareVectorInputPort("true_state", STATE_SIZE)
        self.estimated_state_input = self.DeclareVectorInputPort("estimated_state", STATE_SIZE)
        self._returns_index = self.DeclareAbstractState(
            AbstractValue.Make(SonarReturns.empty(model.max_range)))
        self.DeclarePeriodicUnrestrictedUpdateEvent(self.period, 0.0, self._update_returns)
        self.returns_output = self.DeclareStateOutputPort("returns", self._returns_index)
        self._hits_index = None
        if axis_hits:
            self._hits_index = self.DeclareAbstractState(
                AbstractValue.Make(AxisHits.empty(model.max_range)))
            self.axis_hits_output = self.DeclareStateOutputPort("axis_hits", self._hits_index)

    @property
    def mount(self):
        """The `SonarMount` of the sensor frame on the vehicle."""
        return self.model.mount

    @property
    def max_range(self) -> float:
        return self.model.max_range

    def update_angles(self, n: int) -> np.ndarray:
        """Beam angles (rad, scan plane) fired by update n."""
        raise NotImplementedError

    def update_geometry(self, n: int, model: SonarModel | None = None) -> BeamGeometry:
        """Body-frame beams of update n with `model` (default `self.model`; subclasses with
        fixed beams cache this)."""
        return beam_geometry(self.model if model is None else model, self.update_angles(n))

    def scan_model(self, context) -> SonarModel:
        """The sensor model of the update about to fire (subclasses may switch it)."""
        return self.model

    def _update_returns(self, context, state):
        n = context.get_abstract_state(self._returns_index).get_value().sequence
        model = self.scan_model(context)
        rng = generator(self.seed, *self.stream, n) if model.noise.enabled else None
        returns, hits = scan_with_hits(self.caster, model, None,
                                       self.true_state_input.Eval(context),
                                       self.estimated_state_input.Eval(context), rng=rng,
                                       time=context.get_time(), sequence=n + 1,
                                       geometry=self.update_geometry(n, model),
                                       axis_hits=self._hits_index is not None)
        state.get_mutable_abstract_state(self._returns_index).set_value(returns)
        if hits is not None:
            state.get_mutable_abstract_state(self._hits_index).set_value(hits)
