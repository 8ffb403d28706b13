"""`PencilBeamProfiler`: a mechanically scanned pencil-beam profiling sonar (Tritech SeaKing).

One narrow beam steps by `step_deg` at `ping_rate` pings per second in the scan plane
(horizontal or vertical in the body frame), over a full circle or back and forth over a
sector. For speed the pings are fired in batches: each update (at `update_rate`) casts the
pings that fall in its period in one vectorised call, from the pose at the update time (at
0.5 m/s and 10 Hz the vehicle moves 5 cm within a batch). `returns` holds those pings.
"""

from __future__ import annotations

import math

import numpy as np

from drake_auv.behaviour import LEG_SIZE, read_leg
from drake_auv.sonar.noise import SonarNoise
from drake_auv.sonar.beams import SonarModel, SonarMount, head_angles
from drake_auv.sonar.range_sonar import RangeSonar

# Head set-up for profile following (our choice): a full circle at the SeaKing's coarse 1.8
# degree step and 30 pings/s, one revolution in 6.7 s, batched at 10 Hz.
FOLLOWING_SETUP = dict(sector_deg=(-180.0, 180.0), step_deg=1.8, ping_rate=30.0,
                       update_rate=10.0, beam_width_deg=1.5, max_range=20.0)


class PencilBeamProfiler(RangeSonar):
    """Inputs `true_state`, `estimated_state` (12 each); output `returns` (`SonarReturns`).

    Args:
        world: true world, a trimesh or a shared `RayCaster`.
        scan_plane: "horizontal" or "vertical" (body x-z plane, +90 deg is up).
        sector_deg: (start, end) of the scanned sector, deg; 360 wide rotates continuously.
        step_deg: head step between pings, deg, > 0.
        ping_rate: pings per second, > 0.
        update_rate: batches per second, > 0, <= ping_rate.
        beam_width_deg: beam cone angle, deg (SeaKing class: about 1 to 2).
        max_range: m, > 0.
        mount_position: sensor position in the body frame, m.
        mount: a full `SonarMount`, overriding scan_plane and mount_position.
        noise: error options (default: none).
        seed: the run's seed, drawn through `stream` (`drake_auv.random_streams`).
        stream: the noise's random stream (`RangeSonar`).
        max_incidence_deg: grazing limit, deg.
        planes: {mission leg: scan plane} where the head is tilted to another plane than
            `scan_plane` (a tilt unit: vertical on vertical-following legs); with it the
            profiler gets a `leg` input.
    """

    def __init__(self, world, scan_plane: str = "horizontal", sector_deg=(-180.0, 180.0),
                 step_deg: float = 0.9, ping_rate: float = 30.0, update_rate: float = 10.0,
                 beam_width_deg: float = 1.5, max_range: float = 20.0,
                 mount_position=(0.0, 0.0, 0.0), mount: SonarMount | None = None,
                 noise: SonarNoise | None = None, seed: int = 0,
                 max_incidence_deg: float = 85.0, planes: dict[int, str] | None = None,
                 stream: str | tuple = "profiler"):
        if scan_plane not in ("horizontal", "vertical"):
            raise ValueError(f"scan_plane must be 'horizontal' or 'vertical', got {scan_plane!r}")
        lo, hi = (float(a) for a in sector_deg)
        if not (np.isfinite(lo) and np.isfinite(hi) and 0 < hi - lo <= 360.0):
            raise ValueError(f"sector_deg must be (start, end) with 0 < end - start <= 360, "
                             f"got {sector_deg}")
        if not (np.isfinite(step_deg) and 0 < step_deg <= 90):
            raise ValueError(f"step_deg must be in (0, 90] deg, got {step_deg}")
        if not (np.isfinite(ping_rate) and ping_rate > 0):
            raise ValueError(f"ping_rate must be > 0 pings/s, got {ping_rate}")
        if not (np.isfinite(update_rate) and 0 < update_rate <= ping_rate):
            raise ValueError(f"update_rate must be in (0, ping_rate = {ping_rate}] Hz, "
                             f"got {update_rate}")
        self.planes = dict(planes or {})
        if not set(self.planes.values()) <= {"horizontal", "vertical"}:
            raise ValueError(f"planes must map legs to 'horizontal' or 'vertical', got "
                             f"{self.planes}")

        def model_of(plane_mount):
            return SonarModel(plane_mount, max_range=max_range,
                              beam_width=np.radians(beam_width_deg),
                              max_incidence=np.radians(max_incidence_deg),
                              noise=noise if noise is not None else SonarNoise())

        model = model_of(mount if mount is not None
                         else SonarMount.named(scan_plane, mount_position))
        self._leg_models = {leg: model_of(SonarMount.named(plane, mount_position))
                            for leg, plane in self.planes.items() if plane != scan_plane}
        self.sector = (np.radians(lo), np.radians(hi))
        self.step = np.radians(step_deg)
        self.pings_per_update = ping_rate / update_rate
        # The head repeats after `cycle` pings (a turn, or there and back over a sector); the
        # beams of a batch depend only on its first ping modulo the cycle, so cache them.
        width = self.sector[1] - self.sector[0]
        cycle = (2 * np.pi if width >= 2 * np.pi - 1e-9 else 2 * width) / self.step
        self._cycle = int(round(cycle)) if abs(cycle - round(cycle)) < 1e-6 else None
        self._geometry_cache = {}
        super().__init__(world, model, 1.0 / update_rate, seed, stream=stream)
        if self.planes:
            self.leg_input = self.DeclareVectorInputPort("leg", LEG_SIZE)

    def scan_model(self, context) -> SonarModel:
        if not self._leg_models:
            return self.model
        return self._leg_models.get(read_leg(self.leg_input, context)[0], self.model)

    def _ping_range(self, n: int) -> tuple[int, int]:
        first = math.floor(n * self.pings_per_update + 1e-9)  # Python ints: read every update
        return first, math.floor((n + 1) * self.pings_per_update + 1e-9)

    def update_angles(self, n: int) -> np.ndarray:
        first, last = self._ping_range(n)
        return head_angles(np.arange(first, last), self.sector, self.step)

    def update_geometry(self, n: int, model: SonarModel | None = None):
        model = self.model if model is None else model
        if self._cycle is None:
            return super().update_geometry(n, model)
        first, last = self._ping_range(n)
        key = (id(model), first % self._cycle, last - first)
        geometry = self._geometry_cache.get(key)
        if geometry is None:
            geometry = super().update_geometry(n, model)
            self._geometry_cache[key] = geometry
        return geometry
