"""The builder and port tables of docs/architecture.md, generated from the code.

`port_rows()` builds the boulder mission's Diagram with every fault spliced in and a live
scene and an MCAP log (so the fault gates, the viewers and the recorder are there too), adds
the systems only a fly step brings (the DVL and the autopilot pilot), the one an explore step
brings (the view planner) and a hover step's (the station keeper), and walks every drake_auv
system's ports: its name,
direction and type (a vector's size, an abstract port's value class). The meaning of each port
is the doc's own column, kept by (system, direction, port); a port without a row gets an empty
meaning, so the table the code gives differs from the committed one until its row is written.
`builder_rows()` lists the builder functions with their parameters and their docstrings'
first sentence.

    python scripts/port_table.py          # rewrites both tables in docs/architecture.md
    python scripts/port_table.py --check  # exits 1 when the doc's tables are not the code's
"""

from __future__ import annotations

import inspect
import re
import sys
import tempfile
from pathlib import Path

DOC = Path(__file__).resolve().parents[1] / "docs" / "architecture.md"
PORTS, BUILDERS = "ports", "builders"
FAULTS = ("faults.thruster_failure.start_s=100", "faults.navigation_jump.time_s=100",
          "faults.sonar_silent.start_s=100")
PORT_HEADER = ("| system | in the mission Diagram | direction | port | type | meaning |\n"
               "| --- | --- | --- | --- | --- | --- |")
BUILDER_HEADER = "| builder | parameters | what it adds |\n| --- | --- | --- |"


def _block(text: str, name: str) -> re.Match:
    found = re.search(rf"<!-- {name}:begin -->\n(.*?)<!-- {name}:end -->", text, re.S)
    if found is None:
        raise ValueError(f"{DOC.name}: no <!-- {name}:begin --> ... <!-- {name}:end --> block")
    return found


def _cells(line: str) -> list[str]:
    return [cell.strip() for cell in line.strip().strip("|").split("|")]


def meanings(text: str) -> dict[tuple[str, str, str], str]:
    """{(system, direction, port): meaning} from the doc's port table."""
    rows = _block(text, PORTS).group(1).splitlines()[2:]
    return {tuple(cells[i] for i in (0, 2, 3)): cells[5]
            for cells in map(_cells, rows) if len(cells) == 6}


def _systems():
    """[(class name, [names in the Diagram], system)] of every drake_auv system, in order, and
    the site's number of target faces (a per-face port's size)."""
    from drake_auv.autopilot.pilot import AutopilotPilot
    from drake_auv.exploration.planner import ExploreParameters
    from drake_auv.exploration.view_planner import ViewPlanner
    from drake_auv.mission.config import load_mission
    from drake_auv.mission.diagram import build_mission_diagram
    from drake_auv.mission.plan import plan_mission
    from drake_auv.mission.site import load_site
    from drake_auv.mission.steps.hover import station_keeper
    from drake_auv.rosio.writer import McapLog
    from drake_auv.sonar.altimeter import DvlAltimeter
    from drake_auv.visualization import Scene

    spec = load_mission("boulder", overrides=FAULTS)
    site = load_site(spec.site, spec.seed, label=spec.name)
    with tempfile.TemporaryDirectory() as folder:  # the MCAP recorder of `run --mcap` too
        log = McapLog(Path(folder) / "dive.mcap")
        diagram, handles = build_mission_diagram(site, spec, plan_mission(spec, site),
                                                 scene=Scene(live=True), mcap=log)
        log.close()
    found: dict[str, tuple[list[str], object]] = {}
    for name, system in [*((s.get_name(), s) for s in diagram.GetSystems()),
                         ("dvl (fly, explore steps)", DvlAltimeter(handles.caster)),
                         ("autopilot (fly steps)", AutopilotPilot({})),
                         ("view_planner (explore steps)", ViewPlanner(
                             {0: ExploreParameters(region=(0.0, 0.0, -2.0, 1.0, 1.0, -1.0))})),
                         ("station_keeper (hover steps)", station_keeper()({}))]:
        if type(system).__module__.startswith("drake_auv"):
            found.setdefault(type(system).__name__, ([], system))[0].append(name)
    return [(cls, names, system) for cls, (names, system) in found.items()], len(site.target_faces)


def _type(port, faces: int) -> str:
    from pydrake.systems.framework import PortDataType

    if port.get_data_type() == PortDataType.kVectorValued:
        return "T (target faces)" if port.size() == faces else str(port.size())
    return type(port.Allocate().get_value()).__name__


def port_rows(known: dict) -> list[str]:
    """The port table's rows, meanings from `known`."""
    rows = []
    systems, faces = _systems()
    for cls, names, system in systems:
        ports = [("in", system.get_input_port(i)) for i in range(system.num_input_ports())]
        ports += [("out", system.get_output_port(i)) for i in range(system.num_output_ports())]
        for direction, port in ports:
            key = (f"`{cls}`", direction, f"`{port.get_name()}`")
            rows.append(f"| {key[0]} | {', '.join(names)} | {direction} | {key[2]} | "
                        f"{_type(port, faces)} | {known.get(key, '')} |")
    return rows


def builder_rows() -> list[str]:
    from drake_auv.mission import diagram
    from drake_auv.rosio.recorder import add_mcap_recorder
    from drake_auv.vehicle.diagram import add_girona500
    from drake_auv.mission.live_view import add_mission_view

    rows = []
    for function in (add_girona500, diagram.add_faults, diagram.add_sonars,
                     diagram.add_behaviours, diagram.add_ocean,
                     diagram.add_coverage_recorders, diagram.add_visualizers, add_mission_view,
                     add_mcap_recorder,
                     diagram.build_mission_diagram):
        parameters = ", ".join(inspect.signature(function).parameters)
        summary = re.split(r"(?<=\.)\s", " ".join(inspect.getdoc(function).split()))[0]
        rows.append(f"| `{function.__module__}.{function.__name__}` | {parameters} | "
                    f"{summary.replace('|', '/')} |")
    return rows


def render(text: str) -> str:
    """`text` (the doc) with both tables regenerated from the code."""
    ports = "\n".join([PORT_HEADER, *port_rows(meanings(text))])
    builders = "\n".join([BUILDER_HEADER, *builder_rows()])
    for name, table in ((PORTS, ports), (BUILDERS, builders)):
        block = _block(text, name)
        text = text[:block.start(1)] + table + "\n" + text[block.end(1):]
    return text


if __name__ == "__main__":
    current = DOC.read_text()
    fresh = render(current)
    if "--check" in sys.argv[1:]:
        sys.exit(0 if fresh == current else f"{DOC} is not the code's: run {__file__}")
    DOC.write_text(fresh)
