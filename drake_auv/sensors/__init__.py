"""Sonar models as pure functions (beams, noise, mounts) and the `SonarReturns` signal; no Drake."""

from drake_auv.sensors.noise import SonarNoise, apply_noise
from drake_auv.sensors.returns import SonarReturns
from drake_auv.sensors.sonar import (MOUNT_ROTATIONS, BeamGeometry, SonarModel, SonarMount,
                                     beam_geometry, fan_angles, head_angles, scan)

__all__ = ["MOUNT_ROTATIONS", "BeamGeometry", "SonarModel", "SonarMount", "SonarNoise",
           "SonarReturns", "apply_noise", "beam_geometry", "fan_angles", "head_angles", "scan"]
