"""`OctreeMapper`: builds the on-line octree map from the multibeam and profiler returns.

A thin adapter over `drake_auv.mapping.OctreeMap`. Where the octree lives: in one `OctreeMap`
object owned by the system (`mapper.octree_map`); the context's abstract state holds an
`OctreeMapHandle` to it (whose deepcopy shares the map) and the sequence numbers of the last
returns inserted. An OctoMap octree is a C++ object of megabytes that Drake would otherwise
deep-copy with every context copy and output evaluation; sharing it means every context of
one mapper sees the same map (call `octree_map.clear()` to start a new mission with the
same diagram, or build a new diagram).

Ports: inputs `multibeam_returns`, `profiler_returns` (abstract `SonarReturns`, either may be
left unconnected); output `map` (abstract `OctreeMapHandle`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.systems.framework import LeafSystem

from drake_auv.mapping.octree_map import OctreeMap, OctreeMapHandle
from drake_auv.sonar.returns import SonarReturns


@dataclass(frozen=True)
class _MapperState:
    handle: OctreeMapHandle
    multibeam_sequence: int = -1
    profiler_sequence: int = -1

    def __deepcopy__(self, memo):
        # Immutable (replaced, never mutated) and the map is shared anyway: Drake copies the
        # abstract state at every unrestricted update of the diagram, so copies are free.
        return self


class OctreeMapper(LeafSystem):
    """Inserts new sonar returns into the shared octree at `period`.

    Args:
        octree_map: the map to fill (default: a new `OctreeMap(resolution, beam_stride=...)`).
        resolution: voxel edge of the default map, m.
        period: insertion period, s, in [0.01, 10]; returns of an update that was already
            inserted (same `sequence`) are skipped, so a period shorter than the sensors' is
            harmless, a longer one drops the pings in between.
        multibeam_stride: insert every n-th multibeam beam (profiler beams are all inserted).
    """

    def __init__(self, octree_map: OctreeMap | None = None, resolution: float = 0.5,
                 period: float = 0.1, multibeam_stride: int = 2):
        super().__init__()
        if not (np.isfinite(period) and 0.01 <= period <= 10.0):
            raise ValueError(f"OctreeMapper period must be in [0.01, 10] s, got {period}")
        if int(multibeam_stride) != multibeam_stride or multibeam_stride < 1:
            raise ValueError(f"multibeam_stride must be an integer >= 1, got {multibeam_stride}")
        self.octree_map = octree_map if octree_map is not None else OctreeMap(resolution)
        self.period = float(period)
        self.multibeam_stride = int(multibeam_stride)
        self.multibeam_input = self.DeclareAbstractInputPort(
            "multibeam_returns", AbstractValue.Make(SonarReturns.empty(0.0)))
        self.profiler_input = self.DeclareAbstractInputPort(
            "profiler_returns", AbstractValue.Make(SonarReturns.empty(0.0)))
        self._state_index = self.DeclareAbstractState(
            AbstractValue.Make(_MapperState(OctreeMapHandle(self.octree_map))))
        self.DeclarePeriodicUnrestrictedUpdateEvent(self.period, 0.0, self._update_map)
        self.map_output = self.DeclareAbstractOutputPort(
            "map", lambda: AbstractValue.Make(OctreeMapHandle(self.octree_map)), self._calc_map,
            prerequisites_of_calc={self.abstract_state_ticket(self._state_index)})

    def _new_returns(self, port, context, last_sequence: int):
        if not port.HasValue(context):
            return None
        returns = port.Eval(context)
        if returns is None or returns.sequence == last_sequence or len(returns) == 0:
            return None
        return returns

    def _update_map(self, context, state):
        current = context.get_abstract_state(self._state_index).get_value()
        omap = current.handle.map
        mb_seq, pr_seq = current.multibeam_sequence, current.profiler_sequence
        mb = self._new_returns(self.multibeam_input, context, mb_seq)
        if mb is not None:
            s = self.multibeam_stride
            omap.insert_scan(mb.origin_nav, mb.directions_nav[::s], mb.ranges[::s],
                             mb.max_range)
            mb_seq = mb.sequence
        pr = self._new_returns(self.profiler_input, context, pr_seq)
        if pr is not None:
            omap.insert_returns(pr)
            pr_seq = pr.sequence
        if (mb_seq, pr_seq) != (current.multibeam_sequence, current.profiler_sequence):
            state.get_mutable_abstract_state(self._state_index).set_value(
                _MapperState(current.handle, mb_seq, pr_seq))

    def _calc_map(self, context, output):
        output.set_value(context.get_abstract_state(self._state_index).get_value().handle)
