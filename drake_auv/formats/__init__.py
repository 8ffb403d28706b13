"""The files a vehicle or a GIS reads: COLA2 mission XML (`cola2`), QGroundControl plans for
ArduSub (`qgc`) and GeoJSON (`geojson`), each format's writer beside its reader, and the
`drake-auv plan` output folder (`outputs`). `registry.EXPORTS` is the one table of the
`--export` formats; the fly step reads vehicle files through it too.

Every export writer has one signature, `write_export(plan, geo, outdir, options, missions)`,
with the `ExportOptions` below and the `VehicleMission`s read back from the vehicle files
written before it, and returns what it wrote as `Exported`.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path


@dataclass(frozen=True)
class ExportOptions:
    """The `drake-auv plan` options the exports read.

    Attributes:
        surge_velocity: mission speed, m/s (> 0).
        tolerance_xy: waypoint arrival tolerance (COLA2) or acceptance radius (ArduSub), m.
        max_items: QGC mission items per file, home and DO_CHANGE_SPEED included (>= 4).
        ardusub_frames: "terrain" (frame 10 on lanes) or "depth" (frame 3 everywhere).
        heave_in_3d: the COLA2 vehicle interpolates depth along sections (its heave_in_3D).
    """

    surge_velocity: float = 0.5
    tolerance_xy: float = 1.0
    max_items: int = 700
    ardusub_frames: str = "terrain"
    heave_in_3d: bool = False


@dataclass(frozen=True)
class Exported:
    """What one export wrote.

    Attributes:
        files: the files, in order.
        figures: its entry of report.json's `exports` (None: it has none).
        missions: the vehicle missions read back from its files (`autopilot.items`).
    """

    files: list[Path]
    figures: dict | None = None
    missions: tuple = ()
