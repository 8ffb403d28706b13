"""Live inspection of a mission in Meshcat: the leg flying, the replanner's section, the reference.

`MissionView` draws, every `period` s, what the supervisor and the replanner decide while a
mission flies, for a browser watching the served scene (`drake-auv run MISSION --meshcat`):
- `leg`: the current leg's goal, from the supervisor's `leg` output and the mission's legs
  (an "arrive" leg's target as a sphere joined to the vehicle, a "loops" leg's centre as a
  vertical line, a "distance" leg's run as a line from the vehicle along its direction), and a
  label in Meshcat's control panel ("leg 4 of 4: survey, replan until replanner"), drawn
  when the leg begins;
- `section`: the replanner's last optimised section (its `section` output), a polyline in the
  navigation frame;
- `reference`: a small sphere at the reference the tracker follows;
- the mission clock: a slider of Meshcat's control panel ("mission clock (s)") the view moves
  to the simulated time at every publish (dragging it changes nothing);
- the legend of these markers (`Scene.add_legend`: read-only entries of the control panel).
It only publishes (no state, no computed output), so a mission flies the same with it or
without it as long as its period falls on event times the mission already has (1 s does: the
supervisor judges every 0.5 s and the logs sample every 0.1 s).
"""

from __future__ import annotations

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.geometry import Cylinder, Rgba, Sphere
from pydrake.math import RigidTransform
from pydrake.systems.framework import LeafSystem

from drake_auv.behaviour import LEG_SIZE, read_leg
from drake_auv.mission.legs import Leg
from drake_auv.signals import Reference, VehicleState
from drake_auv.visualization.legend import LegendEntry, css_colour

LABEL_PREFIX = "leg "  # the control-panel label's name starts with it
CLOCK = "mission clock (s)"  # the control-panel slider showing the simulated time
LEG_RGBA = Rgba(1.0, 0.1, 0.8, 1.0)
SECTION_RGBA = Rgba(0.1, 1.0, 0.3, 1.0)
REFERENCE_RGBA = Rgba(1.0, 1.0, 0.2, 1.0)


def leg_label(legs: tuple[Leg, ...], index: int, start: float | None = None) -> str:
    """The label of leg `index` (begun at `start` s, when given: the control panel's)."""
    leg = legs[index]
    return (f"{LABEL_PREFIX}{index + 1} of {len(legs)}: {leg.phase}, {leg.behaviour} until "
            f"{leg.goal}" + ("" if start is None else f" (since {start:.0f} s)"))


def mission_view_legend(root: str) -> tuple[LegendEntry, ...]:
    """The legend's entries of what a `MissionView` under `root` draws."""
    leg, magenta = f"{root}/leg", css_colour(LEG_RGBA)
    return (LegendEntry("leg's target", "magenta sphere", "where an arrive leg goes (the line "
                        "joins the vehicle; a distance leg's run is a magenta line)", magenta,
                        leg),
            LegendEntry("loops' centre", "magenta bar", "the vertical axis a loops leg "
                        "circles", magenta, leg),
            LegendEntry("section", "green line", "the replanner's last optimised section",
                        css_colour(SECTION_RGBA), f"{root}/section"),
            LegendEntry("reference", "yellow sphere", "the point the tracker follows",
                        css_colour(REFERENCE_RGBA), f"{root}/reference"))


class MissionView(LeafSystem):
    """Draws the leg, the section and the reference under `root` in `meshcat` every `period` s.

    Ports (views in `drake_auv.signals`): inputs `leg` (`LegSignal`, the supervisor's),
    `estimated_state` (`VehicleState`), `reference` (`Reference`) and `section` (abstract
    (N, 3) array, m; may be left unconnected: no replanner). `duration`: the clock's end, s
    (default: the legs' budgets).
    """

    def __init__(self, meshcat, root: str, legs: tuple[Leg, ...], period: float = 1.0,
                 duration: float | None = None):
        super().__init__()
        if not (np.isfinite(period) and 0.05 <= period <= 60.0):
            raise ValueError(f"MissionView period must be in [0.05, 60] s, got {period}")
        if not legs:
            raise ValueError("MissionView needs the mission's legs (at least one)")
        self.meshcat, self.root, self.legs = meshcat, "/" + root.strip("/"), tuple(legs)
        self.leg_input = self.DeclareVectorInputPort("leg", LEG_SIZE)
        self.state_input = self.DeclareVectorInputPort("estimated_state", VehicleState.size())
        self.reference_input = self.DeclareVectorInputPort("reference", Reference.size())
        self.section_input = self.DeclareAbstractInputPort(
            "section", AbstractValue.Make(np.zeros((0, 3))))
        self.DeclarePeriodicPublishEvent(period, 0.0, self._publish)
        self.DeclareForcedPublishEvent(self._publish)
        meshcat.SetObject(f"{self.root}/reference", Sphere(0.3), REFERENCE_RGBA)
        if duration is None:
            duration = sum(leg.max_duration for leg in self.legs)
        if not (np.isfinite(duration) and duration > 0):
            raise ValueError(f"MissionView duration must be a finite time > 0 s, got {duration}")
        if CLOCK in meshcat.GetSliderNames():
            meshcat.DeleteSlider(CLOCK)
        meshcat.AddSlider(CLOCK, 0.0, float(np.ceil(duration)), 1.0, 0.0)

    def _publish(self, context):
        self.meshcat.SetSliderValue(CLOCK, context.get_time())
        index, start = read_leg(self.leg_input, context)
        self._draw_leg(index, start, VehicleState(self.state_input.Eval(context)).position)
        reference = Reference(self.reference_input.Eval(context))
        self.meshcat.SetTransform(f"{self.root}/reference", RigidTransform(reference.position))
        section = (self.section_input.Eval(context) if self.section_input.HasValue(context)
                   else np.zeros((0, 3)))
        if len(section) >= 2:
            self.meshcat.SetLine(f"{self.root}/section", np.asfortranarray(section.T), 4.0,
                                 SECTION_RGBA)

    def _draw_leg(self, index: int, start: float, position: np.ndarray) -> None:
        """When leg `index` has no label yet (it has just begun): its label, replacing the
        previous leg's, and its goal geometry, drawn from the vehicle's `position`."""
        label = leg_label(self.legs, index, start)
        names = self.meshcat.GetButtonNames()
        if label in names:
            return
        for name in names:
            if name.startswith(LABEL_PREFIX):
                self.meshcat.DeleteButton(name)
        self.meshcat.AddButton(label)
        leg, path = self.legs[index], f"{self.root}/leg"
        self.meshcat.Delete(path)
        if leg.target is not None:
            target = np.asarray(leg.target, dtype=float)
            self.meshcat.SetObject(f"{path}/target", Sphere(max(leg.tolerance, 0.3)), LEG_RGBA)
            self.meshcat.SetTransform(f"{path}/target", RigidTransform(target))
            self._line(f"{path}/line", position, target)
        elif leg.centre is not None:  # the loops' axis, through the vehicle's depth
            self.meshcat.SetObject(f"{path}/centre", Cylinder(0.15, 20.0), LEG_RGBA)
            self.meshcat.SetTransform(f"{path}/centre",
                                      RigidTransform([*leg.centre, position[2]]))
        elif leg.direction is not None:
            end = position + (leg.distance or 0.0) * np.array([*leg.direction, 0.0])
            self._line(f"{path}/line", position, end)

    def _line(self, path: str, a: np.ndarray, b: np.ndarray) -> None:
        self.meshcat.SetLine(path, np.asfortranarray(np.column_stack([a, b])), 3.0, LEG_RGBA)


def add_mission_view(builder, scene, legs: tuple[Leg, ...], leg_port, estimated_port,
                     reference_port, section_port=None, period: float = 1.0,
                     duration: float | None = None) -> MissionView:
    """Adds a `MissionView` drawing under `scene`'s `live` layer (its markers in the scene's
    legend), wired to the supervisor's `leg`, the estimated state, the tracked reference and
    (with a replanner) its `section`; `duration`: the clock's end, s."""
    view = builder.AddNamedSystem("mission_view", MissionView(
        scene.meshcat, scene.path_of("live"), legs, period, duration))
    for entry in mission_view_legend(view.root):
        if entry.name != "section" or section_port is not None:
            scene.add_legend(entry)
    builder.Connect(leg_port, view.leg_input)
    builder.Connect(estimated_port, view.state_input)
    builder.Connect(reference_port, view.reference_input)
    if section_port is not None:
        builder.Connect(section_port, view.section_input)
    return view
