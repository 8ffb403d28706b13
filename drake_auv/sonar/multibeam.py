"""`MultibeamSonar`: a multibeam echosounder (Imagenex DeltaT 837 class), one fan per update.

`num_beams` equiangular beams over `fan_deg` in the fan plane of the mount: "down" (across
track, below the vehicle), "port" / "starboard" (side-looking, centre beam horizontal), or
"forward" (horizontal fan ahead). `returns` is the point cloud of the last ping; with
`axis_hits_output`, `axis_hits` is the faces of the true world its beams' axes hit (for the
multibeam coverage recorder, which scores the same rays).
"""

from __future__ import annotations

import numpy as np

from drake_auv.sonar.noise import SonarNoise
from drake_auv.sonar.beams import SonarModel, SonarMount, beam_geometry, fan_angles
from drake_auv.sonar.range_sonar import RangeSonar


class MultibeamSonar(RangeSonar):
    """Inputs `true_state`, `estimated_state` (12 each); output `returns` (`SonarReturns`).

    Args:
        world: true world, a trimesh or a shared `RayCaster`.
        num_beams: beams per ping, >= 1.
        fan_deg: fan aperture, deg, in [0, 360).
        rate: pings per second, > 0.
        max_range: m, > 0.
        mount: "down", "port", "starboard", "forward", or a `SonarMount`.
        mount_position: sensor position in the body frame, m (with a named mount).
        beam_width_deg: beam cone angle, deg (0: one ray per beam).
        noise: error options (default: none).
        seed: the run's seed, drawn through `stream` (`drake_auv.random_streams`).
        stream: the noise's random stream (`RangeSonar`).
        max_incidence_deg: grazing limit, deg.
        axis_hits_output: declare the `axis_hits` output (`AxisHits`, true world).
    """

    def __init__(self, world, num_beams: int = 480, fan_deg: float = 120.0, rate: float = 10.0,
                 max_range: float = 20.0, mount="down", mount_position=(0.0, 0.0, 0.0),
                 beam_width_deg: float = 0.0, noise: SonarNoise | None = None, seed: int = 0,
                 max_incidence_deg: float = 85.0, axis_hits_output: bool = False,
                 stream: str | tuple = "multibeam"):
        if not (np.isfinite(rate) and rate > 0):
            raise ValueError(f"rate must be > 0 pings/s, got {rate}")
        if isinstance(mount, str):
            if mount not in ("down", "port", "starboard", "forward"):
                raise ValueError(f"multibeam mount must be 'down', 'port', 'starboard' or "
                                 f"'forward', got {mount!r}")
            mount = SonarMount.named(mount, mount_position)
        self.angles = fan_angles(num_beams, np.radians(fan_deg))
        model = SonarModel(mount, max_range=max_range, beam_width=np.radians(beam_width_deg),
                           max_incidence=np.radians(max_incidence_deg),
                           noise=noise if noise is not None else SonarNoise())
        self._geometry = beam_geometry(model, self.angles)
        super().__init__(world, model, 1.0 / rate, seed, axis_hits=axis_hits_output,
                         stream=stream)

    def update_angles(self, n: int) -> np.ndarray:
        return self.angles

    def update_geometry(self, n: int, model: SonarModel | None = None):
        return self._geometry
