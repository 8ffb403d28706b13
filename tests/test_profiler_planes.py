"""The profiler's head on a tilt unit: horizontal scans, vertical on the legs that need it."""

import numpy as np
from pydrake.systems.analysis import Simulator

from drake_auv.scenarios import get_scenario
from drake_auv.sonar.profiler import FOLLOWING_SETUP, PencilBeamProfiler


def test_head_scans_the_plane_of_the_flying_leg():
    world = get_scenario("pool").world  # 16 m x 8 m, 5 to 7 m deep
    state = np.zeros(12)
    state[2] = -3.0
    profiler = PencilBeamProfiler(world, scan_plane="horizontal", planes={1: "vertical"},
                                  **FOLLOWING_SETUP)
    context = profiler.CreateDefaultContext()
    for port in (profiler.true_state_input, profiler.estimated_state_input):
        port.FixValue(context, state)
    profiler.leg_input.FixValue(context, [0.0, 0.0])
    simulator = Simulator(profiler, context)
    def points_until(end):
        seen = []
        while context.get_time() < end - 1e-9:
            simulator.AdvanceTo(context.get_time() + 0.1)
            seen.append(profiler.returns_output.Eval(context).points_nav)
        points = np.vstack(seen)
        return points[np.all(np.isfinite(points), axis=1)]

    horizontal = points_until(7.0)  # a whole turn of the head: the four walls at 3 m depth
    assert len(horizontal) > 50 and np.allclose(horizontal[:, 2], -3.0, atol=0.3)
    profiler.leg_input.FixValue(context, [1.0, 7.0])
    vertical = points_until(14.0)  # the x-z plane: the end walls and the V bottom
    assert len(vertical) > 50 and np.allclose(vertical[:, 1], 0.0, atol=0.3)
    assert vertical[:, 2].min() < -4.5
