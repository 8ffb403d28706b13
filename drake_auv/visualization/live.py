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
- `reference`: a small sphere at the reference the tracker follows.
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

LABEL_PREFIX = "leg "  # the control-panel label's name starts with it
LEG_RGBA = Rgba(1.0, 0.1, 0.8, 1.0)
SECTION_RGBA = Rgba(0.1, 1.0, 0.3, 1.0)
REFERENCE_RGBA = Rgba(1.0, 1.0, 0.2, 1.0)


def leg_label(legs: tuple[Leg, ...], index: int, start: float) -> str:
    """The control-panel label of leg `index` begun at `start` s."""
    leg = legs[index]
    return (f"{LABEL_PREFIX}{index + 1} of {len(legs)}: {leg.phase}, {leg.behaviour} until "
            f"{leg.goal} (since {start:.0f} s)")


class MissionView(LeafSystem):
    """Draws the leg, the section and the reference under `root` in `meshcat` every `period` s.

    Ports (views in `drake_auv.signals`): inputs `leg` (`LegSignal`, the supervisor's),
    `estimated_state` (`VehicleState`), `reference` (`Reference`) and `section` (abstract
    (N, 3) array, m; may be left unconnected: no replanner).
    """

    def __init__(self, meshcat, root: str, legs: tuple[Leg, ...], period: float = 1.0):
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

    def _publish(self, context):
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
                     reference_port, section_port=None, period: float = 1.0) -> MissionView:
    """Adds a `MissionView` drawing under `scene`'s `live` layer, wired to the supervisor's
    `leg`, the estimated state, the tracked reference and (with a replanner) its `section`."""
    view = builder.AddNamedSystem("mission_view", MissionView(
        scene.meshcat, scene.path_of("live"), legs, period))
    builder.Connect(leg_port, view.leg_input)
    builder.Connect(estimated_port, view.state_input)
    builder.Connect(reference_port, view.reference_input)
    if section_port is not None:
        builder.Connect(section_port, view.section_input)
    return view
