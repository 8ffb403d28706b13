import numpy as np
import pytest

from drake_auv.planning import PlannedPath


def _square():
    pts = np.array([[0, 0, -5], [10, 0, -5], [10, 10, -5], [0, 10, -5.0]])
    return PlannedPath(pts, heading=[0, np.pi / 2, np.pi, -np.pi / 2], sensor_dir=[0, 0, -1],
                labels=["planar", "planar", "transit", "slice"])


def test_length_and_labels():
    path = _square()
    assert path.length == pytest.approx(30.0)
    assert path.length_by_label() == pytest.approx({"planar": 10.0, "transit": 10.0, "slice": 10.0})


def test_resample_keeps_vertices_and_spacing():
    path = _square().resample(0.7)
    assert path.length == pytest.approx(30.0)
    assert np.max(path.segment_lengths()) <= 0.7 + 1e-9
    for v in _square().points:
        assert np.min(np.linalg.norm(path.points - v, axis=1)) < 1e-9
    assert np.allclose(np.linalg.norm(path.sensor_dir, axis=1), 1.0)


def test_times_respect_speed_and_turn_rate():
    path = _square()
    t = path.times(speed=0.5, yaw_rate=np.radians(10))
    # 10 m at 0.5 m/s is 20 s; a 90 degree turn at 10 deg/s takes 9 s, so travel dominates.
    assert np.allclose(np.diff(t), 20.0)
    turn = PlannedPath([[0, 0, 0], [0.1, 0, 0]], heading=[0, np.pi], sensor_dir=[1, 0, 0])
    assert turn.times(0.5, np.radians(10))[-1] == pytest.approx(18.0)


def test_csv_round_trip(tmp_path):
    path = _square().resample(3.0)
    path.to_csv(tmp_path / "p.csv")
    back = PlannedPath.from_csv(tmp_path / "p.csv")
    assert np.allclose(back.points, path.points, atol=1e-6)
    assert np.allclose(back.heading, path.heading, atol=1e-6)
    assert list(back.labels) == list(path.labels)


def test_bad_input_is_named(tmp_path):
    with pytest.raises(ValueError, match="shape"):
        PlannedPath(np.zeros((3, 2)), 0, [0, 0, 1])
    with pytest.raises(ValueError, match="finite"):
        PlannedPath([[0, 0, np.nan]], 0, [0, 0, 1])
    with pytest.raises(ValueError, match="sensor_dir"):
        PlannedPath([[0, 0, 0]], 0, [0, 0, 0])
    with pytest.raises(FileNotFoundError, match="nope.csv"):
        PlannedPath.from_csv(tmp_path / "nope.csv")
    (tmp_path / "bad.csv").write_text("x,y,z,heading,sensor_x,sensor_y,sensor_z,label\n1,2,a,0,0,0,1,p\n")
    with pytest.raises(ValueError, match="bad.csv:2"):
        PlannedPath.from_csv(tmp_path / "bad.csv")


def test_to_trajectory_reference():
    from pydrake.systems.primitives import TrajectorySource

    path = _square()
    traj = path.to_trajectory(speed=0.5)
    assert traj.rows() == 4
    assert traj.end_time() == pytest.approx(60.0)
    source = TrajectorySource(traj, output_derivative_order=1)
    ctx = source.CreateDefaultContext()
    ctx.SetTime(5.0)
    ref = source.get_output_port().Eval(ctx)
    assert ref.shape == (8,)
    assert np.allclose(ref[:3], [2.5, 0, -5])
    assert np.allclose(ref[4:7], [0.5, 0, 0])


def test_chain_trajectory_times_the_pieces_like_their_concatenation():
    """A transit ending near a plan whose headings wrap: the chained trajectory has the
    concatenated path's breaks and samples (yaw continuous, no spin at the joins); built
    with the joins dropped, or the yaw not carried over, it would not."""
    transit = PlannedPath(np.array([[0.0, 0, -5], [3, 0, -5], [3, 2, -4]]), [0.0, 3.0, 3.1],
                   (0, 0, -1))
    plan = PlannedPath(np.array([[3.0, 2.5, -4], [3, 6, -4], [0, 6, -4]]), [-3.1, 3.0, -3.0],
                (0, 0, -1))
    chained = PlannedPath.chain_trajectory([transit, plan], speed=0.5)
    whole = PlannedPath.concatenate([transit, plan]).to_trajectory(speed=0.5)
    assert np.allclose(chained.get_segment_times(), whole.get_segment_times(), atol=1e-12)
    t = np.array(whole.get_segment_times())
    assert np.allclose(chained.vector_values(t), whole.vector_values(t), atol=1e-12)
    assert np.abs(np.diff(chained.vector_values(t)[3])).max() <= 3.0 + 1e-9  # no 2 pi spin
    shifted = PlannedPath.chain_trajectory([transit, plan], speed=0.5)
    shifted.shiftRight(7.0)
    assert shifted.start_time() == 7.0
    assert np.allclose(shifted.EvalDerivative(7.0 + 2.0, 1), whole.EvalDerivative(2.0, 1))
    single = PlannedPath.chain_trajectory([PlannedPath(np.zeros((1, 3)), 0.0, (0, 0, -1))], speed=0.5)
    assert single.end_time() == 1.0  # one sample: held 1 s


def test_label_codes_are_numpys_unique_inverse():
    labels = np.array(["transit", "planar", "slice", "planar", "transit", "zz", "planar"],
                      dtype=object)
    path = PlannedPath(np.zeros((7, 3)), np.zeros(7), np.tile([0, 0, -1.0], (7, 1)), labels)
    names, codes = path.label_codes()
    want_names, want_codes = np.unique(labels.astype(str), return_inverse=True)
    assert names == want_names.tolist()
    np.testing.assert_array_equal(codes, want_codes)
