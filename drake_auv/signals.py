"""The layouts of the mission's vector signals: one named view per signal, read and written by
field name, never by a literal index.

A view wraps a vector (a port's value, a discrete-state group) or an (n, fields) table (a
`MissionResult`'s logs; a `VectorLog`'s `data().T`) whose columns it then names:
`Reference(result.log.reference).z` is the reference depth over time. Writing a field writes the
wrapped array. Spans of consecutive fields are named too
(`VehicleState(x).position`, an aliasing slice). The views behave as pydrake's `namedview`
(`get_fields()`, attribute access, `view[:]` the wrapped array) but import no pydrake, so the
pure modules that read signals (`mission.legs`, `mission.safety`, and `mission.plan` through
them) load without Drake.

`PORT_SIGNALS` tells which view a system's port carries (by the system's class and the
port's name); `signal_views` extends that along a Diagram's connections (a `PortSwitch` input
carries what its source sends, a log sink's `data` what it logs), and `annotate_graphviz`
writes the field names beside every vector port of the Diagram's Graphviz text.
"""

from __future__ import annotations

import re

import numpy as np


class NamedVector:
    """A view naming the entries of the last axis of the array it wraps; subclasses set
    `_fields`."""

    __slots__ = ("_obj",)
    _fields: tuple[str, ...] = ()

    def __init__(self, obj):
        """`obj`: the array to name (aliased); anything else (a list) is read as a new one."""
        self._obj = obj if isinstance(obj, np.ndarray) else np.asarray(obj, dtype=float)

    @classmethod
    def get_fields(cls) -> tuple[str, ...]:
        return cls._fields

    @classmethod
    def size(cls) -> int:
        return len(cls._fields)

    @classmethod
    def zeros(cls):
        """A view of a new zero vector."""
        return cls(np.zeros(len(cls._fields)))

    def __getitem__(self, item):
        return self._obj[item]

    def __setitem__(self, item, value):
        self._obj[item] = value

    def __len__(self) -> int:
        return len(self._fields)

    def __repr__(self) -> str:
        values = ", ".join(f"{f}={self._obj[k]!r}" for k, f in enumerate(self._fields))
        return f"{type(self).__name__}({values})"


def _window(fields: tuple[str, ...], first: str, last: str) -> property:
    window = slice(fields.index(first), fields.index(last) + 1)

    def put(self, value):
        self._obj[..., window] = value

    return property(lambda self: self._obj[..., window], put,
                    doc=f"the fields {first} .. {last}")


def _field(k: int, name: str) -> property:
    def put(self, value):
        self._obj[..., k] = value

    # a vector's field reads as a scalar (as pydrake's namedview), a table's as its column
    return property(lambda self: self._obj[..., k][()], put, doc=f"field {name}")


def _signal(name: str, fields: tuple[str, ...], doc: str, **spans: tuple[str, str]):
    """A `NamedVector` of `fields` with the inclusive spans {span name: (first, last field)}
    as aliasing slice properties (read and assign)."""
    if len(set(fields)) != len(fields):
        raise ValueError(f"{name}: field names must be unique, got {fields}")
    members = {f: _field(k, f) for k, f in enumerate(fields)}
    members.update({k: _window(fields, *v) for k, v in spans.items()})
    return type(name, (NamedVector,), {"__doc__": doc, "__slots__": (), "_fields": fields,
                                       **members})


VehicleState = _signal(
    "VehicleState", ("x", "y", "z", "roll", "pitch", "yaw", "u", "v", "w", "p", "q", "r"),
    "Vehicle state (12): world position (m) and roll, pitch, yaw (rad); body-frame linear (m/s) "
    "and angular (rad/s) velocities.",
    position=("x", "z"), xy=("x", "y"), attitude=("roll", "yaw"), linear_velocity=("u", "w"),
    angular_velocity=("p", "r"))
Reference = _signal(
    "Reference", ("x", "y", "z", "yaw", "vx", "vy", "vz", "yaw_rate"),
    "The tracker's reference (8), world frame: position (m), yaw (rad), their rates (m/s, rad/s).",
    position=("x", "z"), pose=("x", "yaw"), velocity=("vx", "vz"), rates=("vx", "yaw_rate"))
LegSignal = _signal(
    "LegSignal", ("index", "start_s"),
    "The supervisor's `leg` (2): the leg flying and when it began (s).")
BehaviourStatus = _signal(
    "BehaviourStatus", ("leg", "finished", "progress"),
    "A behaviour's `status` (3, `drake_auv.behaviour`): the leg it last flew (-1 before any), "
    "finished (0/1), its own measure of progress (the behaviour's docstring names it).")
FlownLeg = _signal(
    "FlownLeg", ("leg", "end_s"),
    "`PathReference`'s `flown` group (2): the leg whose path it holds (-1 none yet) and when "
    "that path ends (s).")
ReplannerProgress = _signal(
    "ReplannerProgress", ("leg", "next_index", "steps", "finished"),
    "The replanner's `progress` group (4): leg flown (-1 none yet), next waypoint, steps of "
    "this leg, finished (0/1).")
ReplanningStep = _signal(
    "ReplanningStep", ("time", "wall_time", "query_time", "next_index", "planned", "iterations",
                       "map_voxels"),
    "`Replanner.step` (7): sim time of the last step (s), its wall time and its map query's "
    "(s), the next waypoint, whether a section was planned (0/1), STOMP's iterations and the "
    "occupied voxels the query gave (what the step's cost follows).")
ExplorerProgress = _signal(
    "ExplorerProgress", ("leg", "steps", "finished", "viewpoints", "no_gain_steps"),
    "The view planner's `progress` group (5): leg flown (-1 none yet), planning steps of this "
    "leg, finished (0/1), viewpoints chosen, steps without a worthwhile view (a turn counts "
    "half).")
ExplorerStep = _signal(
    "ExplorerStep", ("time", "wall_time", "gain_m2", "candidates", "frontier_cells",
                     "believed_coverage", "viewpoints"),
    "`ViewPlanner.step` (7): sim time of the last planning step (s), its wall time (s), the "
    "chosen view's gain (m^2), candidates scored, frontier cells, the share of the map's "
    "surface believed covered, viewpoints chosen.")
Profile = _signal(
    "Profile", ("distance", "normal_distance", "normal_a", "normal_b", "orientation", "valid",
                "mode"),
    "`ProfileFollowingController.profile` (7), in the scan plane's 2D axes: distances (m, NaN "
    "while no profile is seen), the normal, the orientation (rad), valid (0/1), mode "
    "(`following.controller.MODES`).", normal=("normal_a", "normal_b"))
Consumed = _signal(
    "Consumed", ("sequence", "leg"),
    "The controller's `consumed` group (2): the last returns' sequence, the leg they fed.")
Response = _signal(
    "Response", ("mode", "cause", "start_s", "x0", "y0", "z0", "yaw0", "x1", "y1", "z1"),
    "The supervisor's `response` (10): mode (`safety.RESPONSES`), cause (`safety.CAUSES`), "
    "start time (s), start pose (m, rad) and target (m).",
    start=("x0", "z0"), target=("x1", "z1"))
Watch = _signal(
    "Watch", ("tracking_since_s", "tracking_error0_m", "x", "y", "z", "drift_since_s",
              "drift_error0_m", "drift_x", "drift_y", "drift_z", "drift_windows"),
    "The supervisor's `watch` group (11): tracking error above threshold since (s, -1: not) "
    "and what it was then (m), previous estimated position "
    "(m), the drift window's start (s) and tracking error then (m), the motion the reference "
    "did not command since then (world, m) and how many windows in a row drifted.",
    position=("x", "z"), drift=("drift_x", "drift_z"))
DvlMeasurement = _signal(
    "DvlMeasurement", ("altitude", "count"),
    "The DVL altimeter's `measurement` group (2): the last altitude (m, NaN without bottom "
    "lock) and the measurements made so far.")
DvlBeams = _signal(
    "DvlBeams", ("time", "range_0", "range_1", "range_2", "range_3"),
    "The DVL altimeter's `beams` group (5): the last measurement's time (s) and its four "
    "slant ranges (m, NaN: no echo or no measurement).", ranges=("range_0", "range_3"))
LegProgress = _signal(
    "LegProgress", ("bearing", "turned", "start_x", "start_y"),
    "A leg's progress record (4): last bearing from the loops' centre and the angle turned "
    "(rad), where the leg began (m).", start=("start_x", "start_y"))
NavigationError = _signal(
    "NavigationError", ("drift_x", "drift_y", "noise_x", "noise_y", "noise_z", "noise_yaw",
                        "last_x", "last_y", "index", "started", "current_drift_x",
                        "current_drift_y", "water_tracking"),
    "The `Navigation` system's error state (13): the dead-reckoning drift (m), this update's "
    "white noise (m, rad), the true position at the last update (m), the update index, "
    "whether an update has happened (0/1), the part of the drift the current caused while the "
    "DVL tracked the water (m), whether the last update tracked the water (1) or the bottom "
    "(0).",
    drift=("drift_x", "drift_y"), noise=("noise_x", "noise_yaw"), last=("last_x", "last_y"),
    current_drift=("current_drift_x", "current_drift_y"))
Water = _signal(
    "Water", ("vx", "vy", "vz", "ax", "ay", "az"),
    "The water at the vehicle (6), world frame (x east, y north, z up): velocity (m/s), then "
    "acceleration (m/s^2).", velocity=("vx", "vz"), acceleration=("ax", "az"))
Wrench = _signal(
    "Wrench", ("X", "Y", "Z", "N"),
    "The tracker's body-frame wrench (4): forces along x, y, z (N) and the moment about z (N m).")
THRUSTER_NAMES = ("surge_port", "surge_starboard", "heave_bow", "heave_stern", "sway")
Thrust = _signal(
    "Thrust", THRUSTER_NAMES,
    "The five thrusts (N), in the order of `THRUSTER_NAMES`.")

_STATE_PORTS = ("state", "estimated_state", "true_state", "estimated_in")
# (system class, port name) or port name -> view; the class entry wins. Not named: arrays of
# one kind of value (a coverage recorder's `face_angles`, one per target face).
PORT_SIGNALS = {
    **{name: VehicleState for name in _STATE_PORTS},
    "reference": Reference, "response_reference": Reference, "leg": LegSignal,
    "response": Response, "profile": Profile, "step": ReplanningStep, "wrench": Wrench,
    "thrust": Thrust, "thrust_command": Thrust, "thrust_saturation": Thrust, "water": Water,
    "status": BehaviourStatus,
    ("ViewPlanner", "step"): ExplorerStep,
}


def port_signal(port):
    """The view a system's vector `port` carries by its own declaration, or None (abstract
    ports have size 0, so they never match)."""
    name = port.get_name()
    view = PORT_SIGNALS.get((type(port.get_system()).__name__, name), PORT_SIGNALS.get(name))
    if view is None and name.endswith("_status"):  # the supervisor's input of a behaviour's
        view = BehaviourStatus
    return view if view is not None and view.size() == port.size() else None


def _ports(system, kind: str):
    count = system.num_input_ports() if kind == "u" else system.num_output_ports()
    get = system.get_input_port if kind == "u" else system.get_output_port
    return [get(k) for k in range(count)]


def signal_views(diagram) -> dict:
    """{(system name, "u" or "y", port index): view} for every vector port of `diagram`'s
    systems whose signal is known: declared (`port_signal`) or carried over a connection from
    the port at its other end."""
    views = {}
    for system in diagram.GetSystems():
        for kind in "uy":
            for port in _ports(system, kind):
                view = port_signal(port)
                if view is not None:
                    views[(system.get_name(), kind, int(port.get_index()))] = view
    links = [((sink.get_name(), "u", int(i)), (source.get_name(), "y", int(o)))
             for (sink, i), (source, o) in diagram.connection_map().items()]
    for system in diagram.GetSystems():  # a PortSwitch passes one of its inputs through
        if type(system).__name__ == "PortSwitch":
            out = (system.get_name(), "y", 0)
            links += [((system.get_name(), "u", k), out)
                      for k in range(system.num_input_ports())
                      if system.get_input_port(k).size() > 0]
    changed = True
    while changed:
        changed = False
        for a, b in links:
            for known, other in ((a, b), (b, a)):
                if known in views and other not in views:
                    views[other] = views[known]
                    changed = True
    return views


def annotate_graphviz(diagram, dot: str) -> str:
    """`dot` (`diagram.GetGraphvizString()`) with each vector port's label followed by its
    field names, e.g. `reference [x y z yaw vx vy vz yaw_rate]`."""
    nodes = {}
    for (system, kind, index), view in signal_views(diagram).items():
        nodes.setdefault(system, []).append((kind, index, " ".join(view.get_fields())))
    for system, ports in nodes.items():
        head = dot.find(f"name={system}\n")
        if head < 0:
            continue
        end = dot.find("</TABLE>", head)
        block = dot[head:end]
        for kind, index, fields in ports:
            block = re.sub(rf'(<TD PORT="{kind}{index}" [^>]*>)([^<]*)(</TD>)',
                           lambda m: f"{m[1]}{m[2]} [{fields}]{m[3]}", block, count=1)
        dot = dot[:head] + block + dot[end:]
    return dot
