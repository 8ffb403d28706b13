"""The `leg` signal: which leg of a mission is flying, and since when.

A mission is a sequence of legs (a transit, a profile-following run, a survey), numbered from
0. The `MissionSupervisor` outputs `leg` (`signals.LegSignal`: index, start_s); each behaviour
(the path reference, the profile-following controller, the replanner, the profiler's head) is
given the legs it serves and does its work only while one of them is flying, starting afresh
when a new one begins. A behaviour whose `leg` input is left unconnected serves leg 0 from
t = 0, so it runs on its own in a test or an example.
"""

from __future__ import annotations

from drake_auv.signals import LegSignal

LEG_SIZE = LegSignal.size()


def read_leg(port, context) -> tuple[int, float]:
    """(index, start time in s) from a `leg` input port; (0, 0.0) when it is unconnected."""
    if not port.HasValue(context):
        return 0, 0.0
    leg = LegSignal(port.Eval(context))
    return int(leg.index), float(leg.start_s)
