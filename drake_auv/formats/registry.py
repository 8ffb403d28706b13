"""The `--export` formats: one table (`EXPORTS`), read by `drake-auv plan` (its names, help,
checks and report lines), by `outputs.write_outputs` (which writes them, in the table's order)
and by the mission fly step (`VEHICLE_FILES`: the formats a vehicle flies, by extension).

A new format is a module in this package with a `write_export` (the signature in
`drake_auv.formats`) and one `ExportFormat` line below.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path

from drake_auv.autopilot.items import VehicleMission
from drake_auv.formats import ExportOptions, cola2, geojson, qgc
from drake_auv.terrain.geo import GeoFrame


@dataclass(frozen=True)
class ExportFormat:
    """One `--export` format.

    Attributes:
        name: its `--export` name and its key in report.json's `exports`.
        file: the file it writes into the output folder (a split QGC mission: the first of
            mission_1.plan, ...); a vehicle file's extension names its format.
        help: what `--export`'s help says of it.
        stage: its label on the progress bar.
        write: `write_export(plan, geo, outdir, options, missions) -> Exported`.
        check: (`ExportOptions`) -> None, ValueError naming a bad option; None: none to check.
        warnings: (figures, the plan's parameters) -> the report's warning lines.
        note: (figures) -> a line for the report and the terminal, or None.
        read: for a file a vehicle flies, path -> `VehicleMission`; None: not a vehicle file.
        autopilot: whose semantics fly a vehicle file (`autopilot.items.AUTOPILOTS`).
    """

    name: str
    file: str
    help: str
    stage: str
    write: Callable
    check: Callable | None = None
    warnings: Callable | None = None
    note: Callable | None = None
    read: Callable | None = None
    autopilot: str | None = None


EXPORTS = {f.name: f for f in (
    ExportFormat("cola2", file="mission.xml", help="mission.xml", stage="mission.xml",
                 write=cola2.write_export, warnings=cola2.report_warnings,
                 read=cola2.read_cola2, autopilot="cola2"),
    ExportFormat("qgc", file="mission.plan", help="mission.plan", stage="mission.plan",
                 write=qgc.write_export, check=qgc.check_export, warnings=qgc.report_warnings,
                 note=qgc.report_note, read=qgc.read_qgc_plan, autopilot="ardusub"),
    ExportFormat("geojson", file="path.geojson", help="WGS 84: the route and the waypoints of "
                 "the vehicle files written with it", stage="GeoJSON", write=geojson.write_export),
)}
# The files a vehicle flies, by extension: ".xml" COLA2, ".plan" ArduSub.
VEHICLE_FILES = {Path(f.file).suffix: f for f in EXPORTS.values() if f.read is not None}


def parse_exports(text: str | None) -> tuple[str, ...]:
    """'cola2,qgc,geojson' -> ('cola2', 'qgc', 'geojson'); ValueError naming an unknown one."""
    if not text:
        return ()
    names = tuple(dict.fromkeys(t.strip().lower() for t in text.split(",") if t.strip()))
    bad = [n for n in names if n not in EXPORTS]
    if bad:
        raise ValueError(f"--export: unknown format {bad[0]!r}; choose from "
                         f"{', '.join(EXPORTS)} (comma-separated)")
    return names


def export_help() -> str:
    """`--export`'s help: each format's name and what it writes."""
    return ("comma-separated: " + ", ".join(f"{f.name} ({f.help})" for f in EXPORTS.values())
            + " (default: geojson when georeferenced)")


def check_exports(bathy, exports=None, origin_lonlat=None, options=ExportOptions()
                  ) -> tuple[tuple[str, ...], GeoFrame | None]:
    """The exports of `outputs.write_outputs` (None: "geojson" when `bathy` is georeferenced
    or `origin_lonlat` given) and the `GeoFrame` of the exports and figures (None for a grid
    with neither), every option checked (ValueError naming the first bad one). Cheap, so a
    command checks them before it plans."""
    georeferenced = bathy.crs is not None or origin_lonlat is not None
    if exports is None:
        exports = ("geojson",) if georeferenced else ()
    for name in exports:
        if name not in EXPORTS:
            raise ValueError(f"unknown export {name!r}; choose from {', '.join(EXPORTS)}")
    for name in exports:
        if EXPORTS[name].check is not None:
            EXPORTS[name].check(options)
    return tuple(exports), GeoFrame(bathy, origin_lonlat) if exports or georeferenced else None


def _exported(rep: dict) -> list[tuple[ExportFormat, dict]]:
    """Each export in `rep` (a `planning.report.report_dict`) and its figures, in the table's
    order."""
    exported = rep.get("exports", {})
    return [(f, exported[f.name]) for f in EXPORTS.values() if f.name in exported]


def export_warnings(rep: dict) -> list[str]:
    """One line per violation the exports' figures in `rep` record (each one's `warnings`)."""
    return [line for f, figures in _exported(rep) if f.warnings is not None
            for line in f.warnings(figures, rep["parameters"])]


def export_notes(rep: dict) -> list[str]:
    """The exports' lines for the report and the terminal (each one's `note`): the
    QGroundControl files' upload order when the mission is split."""
    notes = [f.note(figures) for f, figures in _exported(rep) if f.note is not None]
    return [note for note in notes if note is not None]


def read_vehicle_mission(path, heave_in_3d: bool = False) -> VehicleMission:
    """The mission in `path`, read by the format its extension names (`VEHICLE_FILES`).
    `heave_in_3d`: the COLA2 vehicle's heave_in_3D setting (the file does not hold it).
    Raises ValueError (one line, naming the file) for a file that does not parse."""
    path = Path(path)
    fmt = VEHICLE_FILES.get(path.suffix.lower())
    if fmt is None:
        raise ValueError(f"{path.name}: unknown mission format {path.suffix!r}; choose from "
                         f"{', '.join(VEHICLE_FILES)}")
    mission = fmt.read(path)
    return replace(mission, heave_in_3d=True) if heave_in_3d else mission
