"""ROS 2 messages of a dive, built from numpy arrays (rosbags' ROS 2 Humble types; no Drake).

Frames (REP 103 / REP 105): `map` is the mission's local world frame, ENU (x east, y north, z
up, sea surface z = 0; the site's CRS origin is in the log's metadata); `base_link` is the
vehicle as its navigation believes it (what every sonar return is placed with, as on a real
vehicle), `base_link_truth` the simulated true pose; both FLU (x forward, y left, z up), the
project's own body frame, so nothing is converted. Each sonar has a fixed frame on `base_link`
(`/tf_static`): its mount's position and rotation, with the scan plane its x-y plane (beam
angle 0 along x, positive towards y).

A sonar update becomes one organised `sensor_msgs/PointCloud2` (height 1, one column per beam)
in the sensor's frame with the fields `x y z` (float32, the return, NaN where the beam had no
echo: `is_dense` false), `range` (float32, m, NaN: no echo) and `beam_x beam_y beam_z`
(float64, the beam's unit direction in the sensor frame). The last three let a replay rebuild
the beams exactly, those without an echo included (they clear free water in the octree); a
consumer that reads x, y, z alone (Foxglove, PCL, octomap_server) sees the returns.
Stamps are simulated time (s from the dive's start) as `builtin_interfaces/Time`.
"""

from __future__ import annotations

import functools

import numpy as np
from rosbags.typesys import Stores, get_typestore

MAP, BASE, TRUTH = "map", "base_link", "base_link_truth"
# sensor_msgs/PointField datatypes
FLOAT32, FLOAT64 = 7, 8
CLOUD_FIELDS = (("x", FLOAT32), ("y", FLOAT32), ("z", FLOAT32), ("range", FLOAT32),
                ("beam_x", FLOAT64), ("beam_y", FLOAT64), ("beam_z", FLOAT64))
_CLOUD_DTYPE = np.dtype([("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("range", "<f4"),
                         ("beam_x", "<f8"), ("beam_y", "<f8"), ("beam_z", "<f8")])


@functools.cache
def typestore():
    """rosbags' ROS 2 Humble type store (the types and their `ros2msg` definitions)."""
    return get_typestore(Stores.ROS2_HUMBLE)


def msgdef(typename: str) -> str:
    """The `ros2msg` schema text of `typename` ('nav_msgs/msg/Odometry'), its dependencies
    appended as rosbag2 writes them."""
    return typestore().generate_msgdef(typename, ros_version=2)[0]


def serialize(message, typename: str) -> bytes:
    """CDR (little endian) bytes of `message`."""
    return bytes(typestore().serialize_cdr(message, typename))


def make(typename: str, **fields):
    """A message of `typename` with `fields`, every other field zero or empty."""
    return make_in(typestore(), typename, **fields)


def make_in(store, typename: str, **fields):
    """`make` with the types of another rosbags type store (ROS 1 Noetic's, say)."""
    cls = store.types[typename]
    values = {}
    for name, (kind, spec) in store.fielddefs[typename][1]:
        if name in fields:
            values[name] = fields[name]
        elif kind == 1:  # a base type: (name, string bound)
            values[name] = "" if spec[0] == "string" else (False if spec[0] == "bool" else 0)
        elif kind == 2:  # a message
            values[name] = make_in(store, spec)
        elif kind == 3:  # a fixed array
            base, length = spec
            values[name] = (np.zeros(length, _NUMPY.get(base[1][0], float)) if base[0] == 1
                            else [make_in(store, base[1]) for _ in range(length)])
        else:  # a sequence
            base = spec[0]
            values[name] = (np.zeros(0, _NUMPY[base[1][0]]) if base[0] == 1
                            and base[1][0] in _NUMPY else [])
    return cls(**values)


_NUMPY = {"float64": np.float64, "float32": np.float32, "uint8": np.uint8, "int8": np.int8,
          "int32": np.int32, "uint32": np.uint32, "int16": np.int16, "uint16": np.uint16,
          "int64": np.int64, "uint64": np.uint64}


def nanoseconds(t: float) -> int:
    """Simulated time `t` (s) as integer nanoseconds (the MCAP log time)."""
    return int(round(float(t) * 1e9))


def stamp(t: float):
    """`builtin_interfaces/Time` of `t` s."""
    ns = nanoseconds(t)
    return make("builtin_interfaces/msg/Time", sec=ns // 1_000_000_000,
                nanosec=ns % 1_000_000_000)


def seconds(time_msg) -> float:
    """s of a `builtin_interfaces/Time`."""
    return time_msg.sec + 1e-9 * time_msg.nanosec


def header(t: float, frame: str):
    return make("std_msgs/msg/Header", stamp=stamp(t), frame_id=frame)


def quaternion(rotation: np.ndarray) -> np.ndarray:
    """(x, y, z, w) unit quaternion of a 3x3 rotation matrix, w >= 0."""
    m = np.asarray(rotation, dtype=float)
    trace = np.trace(m)
    if trace > 0:
        s = 2.0 * np.sqrt(trace + 1.0)
        q = np.array([(m[2, 1] - m[1, 2]) / s, (m[0, 2] - m[2, 0]) / s,
                      (m[1, 0] - m[0, 1]) / s, 0.25 * s])
    else:
        i = int(np.argmax(np.diag(m)))
        j, k = (i + 1) % 3, (i + 2) % 3
        s = 2.0 * np.sqrt(1.0 + m[i, i] - m[j, j] - m[k, k])
        q = np.empty(4)
        q[i], q[j], q[k] = 0.25 * s, (m[j, i] + m[i, j]) / s, (m[k, i] + m[i, k]) / s
        q[3] = (m[k, j] - m[j, k]) / s
    q /= np.linalg.norm(q)
    return -q if q[3] < 0 else q


def rotation_matrix(q) -> np.ndarray:
    """3x3 rotation of an (x, y, z, w) quaternion (normalised first)."""
    x, y, z, w = np.asarray(q, dtype=float) / np.linalg.norm(q)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def _vector(typename: str, v):
    return make(typename, x=float(v[0]), y=float(v[1]), z=float(v[2]))


def _quaternion_msg(q):
    return make("geometry_msgs/msg/Quaternion", x=float(q[0]), y=float(q[1]), z=float(q[2]),
                w=float(q[3]))


def pose(position, rotation):
    return make("geometry_msgs/msg/Pose", position=_vector("geometry_msgs/msg/Point", position),
                orientation=_quaternion_msg(quaternion(rotation)))


def transform(t: float, parent: str, child: str, position, rotation):
    """`geometry_msgs/TransformStamped`: `child`'s pose in `parent` (position m, rotation
    R_parent_child)."""
    return make("geometry_msgs/msg/TransformStamped", header=header(t, parent),
                child_frame_id=child, transform=make(
                    "geometry_msgs/msg/Transform",
                    translation=_vector("geometry_msgs/msg/Vector3", position),
                    rotation=_quaternion_msg(quaternion(rotation))))


def tf_message(transforms):
    return make("tf2_msgs/msg/TFMessage", transforms=list(transforms))


def odometry(t: float, child: str, position, rotation, linear_body, angular_body):
    """`nav_msgs/Odometry` of `child` in `map`; the twist in `child` (body FLU), m/s, rad/s.
    The covariances are zero (unknown)."""
    return make("nav_msgs/msg/Odometry", header=header(t, MAP), child_frame_id=child,
                pose=make("geometry_msgs/msg/PoseWithCovariance", pose=pose(position, rotation),
                          covariance=np.zeros(36)),
                twist=make("geometry_msgs/msg/TwistWithCovariance", twist=make(
                    "geometry_msgs/msg/Twist",
                    linear=_vector("geometry_msgs/msg/Vector3", linear_body),
                    angular=_vector("geometry_msgs/msg/Vector3", angular_body)),
                    covariance=np.zeros(36)))


def pose_stamped(t: float, frame: str, position, rotation):
    return make("geometry_msgs/msg/PoseStamped", header=header(t, frame),
                pose=pose(position, rotation))


def path(t: float, frame: str, points, yaws=None):
    """`nav_msgs/Path` through (n, 3) `points`, each pose heading along `yaws` (rad, default
    towards the next point)."""
    points = np.asarray(points, dtype=float).reshape(-1, 3)
    if yaws is None:
        step = np.diff(points[:, :2], axis=0)
        yaws = np.arctan2(step[:, 1], step[:, 0]) if len(step) else np.zeros(0)
        yaws = np.r_[yaws, yaws[-1:] if len(yaws) else np.zeros(len(points))]
    h = header(t, frame)
    poses = [make("geometry_msgs/msg/PoseStamped", header=h, pose=pose(
        p, _yaw_rotation(yaw))) for p, yaw in zip(points, yaws)]
    return make("nav_msgs/msg/Path", header=h, poses=poses)


def _yaw_rotation(yaw: float) -> np.ndarray:
    c, s = np.cos(yaw), np.sin(yaw)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def point_cloud(t: float, frame: str, ranges, beams_sensor):
    """The organised `sensor_msgs/PointCloud2` of one sonar update (module doc): `ranges` (n,)
    m, NaN without echo; `beams_sensor` (n, 3) unit directions in the sensor frame."""
    ranges = np.asarray(ranges, dtype=float)
    beams = np.asarray(beams_sensor, dtype=float).reshape(-1, 3)
    data = np.empty(len(ranges), _CLOUD_DTYPE)
    points = beams * ranges[:, None]  # NaN rows where no echo
    data["x"], data["y"], data["z"] = points.T
    data["range"] = ranges
    data["beam_x"], data["beam_y"], data["beam_z"] = beams.T
    fields = [make("sensor_msgs/msg/PointField", name=name, offset=_CLOUD_DTYPE.fields[name][1],
                   datatype=kind, count=1) for name, kind in CLOUD_FIELDS]
    return make("sensor_msgs/msg/PointCloud2", header=header(t, frame), height=1,
                width=len(ranges), fields=fields, is_bigendian=False,
                point_step=_CLOUD_DTYPE.itemsize, row_step=_CLOUD_DTYPE.itemsize * len(ranges),
                data=np.frombuffer(data.tobytes(), np.uint8),
                is_dense=bool(np.isfinite(ranges).all()))


def laser_scan(t: float, frame: str, angles, ranges, max_range: float, period: float):
    """`sensor_msgs/LaserScan` of an equiangular fan in the sensor's x-y plane; a beam without
    echo is +inf (REP 117)."""
    angles = np.asarray(angles, dtype=float)
    increment = float((angles[-1] - angles[0]) / (len(angles) - 1)) if len(angles) > 1 else 0.0
    return make("sensor_msgs/msg/LaserScan", header=header(t, frame),
                angle_min=float(angles[0]), angle_max=float(angles[-1]),
                angle_increment=increment, time_increment=0.0, scan_time=float(period),
                range_min=0.0, range_max=float(max_range),
                ranges=np.where(np.isfinite(ranges), ranges, np.inf).astype(np.float32),
                intensities=np.zeros(0, np.float32))


def scalar(typename: str, value):
    """A std_msgs scalar (`std_msgs/msg/Float64`, `Int32`)."""
    return make(typename, data=value)


def float_array(values, labels):
    """`std_msgs/Float64MultiArray` with one labelled dimension."""
    dim = make("std_msgs/msg/MultiArrayDimension", label=",".join(labels), size=len(values),
               stride=len(values))
    return make("std_msgs/msg/Float64MultiArray",
                layout=make("std_msgs/msg/MultiArrayLayout", dim=[dim], data_offset=0),
                data=np.asarray(values, dtype=np.float64))


def _colour(rgba):
    return make("std_msgs/msg/ColorRGBA", r=float(rgba[0]), g=float(rgba[1]), b=float(rgba[2]),
                a=float(rgba[3]))


def _points(array):
    cls = typestore().types["geometry_msgs/msg/Point"]
    return [cls(x=float(x), y=float(y), z=float(z)) for x, y, z in np.asarray(array, float)]


def marker(t: float, ns: str, kind: int, points, scale, rgba, marker_id: int = 0):
    """A `visualization_msgs/Marker` in `map` (identity pose) of (n, 3) `points`: kind 6
    CUBE_LIST (a cube of edge `scale` at each), 11 TRIANGLE_LIST (each three a triangle)."""
    return make("visualization_msgs/msg/Marker", header=header(t, MAP), ns=ns, id=marker_id,
                type=kind, action=0, pose=pose(np.zeros(3), np.eye(3)),
                scale=_vector("geometry_msgs/msg/Vector3", np.broadcast_to(scale, 3)),
                color=_colour(rgba), points=_points(points))


CUBE_LIST, TRIANGLE_LIST = 6, 11


def mesh_marker(t: float, ns: str, vertices, faces, rgba):
    """A TRIANGLE_LIST marker of a triangle mesh (its faces' corners in order)."""
    corners = np.asarray(vertices, float)[np.asarray(faces).reshape(-1)]
    return marker(t, ns, TRIANGLE_LIST, corners, 1.0, rgba)


def marker_array(markers):
    return make("visualization_msgs/msg/MarkerArray", markers=list(markers))
