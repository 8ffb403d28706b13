"""Sonars: beam geometry and mounts (`beams`), noise (`noise`), the `SonarReturns` signal
(`returns`) and the `Sensor` protocol with the built-in source names (`sensor`), pure; the
LeafSystems `RangeSonar`, `MultibeamSonar` and `PencilBeamProfiler` (`range_sonar`,
`multibeam`, `profiler`) import Drake and load on their own."""

from drake_auv.sonar.noise import SonarNoise, apply_noise
from drake_auv.sonar.returns import SonarReturns
from drake_auv.sonar.beams import (MOUNT_ROTATIONS, BeamGeometry, SonarModel, SonarMount,
                                 beam_geometry, fan_angles, head_angles, scan)

__all__ = ["MOUNT_ROTATIONS", "BeamGeometry", "SonarModel", "SonarMount", "SonarNoise",
           "SonarReturns", "apply_noise", "beam_geometry", "fan_angles", "head_angles", "scan"]
