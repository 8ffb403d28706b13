"""Reading a vehicle mission file by its format: COLA2 mission XML or a QGroundControl plan.

The readers live beside their writers (`drake_auv.planning.cola2`, `drake_auv.planning.qgc`);
this picks one by the autopilot and returns the `VehicleMission`. Pure Python, no Drake.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

from drake_auv.autopilot.items import VehicleMission


def read_vehicle_mission(path, autopilot: str, heave_in_3d: bool = False) -> VehicleMission:
    """The mission in `path` for `autopilot` ("cola2": `.xml`, "ardusub": `.plan`).
    `heave_in_3d`: the COLA2 vehicle's heave_in_3D setting (the file does not hold it).
    Raises ValueError (one line, naming the file) for a file that does not parse."""
    path = Path(path)
    if autopilot == "cola2":
        from drake_auv.planning.cola2 import read_cola2

        return replace(read_cola2(path), heave_in_3d=bool(heave_in_3d))
    if autopilot == "ardusub":
        from drake_auv.planning.qgc import read_qgc_plan

        return read_qgc_plan(path)
    raise ValueError(f"{path.name}: no reader for autopilot {autopilot!r}; choose cola2 or "
                     "ardusub")
