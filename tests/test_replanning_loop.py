"""The replanning loop closed around an ideal vehicle (no Drake): octree map from a ray-cast
side-looking fan, STOMP sections at 1 Hz (warm-started), the vehicle flying each plan at
survey speed; against the same loop without the optimiser."""

import numpy as np
import pytest
import trimesh

from drake_auv.mapping.octree_map import OctreeMap
from drake_auv.replanning.parameters import ReplanningParameters
from drake_auv.replanning.section import replan_section

OMEGA, SPEED, DT, PERIOD = 6.0, 0.5, 0.1, 1.0
BLOCK_CENTRE, BLOCK_HALF = np.array([0.0, 0.0, -4.0]), np.array([2.5, 2.5, 6.0])


def _world():
    block = trimesh.creation.box(extents=2 * BLOCK_HALF)
    block.apply_translation(BLOCK_CENTRE)
    seabed = trimesh.creation.box(extents=(80.0, 80.0, 1.0))
    seabed.apply_translation((0.0, 0.0, -10.5))
    return trimesh.util.concatenate([block, seabed])


def _block_distance(points):
    q = np.abs(points - BLOCK_CENTRE) - BLOCK_HALF
    return np.linalg.norm(np.maximum(q, 0.0), axis=-1)


def _nominal(shift):
    """Open semicircle around the block's +x half at offset Omega, 5 m deep, shifted."""
    legs = [np.stack([np.arange(-2.5, 2.5, 1.0), np.full(5, -2.5 - OMEGA)], axis=1)]
    for a0, cy in ((-np.pi / 2, -2.5), (0.0, 2.5)):
        a = np.linspace(a0, a0 + np.pi / 2, 10)
        legs.append(np.stack([2.5 + OMEGA * np.cos(a), cy + OMEGA * np.sin(a)], axis=1))
        if a0 < 0:
            legs.append(np.stack([np.full(5, 2.5 + OMEGA), np.arange(-2.5, 2.5, 1.0)], axis=1))
    legs.append(np.stack([np.arange(2.5, -2.5, -1.0), np.full(5, 2.5 + OMEGA)], axis=1))
    xy = np.vstack(legs) + shift
    return np.hstack([xy, np.full((len(xy), 1), -5.0)])


def _fly(shift, optimizer, seed=0):
    """The block's distance along the flown trail, and the steps flown (1500: unfinished)."""
    world, waypoints = _world(), _nominal(np.asarray(shift, dtype=float))
    omap, params = OctreeMap(0.5), ReplanningParameters()
    x = waypoints[0] + [-3.0, -3.0, 0.0]
    next_index, plan, trail = 0, None, []
    for step in range(1500):
        if step % round(PERIOD / DT) == 0:
            if plan is not None:
                next_index = plan.next_index(SPEED * PERIOD)
            plan = replan_section(x, waypoints, next_index, omap, params, seed=seed + step,
                                  optimizer=optimizer,
                                  previous=None if plan is None else plan.trajectory)
            if plan is None:
                break
            traj = plan.trajectory
            s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(traj, axis=0),
                                                                axis=1))])
            flown = 0.0
        # Side-looking (port) 480-beam fan, heading along the motion.
        tangent = traj[-1] - traj[0]
        a = np.arctan2(tangent[1], tangent[0]) + np.pi / 2 + np.linspace(-np.pi / 3,
                                                                          np.pi / 3, 480)
        d = np.stack([np.cos(a), np.sin(a), np.zeros_like(a)], axis=1)
        loc, ray, _ = world.ray.intersects_location(np.tile(x, (len(d), 1)), d,
                                                    multiple_hits=False)
        ranges = np.full(len(d), np.nan)
        ranges[ray] = np.linalg.norm(loc - x, axis=1)
        omap.insert_scan(x, d, ranges, 20.0)
        flown = min(flown + SPEED * DT, s[-1])
        x = np.array([np.interp(flown, s, traj[:, k]) for k in range(3)])
        trail.append(x)
    return _block_distance(np.array(trail)), step


@pytest.mark.parametrize("shift", [(-4.0, 0.0), (3.0, -3.0)])
def test_replanning_keeps_the_offset_where_the_nominal_path_does_not(shift):
    # STOMP alone keeps the offset (no waypoint is moved before it runs); "none" flies the
    # same sections' initial trajectories, through the wrong waypoints.
    d_replan, steps = _fly(shift, "stomp")
    d_nominal, steps_nominal = _fly(shift, "none")
    assert steps < 1499 and steps_nominal < 1499, "a mission did not finish the semicircle"
    assert d_replan.min() > 1.0 + 3.0  # vehicle radius plus a margin: no contact
    flown = slice(100, None)  # after the approach from 8 m out
    assert abs(d_replan[flown].mean() - OMEGA) < 0.5
    assert np.abs(d_replan - OMEGA).mean() < 0.35 * np.abs(d_nominal - OMEGA).mean()
