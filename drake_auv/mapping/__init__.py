"""The on-line octree map (OctoMap) and its distance queries, pure (no Drake)."""

from drake_auv.mapping.octree_map import OctreeMap, OctreeMapHandle

__all__ = ["OctreeMap", "OctreeMapHandle"]
