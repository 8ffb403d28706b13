"""Ray casting and visibility against triangle meshes (embree through trimesh/embreex); no Drake."""

from drake_auv.geometry.raycast import RayCaster, RayHits, validate_mesh

__all__ = ["RayCaster", "RayHits", "validate_mesh"]
