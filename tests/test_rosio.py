"""A dive as an MCAP log of ROS 2 messages, read back by the tools users use (the `mcap`
reader with `mcap-ros2-support`'s decoder, and `rosbags`, both independent of the writer's
serialisation), and logs replayed through the map, the point cloud and the scores."""

from __future__ import annotations

import csv
from collections import Counter
from pathlib import Path

import numpy as np
import pytest
import trimesh
from scipy.spatial import cKDTree

from drake_auv.cli import main
from drake_auv.mission.config import load_mission
from drake_auv.mission.report.outputs import write_trajectory
from drake_auv.mission.runner import run_mission
from drake_auv.mission.site import load_site
from drake_auv.reconstruction.pointcloud import read_ply
from drake_auv.reconstruction.products import dive_cloud, write_points
from drake_auv.reconstruction.scoring import score
from drake_auv.rosio import messages as m
from drake_auv.rosio.reader import DEFAULT_TOPICS, open_log
from drake_auv.rosio.replay import map_settings, replay
from drake_auv.rosio.writer import dive_log


def _dive(folder: Path, mission: str, cap_s: float):
    spec = load_mission(mission, overrides=[f"limits.max_time_s={cap_s}"])
    site = load_site(spec.site, spec.seed, label=spec.name)
    result = run_mission(spec, site, progress=False,
                         mcap=dive_log(folder / "dive.mcap", spec, site))
    write_trajectory(result, folder / "trajectory.csv")
    write_points(result.mapping.scan_log, result.site, folder / "points.ply")
    return result


@pytest.fixture(scope="module")
def boulder(tmp_path_factory):
    """A boulder dive capped at 20 s, with its dive.mcap, trajectory.csv and points.ply."""
    folder = tmp_path_factory.mktemp("boulder")
    return folder, _dive(folder, "boulder", 20.0)


def _mcap_messages(filename):
    """[(topic, schema name, log time ns, decoded message)] by the mcap reader and
    mcap-ros2-support's decoder."""
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    with open(filename, "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        return [(channel.topic, schema.name, message.log_time, decoded) for
                schema, channel, message, decoded in reader.iter_decoded_messages()]


def test_dive_mcap_reads_with_mcap_and_rosbags(boulder):
    folder, result = boulder
    filename = folder / "dive.mcap"
    assert not (folder / "dive.mcap.part").exists()
    decoded = _mcap_messages(filename)
    counts = Counter((topic, schema) for topic, schema, _, _ in decoded)
    from rosbags.highlevel import AnyReader

    with AnyReader([filename]) as reader:  # rosbag2 storage: the file itself
        by_rosbags = Counter((c.topic, c.msgtype) for c in reader.connections
                             for _ in range(c.msgcount))
        for conn, _, raw in reader.messages():  # every message deserialises
            reader.deserialize(raw, conn.msgtype)
    assert by_rosbags == counts
    expected = {("/tf", "tf2_msgs/msg/TFMessage"), ("/tf_static", "tf2_msgs/msg/TFMessage"),
                ("/odometry/navigation", "nav_msgs/msg/Odometry"),
                ("/odometry/truth", "nav_msgs/msg/Odometry"),
                ("/reference", "geometry_msgs/msg/PoseStamped"),
                ("/sonar/multibeam/points", "sensor_msgs/msg/PointCloud2"),
                ("/sonar/multibeam/scan", "sensor_msgs/msg/LaserScan"),
                ("/sonar/profiler/points", "sensor_msgs/msg/PointCloud2"),
                ("/plan", "nav_msgs/msg/Path"), ("/mission/leg", "std_msgs/msg/Int32"),
                ("/mission/response", "std_msgs/msg/Int32"),
                ("/thrust", "std_msgs/msg/Float64MultiArray"),
                ("/ocean/current", "std_msgs/msg/Float64MultiArray"),
                ("/coverage/multibeam", "std_msgs/msg/Float64"),
                ("/world", "visualization_msgs/msg/MarkerArray"),
                ("/octomap/occupied", "visualization_msgs/msg/MarkerArray")}
    assert expected <= set(counts)
    with open(folder / "trajectory.csv") as f:
        rows = sum(1 for _ in csv.reader(f)) - 1
    # trajectory.csv and the odometry share the 0.1 s period: a rate ratio of 1
    for topic in ("/odometry/navigation", "/odometry/truth", "/tf"):
        n = sum(v for (t, _), v in counts.items() if t == topic)
        assert abs(n - rows) <= 0.01 * rows, (topic, n, rows)
    # the truth odometry is the trajectory's true pose (trajectory.csv rounds to 1 mm)
    truth = np.array([[d.pose.pose.position.x, d.pose.pose.position.y, d.pose.pose.position.z]
                      for t, _, _, d in decoded if t == "/odometry/truth"])
    with open(folder / "trajectory.csv") as f:
        table = np.array([[float(v) for v in row[1:4]] for row in list(csv.reader(f))[1:]])
    assert np.abs(truth - result.site.to_local(table[:len(truth)])).max() <= 6e-4
    assert {d.header.frame_id for t, _, _, d in decoded if t == "/odometry/truth"} == {"map"}
    # the boulder's sea: the current the log carries is trajectory.csv's (4 decimals there)
    current = np.array([d.data for t, _, _, d in decoded if t == "/ocean/current"])
    with open(folder / "trajectory.csv") as f:
        columns = np.array([[float(r[k]) for k in ("current_x", "current_y", "current_z")]
                            for r in csv.DictReader(f)])
    n = min(len(current), len(columns))
    assert n >= 0.99 * len(columns) and np.abs(current).max() > 0.05
    assert np.abs(current[:n] - columns[:n]).max() <= 6e-5
    from mcap.reader import make_reader

    with open(filename, "rb") as f:
        meta = {r.name: r.metadata for r in make_reader(f).iter_metadata()}
    assert meta["drake_auv"]["convention"] == "ENU"
    assert float(meta["drake_auv"]["origin_x"]) == result.site.origin[0]


def _tf_lookup(decoded):
    """{child: (parent, static pose)} and {child: {stamp ns: pose}} from the decoded TF."""
    static, dynamic = {}, {}
    for topic, _, _, msg in decoded:
        if topic not in ("/tf", "/tf_static"):
            continue
        for t in msg.transforms:
            tr, q = t.transform.translation, t.transform.rotation
            pose = (np.array([tr.x, tr.y, tr.z]), m.rotation_matrix([q.x, q.y, q.z, q.w]))
            if topic == "/tf_static":
                static[t.child_frame_id] = (t.header.frame_id, pose)
            else:
                ns = t.header.stamp.sec * 10**9 + t.header.stamp.nanosec
                dynamic.setdefault(t.child_frame_id, {})[ns] = pose
    return static, dynamic


def test_every_return_of_points_ply_is_in_the_point_clouds(boulder):
    """Each cloud through the TF tree (its sensor on `base_link`, `base_link` in `map` at the
    cloud's stamp) lands on points.ply's returns (site coordinates) within 1 mm."""
    folder, result = boulder
    decoded = _mcap_messages(folder / "dive.mcap")
    static, dynamic = _tf_lookup(decoded)
    placed = []
    for topic, schema, _, msg in decoded:
        if schema != "sensor_msgs/msg/PointCloud2":
            continue
        fields = {f.name: f for f in msg.fields}
        assert [fields[k].datatype for k in "xyz"] == [m.FLOAT32] * 3
        data = np.frombuffer(bytes(msg.data), np.dtype({
            "names": list("xyz"), "formats": ["<f4"] * 3,
            "offsets": [fields[k].offset for k in "xyz"], "itemsize": msg.point_step}))
        points = np.column_stack([data["x"], data["y"], data["z"]]).astype(float)
        points = points[np.isfinite(points).all(axis=1)]
        parent, (p_bs, r_bs) = static[msg.header.frame_id]
        assert parent == "base_link"
        ns = msg.header.stamp.sec * 10**9 + msg.header.stamp.nanosec
        p_mb, r_mb = dynamic["base_link"][ns]  # the pose at the cloud's stamp, exactly
        placed.append(p_mb + (p_bs + points @ r_bs.T) @ r_mb.T)
    placed = result.site.to_site(np.concatenate(placed))
    ply = read_ply(folder / "points.ply").points
    assert len(ply) == result.mapping.scan_log.returns > 1000
    distance, _ = cKDTree(placed).query(ply)
    assert distance.max() <= 1e-3


def test_replay_of_dive_mcap_rebuilds_the_same_octree_and_points(boulder, tmp_path):
    folder, result = boulder
    index = open_log(folder / "dive.mcap")
    assert index.world == "map" and index.base == "base_link"
    settings = map_settings(index)
    assert settings["multibeam_stride"] == result.spec.replanner.multibeam_stride
    replayed = replay(index, settings)
    ours, theirs = replayed.online_map.map, result.mapping.online_map.map
    assert ours.tree.getNumLeafNodes() == theirs.tree.getNumLeafNodes() > 1000
    occupied = ours.occupied_points()
    assert len(occupied) > 100
    np.testing.assert_array_equal(np.unique(occupied, axis=0),
                                  np.unique(theirs.occupied_points(), axis=0))
    write_points(replayed.scan_log, replayed.site, tmp_path / "points.ply")
    a, b = read_ply(folder / "points.ply"), read_ply(tmp_path / "points.ply")
    np.testing.assert_array_equal(a.points, b.points)
    np.testing.assert_array_equal(a.sources, b.sources)


def test_replay_of_a_pool_dive_gives_its_coverage(tmp_path):
    """The returns' coverage of the target (share of its area within 0.5 m of a return)
    from the replayed log equals the run's within 0.001."""
    result = _dive(tmp_path, "pool", 12.0)
    index = open_log(tmp_path / "dive.mcap")
    replayed = replay(index, map_settings(index), target=result.site.target_mesh)
    target = result.site.target_mesh
    run, _ = score(target, None, dive_cloud(result.mapping.scan_log).points)
    again, _ = score(replayed.site.target_mesh, None, dive_cloud(replayed.scan_log).points)
    assert run["point_cloud"]["completeness"] > 0.1
    assert abs(again["point_cloud"]["completeness"]
               - run["point_cloud"]["completeness"]) <= 1e-3


# --- a vehicle's own logs: other topic names, a sonar on a static transform -----------------

WALL_X = 8.0  # m, a vertical wall x = 8 facing the vehicle: 12 m long, 8 m high, 1 m thick
WALL_LO, WALL_HI = np.array([WALL_X, -14.0, -16.0]), np.array([WALL_X + 1.0, -2.0, -8.0])
MB_ANGLES = np.radians(np.linspace(-60, 60, 121))


def _wall():
    return trimesh.creation.box(bounds=np.array([WALL_LO, WALL_HI]))


def _vehicle_log(n: int = 100):
    """A vehicle sailing north at 0.5 m/s, 8 m from the wall, yawed 10 deg; a forward-looking
    fan on a static mount (0.5 m ahead, pitched so the fan is vertical) towards the wall:
    [(ns, position, R_wb)], the mount (p, R_bs) and per ping (ns, ranges) in the fan."""
    yaw = np.radians(10.0)
    r_wb = np.array([[np.cos(yaw), -np.sin(yaw), 0], [np.sin(yaw), np.cos(yaw), 0], [0, 0, 1]])
    p_bs, r_bs = np.array([0.5, 0.0, -0.2]), np.array([[1.0, 0, 0], [0, 0, -1], [0, 1, 0]])
    poses = [(k * 100_000_000, np.array([0.0, -10.0 + 0.05 * k, -12.0]), r_wb)
             for k in range(n)]
    d_s = np.column_stack([np.cos(MB_ANGLES), np.sin(MB_ANGLES), np.zeros_like(MB_ANGLES)])
    pings = []
    for ns, p, r in poses[1:-1]:
        origin, d_w = p + r @ p_bs, d_s @ (r @ r_bs).T
        ranges = (WALL_X - origin[0]) / d_w[:, 0]
        hit = origin + d_w * ranges[:, None]
        on_wall = (hit[:, 1:] >= WALL_LO[1:]).all(axis=1) & (hit[:, 1:] <= WALL_HI[1:]).all(axis=1)
        ranges[(ranges > 20.0) | (d_w[:, 0] <= 0) | ~on_wall] = np.nan
        pings.append((ns + 50_000_000, ranges))  # between two poses: interpolated
    return poses, (p_bs, r_bs), d_s, pings


def _ros1_bag(path: Path, odom_topic="/nav/odom", cloud_topic="/mbes/cloud", ping_shift=0,
              cloud_frame="mbes", corrupt=None):
    """A vehicle's ROS 1 bag (`_vehicle_log`); `corrupt(store, cloud)`: changes to the third
    cloud's fields (a dict of the `PointCloud2`'s)."""
    from rosbags.rosbag1 import Writer
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    store = get_typestore(Stores.ROS1_NOETIC)
    store.register(get_types_from_msg("geometry_msgs/TransformStamped[] transforms",
                                      "tf2_msgs/msg/TFMessage"))
    poses, (p_bs, r_bs), d_s, pings = _vehicle_log()

    def header(ns, frame):
        return m.make_in(store, "std_msgs/msg/Header", stamp=m.make_in(
            store, "builtin_interfaces/msg/Time", sec=ns // 10**9, nanosec=ns % 10**9),
            frame_id=frame)

    def tfs(ns, parent, child, p, r):
        q = m.quaternion(r)
        return m.make_in(store, "geometry_msgs/msg/TransformStamped", header=header(ns, parent),
                         child_frame_id=child, transform=m.make_in(
                             store, "geometry_msgs/msg/Transform",
                             translation=m.make_in(store, "geometry_msgs/msg/Vector3",
                                                   x=p[0], y=p[1], z=p[2]),
                             rotation=m.make_in(store, "geometry_msgs/msg/Quaternion",
                                                x=q[0], y=q[1], z=q[2], w=q[3])))

    with Writer(path) as writer:
        conns = {topic: writer.add_connection(topic, kind, typestore=store) for topic, kind in (
            (odom_topic, "nav_msgs/msg/Odometry"), ("/tf_static", "tf2_msgs/msg/TFMessage"),
            (cloud_topic, "sensor_msgs/msg/PointCloud2"))}

        def put(topic, kind, ns, msg):
            writer.write(conns[topic], ns, store.serialize_ros1(msg, kind))

        put("/tf_static", "tf2_msgs/msg/TFMessage", 0, m.make_in(
            store, "tf2_msgs/msg/TFMessage", transforms=[tfs(0, "vehicle", "mbes", p_bs, r_bs)]))
        for ns, p, r in poses:
            q = m.quaternion(r)
            pose = m.make_in(store, "geometry_msgs/msg/Pose", position=m.make_in(
                store, "geometry_msgs/msg/Point", x=p[0], y=p[1], z=p[2]),
                orientation=m.make_in(store, "geometry_msgs/msg/Quaternion",
                                      x=q[0], y=q[1], z=q[2], w=q[3]))
            put(odom_topic, "nav_msgs/msg/Odometry", ns, m.make_in(
                store, "nav_msgs/msg/Odometry", header=header(ns, "world"),
                child_frame_id="vehicle", pose=m.make_in(
                    store, "geometry_msgs/msg/PoseWithCovariance", pose=pose,
                    covariance=np.zeros(36))))
        for k, (ns, ranges) in enumerate(pings):
            hit = np.isfinite(ranges)
            xyz = (d_s[hit] * ranges[hit, None]).astype("<f4")
            fields = [m.make_in(store, "sensor_msgs/msg/PointField", name=k, offset=4 * i,
                                datatype=m.FLOAT32, count=1) for i, k in enumerate("xyz")]
            cloud = dict(header=header(ns + ping_shift, cloud_frame), height=1, width=len(xyz),
                         fields=fields, point_step=12, row_step=12 * len(xyz),
                         data=np.frombuffer(xyz.tobytes(), np.uint8), is_dense=True)
            if corrupt is not None and k == 2:
                cloud.update(corrupt(store, cloud))
            put(cloud_topic, "sensor_msgs/msg/PointCloud2", ns,
                m.make_in(store, "sensor_msgs/msg/PointCloud2", **cloud))
    return path


def test_replay_of_a_ros1_bag_with_other_topics_and_a_static_sonar(tmp_path, capsys):
    bag = _ros1_bag(tmp_path / "vehicle.bag")
    wall = tmp_path / "wall.ply"
    _wall().export(wall)
    out = tmp_path / "out"
    code = main(["replay", str(bag), "-o", str(out), "--topics",
                 "odometry=/nav/odom,multibeam=/mbes/cloud", "--target", str(wall),
                 "--voxel", "0.25"])
    assert code == 0, capsys.readouterr().err
    import json

    report = json.loads((out / "report.json").read_text())
    assert report["log"]["world_frame"] == "world" and report["log"]["base_frame"] == "vehicle"
    assert report["log"]["sources"]["multibeam"]["frames"] == ["mbes"]
    assert report["map"]["occupied_voxels"] > 100
    # the returns land on the wall's face x = 8 (interpolated poses between the samples)
    ply = read_ply(out / "points.ply").points
    assert np.abs(ply[:, 0] - WALL_X).max() < 1e-4
    assert report["reconstruction"]["built"]
    assert report["reconstruction"]["point_cloud"]["accuracy_median_m"] < 0.01
    assert 0.05 < report["coverage"]["point_cloud"] <= 1.0
    assert (out / "reconstruction.ply").is_file() and (out / "map.bt").is_file()


def test_replay_of_a_rosbag2_folder_with_a_laser_scan(tmp_path):
    """A rosbag2 (sqlite3) folder: PoseStamped odometry, a LaserScan on a static mount."""
    from rosbags.rosbag2 import StoragePlugin, Writer

    poses, (p_bs, r_bs), d_s, pings = _vehicle_log()
    folder = tmp_path / "bag2"
    with Writer(folder, version=8, storage_plugin=StoragePlugin.SQLITE3) as writer:
        store = m.typestore()
        conns = {t: writer.add_connection(t, k, typestore=store) for t, k in (
            ("/pose", "geometry_msgs/msg/PoseStamped"), ("/tf_static", "tf2_msgs/msg/TFMessage"),
            ("/scan", "sensor_msgs/msg/LaserScan"))}

        def put(topic, kind, ns, msg):
            writer.write(conns[topic], ns, store.serialize_cdr(msg, kind))

        put("/tf_static", "tf2_msgs/msg/TFMessage", 0, m.tf_message(
            [m.transform(0.0, "base_link", "fls", p_bs, r_bs)]))
        for ns, p, r in poses:
            put("/pose", "geometry_msgs/msg/PoseStamped", ns,
                m.pose_stamped(ns / 1e9, "odom", p, r))
        for ns, ranges in pings:
            put("/scan", "sensor_msgs/msg/LaserScan", ns,
                m.laser_scan(ns / 1e9, "fls", MB_ANGLES, ranges, 20.0, 0.1))
    topics = dict(DEFAULT_TOPICS, odometry="/pose", multibeam="/scan")
    index = open_log(folder, topics, {"odometry", "multibeam"})
    assert index.max_ranges["multibeam"] == 20.0
    replayed = replay(index, map_settings(index, voxel=0.25))
    points = dive_cloud(replayed.scan_log, voxel=1e-6).points
    hits = sum(int(np.isfinite(r).sum()) for _, r in pings)
    assert len(points) == replayed.scan_log.returns == hits
    assert np.abs(points[:, 0] - WALL_X).max() < 1e-4
    # beams without an echo (+inf) cleared free water: more leaves than the returns' alone
    assert replayed.scan_log.count == len(pings)


# --- bad input: one line, exit 2, nothing built --------------------------------------------

@pytest.mark.parametrize("case, topics, needle", [
    ("no odometry", "odometry=/nope", "no odometry topic /nope"),
    ("no returns", "odometry=/nav/odom,multibeam=/none", "no multibeam topic /none"),
    ("wrong type", "odometry=/mbes/cloud,multibeam=/mbes/cloud",
     "odometry topic /mbes/cloud carries sensor_msgs/msg/PointCloud2"),
])
def test_replay_rejects_bad_topics(tmp_path, capsys, case, topics, needle):
    bag = _ros1_bag(tmp_path / "v.bag")
    out = tmp_path / "out"
    assert main(["replay", str(bag), "-o", str(out), "--topics", topics]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and needle in err, err
    assert not (out / "points.ply").exists()


def _field(store, name, offset, datatype=m.FLOAT32):
    return m.make_in(store, "sensor_msgs/msg/PointField", name=name, offset=offset,
                     datatype=datatype, count=1)


@pytest.mark.parametrize("corrupt, needle", [
    (lambda store, c: dict(data=c["data"][:-12]), "not height 1 x row_step"),
    (lambda store, c: dict(point_step=8, row_step=8 * c["width"]),
     "field z at offset 8 overruns point_step 8"),
    (lambda store, c: dict(row_step=12 * c["width"] - 1), "row_step"),
    (lambda store, c: dict(fields=[_field(store, "x", 0, 2), *c["fields"][1:]]),
     "field x is datatype 2 count 1, not FLOAT32 (7) or FLOAT64 (8)"),
    (lambda store, c: dict(fields=c["fields"][:2]), "no field z"),
    (lambda store, c: dict(fields=[*c["fields"], _field(store, "t", 8, 11)]),
     "field t has datatype 11"),
])
def test_replay_rejects_a_cloud_it_cannot_read_before_any_work(tmp_path, capsys, corrupt,
                                                              needle):
    bag = _ros1_bag(tmp_path / "v.bag", corrupt=corrupt)
    out = tmp_path / "out"
    assert main(["replay", str(bag), "-o", str(out), "--topics",
                 "odometry=/nav/odom,multibeam=/mbes/cloud"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "/mbes/cloud message 3" in err and needle in err, err
    assert not out.exists() or not any(out.iterdir())


def test_replay_rejects_returns_without_a_transform_at_their_stamp(tmp_path, capsys):
    bag = _ros1_bag(tmp_path / "v.bag", ping_shift=30 * 10**9)  # stamps after the poses
    out = tmp_path / "out"
    assert main(["replay", str(bag), "-o", str(out), "--topics",
                 "odometry=/nav/odom,multibeam=/mbes/cloud"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert "frame 'mbes' have no transform to 'world' at their stamp" in err, err
    assert not (out / "points.ply").exists()


def test_replay_rejects_returns_in_a_frame_without_a_path_to_the_world(tmp_path, capsys):
    bag = _ros1_bag(tmp_path / "v.bag", cloud_frame="sidescan")  # not in the TF tree
    assert main(["replay", str(bag), "-o", str(tmp_path / "out"), "--topics",
                 "odometry=/nav/odom,multibeam=/mbes/cloud"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert "returns in frame 'sidescan' have no transform to the world frame 'world'" in err


def test_replay_rejects_a_log_without_returns_topics_and_a_truncated_file(boulder, tmp_path,
                                                                           capsys):
    bag = _ros1_bag(tmp_path / "v.bag")
    assert main(["replay", str(bag), "-o", str(tmp_path / "a"), "--topics",
                 "odometry=/nav/odom"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "no returns topic" in err, err
    folder, _ = boulder
    data = (folder / "dive.mcap").read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[:len(data) // 2])
    assert main(["replay", str(cut), "-o", str(tmp_path / "b")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and str(cut) in err, err
    assert not (tmp_path / "b" / "points.ply").exists()


# --- the writer's pieces ------------------------------------------------------------------

def test_templates_write_the_bytes_rosbags_writes():
    q = m.quaternion_rpy(0.1, -0.2, 2.5)
    from drake_auv.vehicle.control import rotation_world_body

    np.testing.assert_allclose(q, m.quaternion(rotation_world_body(0.1, -0.2, 2.5)), atol=1e-15)
    np.testing.assert_allclose(m.rotation_matrix(q), rotation_world_body(0.1, -0.2, 2.5),
                               atol=1e-15)
    ns = m.nanoseconds(12.3)
    odometry = m.odometry(12.3, m.BASE, (1, 2, 3), q, (0.5, 0, 0), (0, 0, 0.1))
    assert bytes(m.odometry_template(m.BASE).cdr(
        (1, 2, 3, *q, 0.5, 0, 0, 0, 0, 0.1), (ns,))) == m.serialize(odometry,
                                                                      "nav_msgs/msg/Odometry")
    tf = m.tf_message([m.transform(12.3, m.MAP, m.BASE, (1, 2, 3), q),
                       m.transform(12.3, m.MAP, m.TRUTH, (4, 5, 6), q)])
    assert bytes(m.tf_template(m.MAP, (m.BASE, m.TRUTH)).cdr(
        (1, 2, 3, *q, 4, 5, 6, *q), (ns, ns))) == m.serialize(tf, "tf2_msgs/msg/TFMessage")
    ranges = np.array([2.0, np.nan, 3.5])
    beams = np.array([[1.0, 0, 0], [0, 1.0, 0], [0.6, 0.8, 0]])
    assert m.CloudWriter("profiler").cdr(12.3, ranges, beams) == m.serialize(
        m.point_cloud(12.3, "profiler", ranges, beams), "sensor_msgs/msg/PointCloud2")
    wide = np.random.default_rng(0).normal(size=(5, 4))  # beams as a strided view
    assert m.CloudWriter("dvl").cdr(0.5, wide[:, 3], wide[:, :3]) == m.serialize(
        m.point_cloud(0.5, "dvl", wide[:, 3], wide[:, :3]), "sensor_msgs/msg/PointCloud2")
    scans = m.ScanWriter("multibeam", 0.1)
    for k, (angles, echoes) in enumerate(((np.linspace(-1, 1, 3), ranges),
                                          (np.linspace(-1, 1, 3), ranges[::-1]),
                                          (np.linspace(-0.5, 0.7, 5), np.arange(5.0)))):
        assert scans.cdr(12.3 + k, angles, echoes, 20.0) == m.serialize(m.laser_scan(
            12.3 + k, "multibeam", angles, echoes, 20.0, 0.1), "sensor_msgs/msg/LaserScan")
    for typename, value in (("std_msgs/msg/Int32", -7), ("std_msgs/msg/Int32", 2**31 - 1),
                            ("std_msgs/msg/Float64", 0.8125)):
        assert m.scalar_cdr(typename, value) == m.serialize(m.scalar(typename, value),
                                                            typename)


def test_marker_points_spliced_into_the_serialisation_decode():
    from mcap.records import Schema
    from mcap_ros2.decoder import DecoderFactory

    points = [np.arange(12.0).reshape(4, 3), np.zeros((0, 3)), np.ones((2, 3))]
    markers = [m.marker(1.0, f"m{k}", m.CUBE_LIST, 0.5, (1, 0, 0, 1), k) for k in range(3)]
    data = m.marker_array_cdr(markers, points)
    typename = "visualization_msgs/msg/MarkerArray"
    decoder = DecoderFactory().decoder_for("cdr", Schema(
        id=1, name=typename, encoding="ros2msg", data=m.msgdef(typename).encode()))
    decoded = decoder(data)
    assert [mk.ns for mk in decoded.markers] == ["m0", "m1", "m2"]
    for mk, expected in zip(decoded.markers, points):
        got = np.array([[p.x, p.y, p.z] for p in mk.points]).reshape(-1, 3)
        np.testing.assert_array_equal(got, expected)
    again = m.typestore().deserialize_cdr(data, typename)
    assert again.markers[2].color.r == 1.0 and len(again.markers[0].points) == 4


def test_recorder_periods_must_be_multiples_of_its_tick(tmp_path):
    from drake_auv.rosio.recorder import McapRecorder
    from drake_auv.rosio.writer import McapLog

    log = McapLog(tmp_path / "x.mcap")
    with pytest.raises(ValueError, match="coverage_period must be a multiple of its tick"):
        McapRecorder(log, {}, coverage_period=0.15)
    log.close()


def test_foxglove_layout_names_the_logs_topics(boulder):
    """Every topic the layout shows is one a dive writes (the replanned sections: with a
    replanning leg, which the capped dive does not reach)."""
    import json
    import re
    from importlib.resources import files

    from drake_auv.rosio.recorder import TOPICS

    layout = json.loads(files("drake_auv.rosio").joinpath("foxglove_layout.json").read_text())
    folder, _ = boulder
    topics = {topic for topic, _, _, _ in _mcap_messages(folder / "dive.mcap")}
    text = json.dumps(layout["configById"])
    named = set(re.findall(r'"(/[a-z_/]+)(?:[."]|\[)', text))
    assert named and named <= topics | {TOPICS["section"]}, named - topics
    panels = set(re.findall(r'"([A-Za-z0-9]+![a-z]+)"', json.dumps(layout["layout"])))
    assert panels == set(layout["configById"])


def test_run_writes_dive_mcap_from_the_mission_key(tmp_path):
    out = tmp_path / "run"
    assert main(["run", "pool", "-o", str(out), "--set", "limits.max_time_s=2", "--set",
                 "outputs.mcap=true", "--no-html", "--quiet"]) == 0
    index = open_log(out / "dive.mcap")
    assert index.sources["multibeam"]["count"] > 10


def test_recorder_alone_with_fixed_inputs(tmp_path):
    """The recorder with `FixValue` inputs: one message per tick, a sonar update written
    once, in its frame with the pose of its update time, a section each time it changes."""
    from pydrake.systems.analysis import Simulator

    from drake_auv.rosio.recorder import McapRecorder
    from drake_auv.rosio.writer import McapLog
    from drake_auv.sonar.beams import SonarMount
    from drake_auv.sonar.returns import SonarReturns
    from drake_auv.vehicle.control import rotation_world_body

    log = McapLog(tmp_path / "r.mcap")
    mount = SonarMount.named("port", (0.3, 0.0, -0.2))
    recorder = McapRecorder(log, {"multibeam": (mount, 0.1, 20.0)}, coverage=("multibeam",),
                            section_input=True)
    context = recorder.CreateDefaultContext()
    estimated = np.array([1.0, 2.0, -3.0, 0.02, -0.01, 0.5, 0.3, 0, 0, 0, 0, 0.01])
    r_nb = rotation_world_body(0.02, -0.01, 0.5)
    d_s = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    d_nav = d_s @ (r_nb @ mount.rotation).T
    origin = estimated[:3] + r_nb @ mount.position
    ranges = np.array([4.0, np.nan])
    points = origin + d_nav * ranges[:, None]
    returns = SonarReturns(0.0, origin, np.zeros(2), ranges, d_nav, points, np.zeros((2, 3)),
                           20.0, 1)
    for port, value in ((recorder.state_input, np.zeros(12)),
                        (recorder.estimated_state_input, estimated),
                        (recorder.reference_input, np.zeros(8)),
                        (recorder.leg_input, [1, 0]), (recorder.response_input, np.zeros(10)),
                        (recorder.thrust_input, np.arange(5.0)),
                        (recorder.coverage_inputs["multibeam"], [0.25])):
        port.FixValue(context, np.asarray(value, dtype=float))
    recorder.returns_inputs["multibeam"].FixValue(context, returns)
    recorder.section_input.FixValue(context, np.zeros((2, 3)) + [[0, 0, -5], [1, 0, -5]])
    simulator = Simulator(recorder, context)
    simulator.AdvanceTo(0.35)  # ticks at 0, 0.1, 0.2, 0.3
    recorder.section_input.FixValue(context, np.zeros((2, 3)) + [[0, 0, -6], [2, 0, -6]])
    simulator.AdvanceTo(0.45)
    log.close()
    decoded = _mcap_messages(tmp_path / "r.mcap")
    counts = Counter(topic for topic, _, _, _ in decoded)
    assert counts["/tf"] == counts["/odometry/navigation"] == counts["/thrust"] == 5
    assert counts["/plan/section"] == 2 and counts["/sonar/multibeam/points"] == 1
    assert counts["/mission/leg"] == 1 and counts["/coverage/multibeam"] == 1
    cloud = next(d for t, _, _, d in decoded if t == "/sonar/multibeam/points")
    assert cloud.header.frame_id == "multibeam" and cloud.width == 2 and not cloud.is_dense
    assert (cloud.header.stamp.sec, cloud.header.stamp.nanosec) == (0, 0)
    data = np.frombuffer(bytes(cloud.data), np.float32, count=3)  # x, y, z of beam 0
    np.testing.assert_allclose(data, [4.0, 0.0, 0.0], atol=1e-6)
    static, dynamic = _tf_lookup(decoded)
    p_bs, r_bs = static["multibeam"][1]
    p_mb, r_mb = dynamic["base_link"][0]
    np.testing.assert_allclose(p_mb + r_mb @ (p_bs + r_bs @ [4.0, 0, 0]), points[0], atol=1e-12)


@pytest.mark.parametrize("compression", ["zstd", "lz4", "none"])
def test_mcap_log_of_many_chunks_reads_back_whole(tmp_path, monkeypatch, compression):
    """Messages spread over many chunks (a 4 kB chunk) come back from the mcap reader (CRCs
    checked, through the summary's indexes and sequentially) and rosbags, in order, with the
    summary's counts."""
    from mcap.reader import make_reader
    from mcap.records import Chunk
    from mcap.stream_reader import StreamReader
    from rosbags.highlevel import AnyReader

    from drake_auv.rosio import writer

    monkeypatch.setattr(writer, "CHUNK_BYTES", 4096)
    rng = np.random.default_rng(3)
    expected = []
    with writer.McapLog(tmp_path / "many.mcap", {"k": 1}, compression) as log:
        for k in range(400):
            t = 0.1 * k
            log.write_cdr("/leg", "std_msgs/msg/Int32", m.scalar_cdr("std_msgs/msg/Int32", k), t)
            expected.append(("/leg", k))
            if k % 3 == 0:
                beams = rng.normal(size=(20, 3))
                beams /= np.linalg.norm(beams, axis=1)[:, None]
                ranges = rng.uniform(1, 9, 20)
                log.write_cdr("/cloud", "sensor_msgs/msg/PointCloud2",
                              m.CloudWriter("dvl").cdr(t, ranges, beams), t)
                expected.append(("/cloud", ranges.astype(np.float32)))
    with open(tmp_path / "many.mcap", "rb") as f:
        reader = make_reader(f, validate_crcs=True)
        summary = reader.get_summary()
        assert summary.statistics.message_count == len(expected)
        assert summary.statistics.chunk_count == len(summary.chunk_indexes) > 10
        assert {summary.channels[c].topic: n for c, n in
                summary.statistics.channel_message_counts.items()} == {"/leg": 400,
                                                                       "/cloud": 134}
        assert {c.compression for c in summary.chunk_indexes} == {
            "" if compression == "none" else compression}
        got = [(channel.topic, message) for _, channel, message in reader.iter_messages()]
        assert {r.name: r.metadata for r in reader.iter_metadata()} == {"drake_auv": {"k": "1"}}
    assert [topic for topic, _ in got] == [topic for topic, _ in expected]
    assert [msg.sequence for topic, msg in got if topic == "/leg"] == list(range(400))
    with open(tmp_path / "many.mcap", "rb") as f:
        chunks = [r for r in StreamReader(f, validate_crcs=True, emit_chunks=True).records
                  if isinstance(r, Chunk)]
    assert len(chunks) == summary.statistics.chunk_count
    with AnyReader([tmp_path / "many.mcap"]) as bag:
        decoded = [(c.topic, bag.deserialize(raw, c.msgtype))
                   for c, _, raw in bag.messages()]
    assert len(decoded) == len(expected)
    for (topic, msg), (want_topic, want) in zip(decoded, expected):
        assert topic == want_topic
        if topic == "/leg":
            assert msg.data == want
        else:
            np.testing.assert_array_equal(
                np.frombuffer(bytes(msg.data), np.float32).reshape(-1, 10)[:, 3], want)


def test_mcap_log_replaces_a_link_and_an_aborted_log_leaves_nothing(tmp_path):
    from drake_auv.rosio.writer import McapLog

    victim = tmp_path / "victim.txt"
    victim.write_text("keep")
    (tmp_path / "dive.mcap").symlink_to(victim)
    log = McapLog(tmp_path / "dive.mcap")
    log.write_cdr("/x", "std_msgs/msg/Float64", m.scalar_cdr("std_msgs/msg/Float64", 1.0), 0.0)
    log.close()
    assert victim.read_text() == "keep" and not (tmp_path / "dive.mcap").is_symlink()
    assert (tmp_path / "dive.mcap").read_bytes()[:8] == b"\x89MCAP0\r\n"
    before = sorted(p.name for p in tmp_path.iterdir())
    with pytest.raises(RuntimeError, match="mid-dive"):
        with McapLog(tmp_path / "other.mcap") as other:
            other.write_cdr("/x", "std_msgs/msg/Float64",
                            m.scalar_cdr("std_msgs/msg/Float64", 1.0), 0.0)
            raise RuntimeError("mid-dive")
    assert other.closed and sorted(p.name for p in tmp_path.iterdir()) == before
    other.close()  # after an abort: nothing to do
    assert sorted(p.name for p in tmp_path.iterdir()) == before


def test_run_mission_aborts_its_log_when_building_or_flying_fails(tmp_path, monkeypatch):
    """A failure while the diagram is built or while the dive flies closes the log's file
    and leaves no dive.mcap (nor its temporary folder)."""
    import drake_auv.mission.runner as runner

    spec = load_mission("pool", overrides=["limits.max_time_s=2"])
    site = load_site(spec.site, spec.seed, label=spec.name)
    real_build = runner.build_mission_diagram

    def failing_build(*args, **kwargs):
        raise RuntimeError("no diagram")

    monkeypatch.setattr(runner, "build_mission_diagram", failing_build)
    log = dive_log(tmp_path / "dive.mcap", spec, site)
    with pytest.raises(RuntimeError, match="no diagram"):
        run_mission(spec, site, progress=False, mcap=log)
    assert log.closed and list(tmp_path.iterdir()) == []
    monkeypatch.setattr(runner, "build_mission_diagram", real_build)

    def probe(context):
        if context.get_time() > 0.5:
            raise RuntimeError("sensor fault")

    log = dive_log(tmp_path / "dive.mcap", spec, site)
    with pytest.raises(RuntimeError, match="sensor fault"):
        run_mission(spec, site, progress=False, mcap=log, probe=probe)
    assert log.closed and list(tmp_path.iterdir()) == []


def test_message_block_writes_the_records_single_writes_do(tmp_path):
    from mcap.reader import make_reader

    from drake_auv.rosio.writer import McapLog, MessageBlock

    templates = [("/tf", m.tf_template(m.MAP, (m.BASE, m.TRUTH))),
                 ("/odometry", m.odometry_template(m.BASE)),
                 ("/thrust", m.array_template(("a", "b", "c")))]
    rng = np.random.default_rng(5)
    ticks = [(0.1 * k, rng.normal(size=14 + 13 + 3).tolist()) for k in range(5)]
    with McapLog(tmp_path / "block.mcap") as log:
        block = MessageBlock(log, templates)
        log.write_cdr("/other", "std_msgs/msg/Int32", m.scalar_cdr("std_msgs/msg/Int32", 3), 0)
        for t, floats in ticks:
            block.write(floats, t)
    with McapLog(tmp_path / "single.mcap") as log:
        log.write_cdr("/other", "std_msgs/msg/Int32", m.scalar_cdr("std_msgs/msg/Int32", 3), 0)
        for t, floats in ticks:
            ns = m.nanoseconds(t)
            for (topic, template), (first, end) in zip(templates, ((0, 14), (14, 27),
                                                                   (27, 30))):
                log.write_cdr(topic, template.typename, template.cdr(
                    floats[first:end], (ns,) * len(template.stamp_offsets)), t)

    def records(name):
        with open(tmp_path / name, "rb") as f:
            return [(channel.topic, message.sequence, message.log_time, message.data)
                    for _, channel, message in make_reader(f).iter_messages()]

    assert records("block.mcap") == records("single.mcap") and len(records("block.mcap")) == 16


def test_an_error_writing_a_chunk_reaches_the_dive_and_drops_the_log(tmp_path, monkeypatch):
    """A chunk that cannot be written (on the log's writing thread) fails the next write or
    the close, and the log is then dropped whole."""
    from drake_auv.rosio import writer

    def full_disk(data):
        raise OSError("No space left on device")

    monkeypatch.setattr(writer, "CHUNK_BYTES", 256)
    monkeypatch.setitem(writer.COMPRESSIONS, "zstd", full_disk)
    with pytest.raises(OSError, match="No space left"):
        with writer.McapLog(tmp_path / "full.mcap") as log:
            for k in range(200):
                log.write_cdr("/x", "std_msgs/msg/Float64",
                              m.scalar_cdr("std_msgs/msg/Float64", k), 0.1 * k)
    assert log.closed and list(tmp_path.iterdir()) == []
    log = writer.McapLog(tmp_path / "late.mcap")
    log.write_cdr("/x", "std_msgs/msg/Float64", m.scalar_cdr("std_msgs/msg/Float64", 1.0), 0)
    with pytest.raises(OSError, match="No space left"):
        log.close()
    assert log.closed and list(tmp_path.iterdir()) == []
