"""`OctreeMapper`: the on-line octree map, built from the sonars' and the DVL's returns.

All of it lives in the Context. The state is the log of the returns received so far (a
`ScanLog`, immutable and persistent, so Drake's state copies are free and each Context's
history is its own; its beams stream to a temporary file, so memory does not grow with them),
written at `period` by an unrestricted update. The `map` output is the
octree of that log: an `OnlineMap` held in the output port's cache, which is per Context.
Evaluating it brings the octree up to the Context's log by inserting only the batches it has
not seen (OctoMap insertion is incremental), or rebuilds from the whole log when the log is
not its future (a state set by hand). Copying a Context rebuilds its octree from the log
(`OnlineMap.__deepcopy__`, reading the log back from its file). So two Contexts of one
diagram never share a map. A step's cost is the batches since the last one, never the log.

Ports: an input `{name}_returns` (`SonarReturns`) per source it is given (by default the
built-in `multibeam`, `profiler` and `dvl`; any may be left unconnected: the DVL's four beams
map what lies under the vehicle); outputs `map` (`OnlineMap`) and `scan_log` (`ScanLog`, the
recorded returns, whose `sources` are the mapper's, built-in ones first).
"""

from __future__ import annotations

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.systems.framework import LeafSystem

from drake_auv.mapping.octree_map import OctreeMap
from drake_auv.mapping.scan_log import ScanBatch, ScanLog
from drake_auv.sonar.returns import SonarReturns
from drake_auv.sonar.sensor import BUILT_IN, source_table


class OnlineMap:
    """The octree of a `ScanLog` up to `version` (None: nothing inserted yet).

    A cache value: its deep copy (a Context's copy) rebuilds the octree from the same log
    version, so the copy holds an equal map of its own, never a second owner of this one.
    """

    def __init__(self, resolution: float, no_return_clear_m: float = np.inf,
                 discretize: bool = False):
        self.map = OctreeMap(resolution, no_return_clear_m=no_return_clear_m,
                             discretize=discretize)
        self.version: ScanLog | None = None

    def __deepcopy__(self, memo):
        clone = OnlineMap(self.map.resolution, self.map.no_return_clear_m, self.map.discretize)
        if self.version is not None:
            clone.catch_up(self.version)
        return clone

    def catch_up(self, log: ScanLog) -> None:
        """Inserts the batches of `log` this map has not seen (all of them if its version is
        not in `log`'s past)."""
        if log is self.version:
            return
        new = log.since(self.version)
        if new is None:
            self.map.clear()
            new = log.iter_batches()
        for batch in new:
            self.map.insert_scan(batch.origin, batch.directions, batch.ranges, batch.max_range)
        self.version = log


def map_memory(online: OnlineMap, log: ScanLog) -> dict:
    """The report's `map` section: the octree's memory (`OctreeMap.memory`), the batches and
    returns of the log and the size of its file (MB, on disk, not in memory)."""
    store = log.store
    return dict(**online.map.memory(), batches=log.count, returns=log.returns,
                scan_file_mb=(store.nbytes if store is not None else 0) / 2**20)


class OctreeMapper(LeafSystem):
    """Records new sonar returns at `period` and serves the octree map of them.

    Args:
        resolution: voxel edge, m, in (0.01, 10].
        period: recording period, s, in [0.01, 10]; returns of an update already recorded
            (same `sequence`) are skipped, so a period shorter than the sensors' is harmless,
            a longer one drops the pings in between.
        multibeam_stride: record every n-th beam of the built-in multibeam (the profiler's and
            the DVL's are all kept).
        extra: {name: stride} the configured sensors' returns recorded besides the built-in
            ones (every stride-th beam), after them in the log's `sources`.
        no_return_clear_m: how far a beam without an echo clears free water in the map, m
            (`OctreeMap`; inf: to the sonar's range).
        discretize: OctoMap's discretised insertion, one ray per endpoint voxel (`OctreeMap`).
    """

    def __init__(self, resolution: float = 0.5, period: float = 0.1, multibeam_stride: int = 2,
                 no_return_clear_m: float = np.inf, discretize: bool = False,
                 extra: dict[str, int] | None = None):
        super().__init__()
        extra = dict(extra or {})
        if not (np.isfinite(period) and 0.01 <= period <= 10.0):
            raise ValueError(f"OctreeMapper period must be in [0.01, 10] s, got {period}")
        for name, stride in {"multibeam": multibeam_stride, **extra}.items():
            if int(stride) != stride or stride < 1:
                raise ValueError(f"{name}'s stride must be an integer >= 1, got {stride}")
        if not (np.isfinite(resolution) and 0.01 < resolution <= 10.0):
            raise ValueError(f"OctreeMapper resolution must be in (0.01, 10] m, got {resolution}")
        if not no_return_clear_m > 0:
            raise ValueError(f"OctreeMapper no_return_clear_m must be > 0 m (inf: the sonar's "
                             f"range), got {no_return_clear_m}")
        self.resolution = float(resolution)
        self.no_return_clear_m = float(no_return_clear_m)
        self.period = float(period)
        self.multibeam_stride = int(multibeam_stride)
        self.discretize = bool(discretize)
        self.sources = source_table(extra)
        # {source name: every how many beams are recorded}, in the order of `sources`
        self.strides = {**{name: 1 for name in BUILT_IN}, "multibeam": self.multibeam_stride,
                        **{name: int(stride) for name, stride in extra.items()}}
        model = AbstractValue.Make(SonarReturns.empty(20.0))
        self.returns_inputs = {name: self.DeclareAbstractInputPort(f"{name}_returns",
                                                                   model.Clone())
                               for name in self.sources}
        self._log_index = self.DeclareAbstractState(AbstractValue.Make(
            ScanLog(sources=self.sources)))
        # The `sequence` of the last batch recorded from each source, in `sources` order.
        self._sequences = self.DeclareDiscreteState(np.full(len(self.sources), -1.0))
        self.DeclarePeriodicUnrestrictedUpdateEvent(self.period, 0.0, self._update_log)
        self.map_output = self.DeclareAbstractOutputPort(
            "map", lambda: AbstractValue.Make(OnlineMap(self.resolution, self.no_return_clear_m,
                                                        self.discretize)),
            self._calc_map,
            prerequisites_of_calc={self.abstract_state_ticket(self._log_index)})
        self.scan_log_output = self.DeclareStateOutputPort("scan_log", self._log_index)

    def _update_log(self, context, state):
        log = context.get_abstract_state(self._log_index).get_value()
        sequences = context.get_discrete_state(self._sequences).get_value().copy()
        for k, (port, stride) in enumerate(zip(self.returns_inputs.values(),
                                               self.strides.values())):
            if not port.HasValue(context):
                continue
            returns = port.Eval(context)
            if returns.sequence == sequences[k] or len(returns) == 0:
                continue
            log = log.append(ScanBatch.make(returns.time, k, returns.origin_nav,
                                            returns.directions_nav[::stride],
                                            returns.ranges[::stride], returns.max_range))
            sequences[k] = returns.sequence
        state.get_mutable_abstract_state(self._log_index).set_value(log)
        state.get_mutable_discrete_state(self._sequences).set_value(sequences)

    def _calc_map(self, context, output):
        output.get_mutable_value().catch_up(
            context.get_abstract_state(self._log_index).get_value())

    def scan_log(self, context) -> ScanLog:
        """The returns recorded in this system's `context`."""
        return context.get_abstract_state(self._log_index).get_value()
