"""On-line view planning from the octree: frontiers, gains, paths (pure) and the ViewPlanner."""
