"""The current at the vehicle in Meshcat: an arrow along the world-frame water velocity.

`CurrentVisualizer` reads the `Ocean`'s `water` output (world frame, m/s) and the true state,
and every `period` s poses an arrow above the vehicle along the water velocity, `ARROW_M_PER_MPS`
metres long per m/s (the whole arrow scaled, so it keeps its proportions). Below `STILL_MPS`
the arrow is hidden. While the scene records, its pose, scale and visibility are keyframed, so
the recording animates the current as the dive meets it. A mission in still water (`ocean:
none`) has no `Ocean` and no arrow.
"""

from __future__ import annotations

import math

import numpy as np
from pydrake.geometry import Cylinder, MeshcatCone, Rgba
from pydrake.math import RigidTransform, RotationMatrix
from pydrake.systems.framework import LeafSystem

from drake_auv.signals import VehicleState, Water
from drake_auv.visualization.legend import LegendEntry, css_colour

ARROW_M_PER_MPS = 20.0  # arrow length per water speed, m per m/s
STILL_MPS = 0.005  # water slower than this: the arrow is hidden
ARROW_RGBA = Rgba(0.0, 0.85, 0.95, 1.0)
_LIFT_M = 1.0  # the arrow's tail above the vehicle's centre (clear of the hulls)
_SHAFT = (0.03, 0.75)  # radius and length of a unit arrow's shaft, m
_HEAD = (0.25, 0.08)  # length and radius of its head, m


class CurrentVisualizer(LeafSystem):
    """Inputs `state` (12, the true `VehicleState`) and `water` (6, `signals.Water`, world
    frame); draws the arrow at `scene`'s `current` layer every `period` s."""

    def __init__(self, scene, period: float = 0.5, metres_per_mps: float = ARROW_M_PER_MPS):
        super().__init__()
        if not (math.isfinite(period) and 1e-3 <= period <= 10.0):
            raise ValueError(f"current arrow period must be in [0.001, 10] s, got {period}")
        if not (math.isfinite(metres_per_mps) and 0.1 <= metres_per_mps <= 1000.0):
            raise ValueError(f"arrow scale must be in [0.1, 1000] m per m/s, got "
                             f"{metres_per_mps}")
        # the layer (a user's toggle) and, under it, the arrow its keyframes move and hide
        self.scene, self.path = scene, scene.path_of("current")
        self.arrow = f"{self.path}/arrow"
        self.metres_per_mps = float(metres_per_mps)
        self.state_input = self.DeclareVectorInputPort("state", VehicleState.size())
        self.water_input = self.DeclareVectorInputPort("water", Water.size())
        self.DeclarePeriodicPublishEvent(period, 0.0, self._publish_arrow)
        self.DeclareForcedPublishEvent(self._publish_arrow)
        self._draw_arrow()
        scene.add_legend(LegendEntry(
            "current", "cyan arrow",
            f"the water's velocity at the vehicle, {self.metres_per_mps:g} m per m/s",
            css_colour(ARROW_RGBA), self.path))

    def _draw_arrow(self) -> None:
        """A unit arrow along +z from the origin: shaft, then head with its point at z = 1."""
        meshcat = self.scene.meshcat
        radius, length = _SHAFT
        meshcat.SetObject(f"{self.arrow}/shaft", Cylinder(radius, length), ARROW_RGBA)
        meshcat.SetTransform(f"{self.arrow}/shaft", RigidTransform([0.0, 0.0, length / 2]))
        height, head = _HEAD
        meshcat.SetObject(f"{self.arrow}/head", MeshcatCone(height, head, head), ARROW_RGBA)
        meshcat.SetTransform(f"{self.arrow}/head",
                             RigidTransform(RotationMatrix.MakeXRotation(np.pi), [0, 0, 1.0]))

    def _publish_arrow(self, context):
        velocity = np.array(Water(self.water_input.Eval(context)).velocity)
        speed = float(np.linalg.norm(velocity))
        position = np.array(VehicleState(self.state_input.Eval(context)).position)
        scene, when = self.scene, None
        if scene.recording:
            when = scene.recording_time(context.get_time())
        visible = speed >= STILL_MPS
        if visible:
            rotation = RotationMatrix.MakeFromOneVector(velocity / speed, 2)
            scene.meshcat.SetTransform(self.arrow, RigidTransform(
                rotation, position + [0.0, 0.0, _LIFT_M]), when)
            length = self.metres_per_mps * speed
            scene.meshcat.SetProperty(self.arrow, "scale", [length] * 3, when)
        scene.meshcat.SetProperty(self.arrow, "visible", visible, when)
