"""The `Sensor` protocol: what the mission Diagram's builder, the octree mapper and the MCAP
recorder need of a ranging sensor, and the table of the sources that feed the map. Pure.

A sensor is a LeafSystem with vector inputs `true_state` and `estimated_state` (12 each: it
casts its beams against the true world and places them with the estimate) and an abstract
output `returns` (`SonarReturns`, navigation frame), updated every `period` s, seeing up to
`max_range` m, from its `mount` (its frame on the vehicle). `RangeSonar` (the multibeam and
the profiler) and the DVL altimeter satisfy it; a sensor of your own that does is built,
mapped and recorded as they are.

The sources of a dive's returns are named: `BUILT_IN` lists the built-in ones, and a mission's
table (`source_table`) appends its configured sensors after them, so the index a built-in
source has in a `ScanLog` or a point cloud never changes. Each sensor's noise draws from the
run's stream of its name (`stream_of`): a built-in sensor keeps its own entry of
`drake_auv.random_streams.STREAMS`, a configured one a child of the `sensors` stream keyed by
its name.
"""

from __future__ import annotations

import zlib
from typing import Protocol, runtime_checkable

from drake_auv.sonar.beams import SonarMount

# The built-in sources of returns, in the order of their index in a `ScanLog`.
BUILT_IN = ("multibeam", "profiler", "dvl")


@runtime_checkable
class Sensor(Protocol):
    """A ranging sensor the mission builds, maps and records (module doc). Its system name is
    the sensor's name (its topics, its `{name}_returns` ports downstream)."""

    true_state_input: object  # InputPort, 12: the true state, to cast against the world
    estimated_state_input: object  # InputPort, 12: the estimate that places the returns
    returns_output: object  # OutputPort of `SonarReturns` (navigation frame)

    @property
    def mount(self) -> SonarMount:
        """The sensor frame on the vehicle (body frame, m)."""

    @property
    def period(self) -> float:
        """Update period, s."""

    @property
    def max_range(self) -> float:
        """Range beyond which a beam returns nothing, m."""


def source_table(extra=()) -> tuple[str, ...]:
    """The source names of a `ScanLog`: `BUILT_IN`, then the `extra` names in their order."""
    clash = sorted(set(extra) & set(BUILT_IN))
    if clash or len(set(extra)) != len(tuple(extra)):
        raise ValueError(f"extra sensor names must be unique and not built-in "
                         f"({', '.join(BUILT_IN)}), got {list(extra)}")
    return (*BUILT_IN, *extra)


def stream_of(name: str) -> tuple:
    """The random stream (`random_streams.stream`'s name and keys) of sensor `name`."""
    return (name,) if name in BUILT_IN else ("sensors", zlib.crc32(name.encode()))
