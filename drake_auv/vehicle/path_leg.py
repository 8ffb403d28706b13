"""`PathLeg`: one leg `PathReference` flies along a path, as plain data (no Drake), so the
off-line mission plan (`drake_auv.mission.plan`) builds its legs without loading pydrake."""

from __future__ import annotations

from dataclasses import dataclass

from drake_auv.params import param, validate


@dataclass(frozen=True)
class PathLeg:
    """One leg flown along a path.

    Attributes:
        kind: "goto" (to `target`) or "nominal" (the `nominal` input's path).
        target: (x, y, z) of a goto, m. yaw: its final heading, rad (None: along the motion).
        speed: m/s along the path, > 0.
    """

    kind: str = param(kind="choice", choices=("goto", "nominal"))
    target: tuple | None = param(None, kind="vector", names=("x", "y", "z"), unit="m",
                                 nullable=True)
    yaw: float | None = param(None, nullable=True, unit="rad")
    speed: float = param(0.5, low=0.0, low_open=True, unit="m/s")

    def __post_init__(self):
        validate(self)
        if self.kind == "goto" and self.target is None:
            raise ValueError("PathLeg.target = None: a goto leg needs a finite (x, y, z) target")
