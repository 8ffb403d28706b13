"""benchmarks/bench_sensors.py's floor systems: they fire at the sonars' rates and, when asked,
cast the sonars' own rays from the true pose (what the floor of the sensors' ratio counts)."""

import sys
from pathlib import Path

import numpy as np
import trimesh
from pydrake.systems.analysis import Simulator

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))
import bench_sensors as bench  # noqa: E402
from drake_auv.geometry import RayCaster  # noqa: E402
from drake_auv.sonar.multibeam import MultibeamSonar  # noqa: E402


class CountingCaster(RayCaster):
    """A RayCaster that records the rays it is asked to cast."""

    def __init__(self, mesh):
        super().__init__(mesh)
        self.calls = []

    def cast_unit(self, origins, unit_directions, max_range):
        self.calls.append((np.array(origins), np.array(unit_directions)))
        return super().cast_unit(origins, unit_directions, max_range)


def _floor_run(cast: bool, seconds: float = 1.0):
    caster = CountingCaster(trimesh.creation.box(extents=(100.0, 100.0, 1.0)))
    sonars = bench.floor_sonars(caster, cast)
    state = np.zeros(12)
    state[:3] = 1.0, 2.0, 10.0  # 9.5 m above the box's top face
    state[5] = 0.3  # yawed: the rays turn with the vehicle
    counts = []
    for sonar in sonars:
        context = sonar.CreateDefaultContext()
        sonar.true_state_input.FixValue(context, state)
        sonar.estimated_state_input.FixValue(context, state)
        simulator = Simulator(sonar, context)
        simulator.AdvanceTo(seconds)
        counts.append(context.get_abstract_state(0).get_value())
    return caster, counts, state


def test_the_floor_systems_fire_at_the_sonars_rates_without_casting():
    caster, counts, _ = _floor_run(cast=False)
    assert counts == [10, 10]  # 10 Hz, t = 0 to 0.9 s (AdvanceTo(1) leaves t = 1's for the next)
    assert caster.calls == []


def test_the_floor_systems_cast_the_sonars_rays_from_the_true_pose():
    caster, counts, state = _floor_run(cast=True)
    assert counts == [10, 10]
    assert len(caster.calls) == 20
    origin, rays = caster.calls[0]  # the multibeam's first update
    np.testing.assert_allclose(origin, state[:3])
    multibeam = MultibeamSonar(caster)
    body = multibeam.update_geometry(0).rays_body
    assert rays.shape == body.shape == (480, 3)
    c, s = np.cos(0.3), np.sin(0.3)
    np.testing.assert_allclose(rays, body @ np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]]).T,
                               atol=1e-12)
    # the profiler's batches follow its head: consecutive updates cast different rays
    assert not np.array_equal(caster.calls[10][1], caster.calls[11][1])
