"""Ray casting and visibility against triangle meshes (embree through embreex); no Drake."""

from drake_auv.geometry.raycast import RayCaster, RayHits, validate_mesh
from drake_auv.geometry.visibility import (CoverageMap, FaceVisibility, angle_histogram,
                                           coverage_share, merge_best)

__all__ = ["CoverageMap", "FaceVisibility", "RayCaster", "RayHits", "angle_histogram",
           "coverage_share", "merge_best", "validate_mesh"]
