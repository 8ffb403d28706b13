"""The on-line octree map: the OctoMap octree and its distance queries (`octree_map`) and the
log of returns it is built from (`scan_log`), pure, with the lattice codes their indices and
the replanner's tube share (`lattice`); the `OctreeMapper` LeafSystem (`mapper`)."""

from drake_auv.mapping.octree_map import OctreeMap
from drake_auv.mapping.scan_log import ScanBatch, ScanLog

__all__ = ["OctreeMap", "ScanBatch", "ScanLog"]
