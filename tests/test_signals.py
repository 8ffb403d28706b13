"""The signals' named views: every vector port of the mission Diagram has one, its fields
alias the vector they name, and diagram.dot writes them beside the ports."""

import re

import numpy as np
import pytest

from drake_auv.mission.config import load_mission
from drake_auv.mission.diagram import build_mission_diagram
from drake_auv.mission.site import load_site
from drake_auv.signals import (PORT_SIGNALS, Reference, Response, VehicleState,
                               annotate_graphviz, signal_views)

# arrays of one kind of value (one angle per target face), not named fields
UNNAMED = {"face_angles"}


@pytest.fixture(scope="module", params=["breakwater", "boulder"])
def diagram(request):
    spec = load_mission(request.param)
    return build_mission_diagram(load_site(spec.site, spec.seed), spec)[0]


def _vector_ports(diagram):
    for system in diagram.GetSystems():
        for kind, count, get in (("u", system.num_input_ports(), system.get_input_port),
                                 ("y", system.num_output_ports(), system.get_output_port)):
            for k in range(count):
                port = get(k)
                if port.size() > 2 and port.get_name() not in UNNAMED:
                    yield (system.get_name(), kind, k), port


def test_every_vector_port_of_the_mission_has_a_view_of_its_size(diagram):
    views = signal_views(diagram)
    ports = dict(_vector_ports(diagram))
    assert len(ports) > 30
    missing = sorted(f"{key[0]}.{port.get_name()}" for key, port in ports.items()
                     if key not in views)
    assert not missing, f"vector ports without a layout in drake_auv.signals: {missing}"
    for key, port in ports.items():
        assert views[key].size() == port.size(), key


def test_diagram_dot_names_every_vector_ports_fields(diagram):
    dot = annotate_graphviz(diagram, diagram.GetGraphvizString())
    labels = re.findall(r'<TD PORT="[uy]\d+" [^>]*>([^<]*)</TD>', dot)
    named = [label for label in labels if "[" in label]
    assert len(named) >= len(dict(_vector_ports(diagram)))
    state = " ".join(VehicleState.get_fields())
    assert f"estimated_state [{state}]" in labels and f"true_state [{state}]" in labels
    assert "response [mode cause start_s x0 y0 z0 yaw0 x1 y1 z1]" in labels
    assert "value [x y z yaw vx vy vz yaw_rate]" in labels  # the PortSwitch's output


def test_a_port_of_another_size_gets_no_view():
    from drake_auv.signals import port_signal
    from pydrake.systems.primitives import PassThrough

    assert port_signal(PassThrough(8).get_input_port()) is None  # named "u"
    assert PORT_SIGNALS["reference"] is Reference
    from drake_auv.vehicle.tracker import TrajectoryTracker

    tracker = TrajectoryTracker()
    assert port_signal(tracker.GetInputPort("reference")) is Reference
    assert port_signal(tracker.GetInputPort("state")) is VehicleState


def test_views_alias_vectors_and_name_the_columns_of_tables():
    x = np.arange(12.0)
    state = VehicleState(x)
    assert (state.yaw, state.r) == (5.0, 11.0)
    yaw = state.yaw
    x[5] = 2.0
    assert yaw == 5.0 and state.yaw == 2.0  # a field reads a scalar, the view follows x
    state.position = [7.0, 8.0, 9.0]
    state.yaw = -1.0
    assert x[:6].tolist() == [7.0, 8.0, 9.0, 3.0, 4.0, -1.0]
    table = np.arange(30.0).reshape(3, 10)  # a log: one row per sample
    response = Response(table)
    assert response.start_s.tolist() == [2.0, 12.0, 22.0]
    assert response.target.shape == (3, 3) and response.target[1].tolist() == [17.0, 18.0, 19.0]
    reference = Reference.zeros()
    reference.velocity = [1.0, 2.0, 3.0]
    assert reference[:].tolist() == [0, 0, 0, 0, 1, 2, 3, 0]
    assert Reference.get_fields() == ("x", "y", "z", "yaw", "vx", "vy", "vz", "yaw_rate")
