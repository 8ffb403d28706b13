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
import math
import struct

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
    cls, defaults = _layout(store, typename)
    for name, default in defaults:
        if name not in fields:
            fields[name] = default()
    return cls(**fields)


@functools.cache
def _layout(store, typename: str):
    """(class, [(field, zero-value factory)]) of `typename` in `store`."""
    defaults = []
    for name, (kind, spec) in store.fielddefs[typename][1]:
        if kind == 1:  # a base type: (name, string bound)
            value = "" if spec[0] == "string" else (False if spec[0] == "bool" else 0)
            defaults.append((name, lambda value=value: value))
        elif kind == 2:  # a message
            defaults.append((name, functools.partial(make_in, store, spec)))
        elif kind == 3:  # a fixed array
            base, length = spec
            defaults.append((name, functools.partial(np.zeros, length, _NUMPY.get(
                base[1][0], float))) if base[0] == 1 else
                (name, lambda s=base[1], n=length: [make_in(store, s) for _ in range(n)]))
        else:  # a sequence
            base = spec[0]
            defaults.append((name, functools.partial(np.zeros, 0, _NUMPY[base[1][0]]))
                            if base[0] == 1 and base[1][0] in _NUMPY else (name, list))
    return store.types[typename], defaults


_NUMPY = {"float64": np.float64, "float32": np.float32, "uint8": np.uint8, "int8": np.int8,
          "int32": np.int32, "uint32": np.uint32, "int16": np.int16, "uint16": np.uint16,
          "int64": np.int64, "uint64": np.uint64}


class CdrTemplate:
    """A message of fixed layout serialised once, its numbers written into a copy per message.

    `build(floats, stamps, counts)` makes the message from `n_floats` float64 values,
    `n_stamps` `builtin_interfaces/Time`s and `n_counts` uint32 values; it is built once with
    sentinel values, serialised by rosbags, and each sentinel's bytes located (each must
    occur once). `cdr(floats, stamps_ns, counts)` then packs the values at those offsets:
    the bytes rosbags would write for the same message, at a few microseconds a message (the
    recorder writes several each tick)."""

    def __init__(self, typename: str, build, n_floats: int, n_stamps: int = 1,
                 n_counts: int = 0):
        self.typename, self.n_floats = typename, n_floats
        floats = [float(np.float64(-1.2345678e301) * (1.0 + 1e-9 * k)) for k in range(n_floats)]
        stamps = [(0x5E_C0_00_00 + k, 0x3A_5E_C0_00 + k) for k in range(n_stamps)]
        counts = [0x7C_0A_70_00 + k for k in range(n_counts)]
        data = serialize(build(floats, [make("builtin_interfaces/msg/Time", sec=sec, nanosec=ns)
                                        for sec, ns in stamps], counts), typename)
        self.float_runs = _runs([self._find(data, _F64.pack(v)) for v in floats])
        self.stamp_offsets = [self._find(data, _STAMP.pack(*v)) for v in stamps]
        self._counts = [self._find(data, _U32.pack(v)) for v in counts]
        self.data = bytes(data)

    def _find(self, data: bytes, mark: bytes) -> int:
        at = data.find(mark)
        if at < 0 or data.find(mark, at + 1) >= 0:
            raise ValueError(f"CdrTemplate({self.typename}): a value must occur once")
        return at

    def cdr(self, floats=(), stamps_ns=(), counts=()) -> bytearray:
        buf = bytearray(self.data)
        for packer, at, first, end in self.float_runs:
            packer.pack_into(buf, at, *floats[first:end])
        for at, ns in zip(self.stamp_offsets, stamps_ns):
            _STAMP.pack_into(buf, at, ns // 1_000_000_000, ns % 1_000_000_000)
        for at, value in zip(self._counts, counts):
            _U32.pack_into(buf, at, value)
        return buf


def _runs(offsets) -> list:
    """[(struct of k float64, offset, first, end)]: the floats first..end-1 lie back to back
    from `offset` (one `pack_into` each run)."""
    runs = []
    for k, at in enumerate(offsets):
        if runs and at == runs[-1][1] + 8 * (k - runs[-1][2]):
            runs[-1][3] = k + 1
        else:
            runs.append([None, at, k, k + 1])
    return [(struct.Struct(f"<{end - first}d"), at, first, end) for _, at, first, end in runs]


_F64, _STAMP, _U32 = struct.Struct("<d"), struct.Struct("<iI"), struct.Struct("<I")


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


def header(t, frame: str):
    """`std_msgs/Header`; `t` s, or a `builtin_interfaces/Time`."""
    return make("std_msgs/msg/Header", stamp=t if hasattr(t, "nanosec") else stamp(t),
                frame_id=frame)


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


def quaternion_rpy(roll: float, pitch: float, yaw: float) -> tuple:
    """(x, y, z, w) of R = Rz(yaw) Ry(pitch) Rx(roll) (the vehicle's attitude), w >= 0."""
    cr, sr = math.cos(0.5 * roll), math.sin(0.5 * roll)
    cp, sp = math.cos(0.5 * pitch), math.sin(0.5 * pitch)
    cy, sy = math.cos(0.5 * yaw), math.sin(0.5 * yaw)
    q = (sr * cp * cy - cr * sp * sy, cr * sp * cy + sr * cp * sy,
         cr * cp * sy - sr * sp * cy, cr * cp * cy + sr * sp * sy)
    return tuple(-v for v in q) if q[3] < 0 else q


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


def _as_quaternion(rotation):
    """A 3x3 rotation or an (x, y, z, w) quaternion as a quaternion."""
    return quaternion(rotation) if np.ndim(rotation) == 2 else rotation


def pose(position, rotation):
    """`geometry_msgs/Pose`; `rotation` a 3x3 matrix or an (x, y, z, w) quaternion."""
    return make("geometry_msgs/msg/Pose", position=_vector("geometry_msgs/msg/Point", position),
                orientation=_quaternion_msg(_as_quaternion(rotation)))


def transform(t: float, parent: str, child: str, position, rotation):
    """`geometry_msgs/TransformStamped`: `child`'s pose in `parent` (position m, rotation
    R_parent_child as a 3x3 matrix or an (x, y, z, w) quaternion)."""
    return make("geometry_msgs/msg/TransformStamped", header=header(t, parent),
                child_frame_id=child, transform=make(
                    "geometry_msgs/msg/Transform",
                    translation=_vector("geometry_msgs/msg/Vector3", position),
                    rotation=_quaternion_msg(_as_quaternion(rotation))))


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


def tf_template(parent: str, children) -> CdrTemplate:
    """`/tf` of `children` in `parent`: floats per child (x, y, z, qx, qy, qz, qw), one
    stamp per child."""
    return CdrTemplate("tf2_msgs/msg/TFMessage", lambda f, s, _: tf_message(
        transform(s[k], parent, child, f[7 * k:7 * k + 3], f[7 * k + 3:7 * k + 7])
        for k, child in enumerate(children)), 7 * len(children), len(children))


def odometry_template(child: str) -> CdrTemplate:
    """`nav_msgs/Odometry` of `child` in `map`: floats (x, y, z, qx, qy, qz, qw, u, v, w, p,
    q, r)."""
    return CdrTemplate("nav_msgs/msg/Odometry", lambda f, s, _: odometry(
        s[0], child, f[:3], f[3:7], f[7:10], f[10:13]), 13)


def pose_template(frame: str) -> CdrTemplate:
    """`geometry_msgs/PoseStamped` in `frame`: floats (x, y, z, qx, qy, qz, qw)."""
    return CdrTemplate("geometry_msgs/msg/PoseStamped",
                       lambda f, s, _: pose_stamped(s[0], frame, f[:3], f[3:7]), 7)


def array_template(labels) -> CdrTemplate:
    """`std_msgs/Float64MultiArray` of len(labels) values (no stamp)."""
    return CdrTemplate("std_msgs/msg/Float64MultiArray",
                       lambda f, s, _: float_array(f, labels), len(labels), 0)


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


def _cloud_fields():
    return [make("sensor_msgs/msg/PointField", name=name, offset=_CLOUD_DTYPE.fields[name][1],
                 datatype=kind, count=1) for name, kind in CLOUD_FIELDS]


def cloud_data(ranges, beams_sensor) -> np.ndarray:
    """The (n,) records (`CLOUD_FIELDS`) of n beams: `ranges` (n,) m, NaN without echo;
    `beams_sensor` (n, 3) unit directions in the sensor frame."""
    ranges = np.asarray(ranges, dtype=float)
    beams = np.ascontiguousarray(np.asarray(beams_sensor, dtype="<f8").reshape(-1, 3))
    n = len(ranges)
    singles = np.empty((n, 4), "<f4")
    np.multiply(beams, ranges[:, None], out=singles[:, :3], casting="same_kind")  # NaN: no echo
    singles[:, 3] = ranges
    data = np.empty((n, _CLOUD_DTYPE.itemsize), np.uint8)
    data[:, :16] = singles.view(np.uint8)
    data[:, 16:] = beams.view(np.uint8).reshape(n, 24)
    return data.view(_CLOUD_DTYPE).reshape(n)


def point_cloud(t: float, frame: str, ranges, beams_sensor):
    """The organised `sensor_msgs/PointCloud2` of one sonar update (module doc): `ranges` (n,)
    m, NaN without echo; `beams_sensor` (n, 3) unit directions in the sensor frame."""
    data = cloud_data(ranges, beams_sensor)
    return make("sensor_msgs/msg/PointCloud2", header=header(t, frame), height=1,
                width=len(data), fields=_cloud_fields(), is_bigendian=False,
                point_step=_CLOUD_DTYPE.itemsize, row_step=_CLOUD_DTYPE.itemsize * len(data),
                data=np.frombuffer(data.tobytes(), np.uint8),
                is_dense=bool(np.isfinite(data["range"]).all()))


class CloudWriter:
    """`point_cloud`'s CDR bytes in `frame` without building the message: the part before
    `data` is a `CdrTemplate` (stamp, width, row_step); `data` (uint8[], no alignment) and
    `is_dense` (bool) end the message."""

    def __init__(self, frame: str):
        self._template = CdrTemplate("sensor_msgs/msg/PointCloud2", lambda f, s, c: make(
            "sensor_msgs/msg/PointCloud2", header=header(s[0], frame), height=1, width=c[0],
            fields=_cloud_fields(), is_bigendian=False, point_step=_CLOUD_DTYPE.itemsize,
            row_step=c[1], data=np.zeros(0, np.uint8), is_dense=False), 0, 1, 2)
        self._prefix_bytes = len(self._template.data) - 5  # an empty data's length, is_dense

    def cdr(self, t: float, ranges, beams_sensor) -> bytes:
        data = cloud_data(ranges, beams_sensor)
        head = self._template.cdr((), (nanoseconds(t),), (len(data), data.nbytes))
        return b"".join((head[:self._prefix_bytes], _U32.pack(data.nbytes), data.view(np.uint8),
                         b"\x01" if np.isfinite(data["range"]).all() else b"\x00"))


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


class ScanWriter:
    """`laser_scan`'s CDR bytes in `frame` without building the message: the part before
    `ranges` (the fan, the range limits, `period`) is a `CdrTemplate` (the stamp), rebuilt
    when the fan changes; `ranges` (float32[]) and the empty `intensities` end the message
    (4-aligned whatever their length)."""

    def __init__(self, frame: str, period: float):
        self.frame, self.period = frame, float(period)
        self._fan = self._template = None

    def cdr(self, t: float, angles, ranges, max_range: float) -> bytes:
        fan = (float(angles[0]), float(angles[-1]), len(angles), float(max_range))
        if fan != self._fan:
            self._fan, angles = fan, np.array(angles, dtype=float)
            self._template = CdrTemplate("sensor_msgs/msg/LaserScan", lambda f, s, c: laser_scan(
                s[0], self.frame, angles, np.zeros(0), max_range, self.period), 0, 1)
        head = self._template.cdr((), (nanoseconds(t),))
        ranges = np.where(np.isfinite(ranges), ranges, np.inf).astype("<f4")
        return b"".join((head[:-8], _U32.pack(len(ranges)), ranges.tobytes(), bytes(4)))


def scalar(typename: str, value):
    """A std_msgs scalar (`std_msgs/msg/Float64`, `Int32`)."""
    return make(typename, data=value)


_SCALARS = {"std_msgs/msg/Int32": struct.Struct("<4si"),
            "std_msgs/msg/Float64": struct.Struct("<4sd")}
_LITTLE_ENDIAN_CDR = b"\x00\x01\x00\x00"  # the encapsulation header


def scalar_cdr(typename: str, value) -> bytes:
    """`scalar`'s CDR bytes (`_SCALARS`' types): the header, then the value (at offset 0 of
    the body, aligned whatever its size)."""
    return _SCALARS[typename].pack(_LITTLE_ENDIAN_CDR, value)


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


def _sentinel(k: int) -> np.ndarray:
    """A point no marker holds, unique to marker k of an array: its bytes mark where the
    serialised points go."""
    return np.array([1.0e300 + k * 1.0e286, -7.0e299, 3.0e298])


def marker(t: float, ns: str, kind: int, scale, rgba, marker_id: int = 0):
    """A `visualization_msgs/Marker` in `map` (identity pose) whose points are given to
    `marker_array_cdr`: kind 6 CUBE_LIST (a cube of edge `scale` at each), 11 TRIANGLE_LIST
    (each three a triangle)."""
    return make("visualization_msgs/msg/Marker", header=header(t, MAP), ns=ns, id=marker_id,
                type=kind, action=0, pose=pose(np.zeros(3), np.eye(3)),
                scale=_vector("geometry_msgs/msg/Vector3", np.broadcast_to(scale, 3)),
                color=_colour(rgba))


CUBE_LIST, TRIANGLE_LIST = 6, 11


def marker_array_cdr(markers, points) -> bytes:
    """CDR bytes of a `visualization_msgs/MarkerArray` of `markers` (from `marker`), marker k
    with the (n_k, 3) `points[k]`, m. rosbags serialises the markers with one sentinel point
    each, whose 24 bytes are then replaced by the n_k points' float64 bytes and its sequence
    length by n_k: a sequence of float64 triples ends 8-aligned whatever its length, so the
    rest of the message keeps its alignment (a million points without a million objects)."""
    cls = typestore().types["geometry_msgs/msg/Point"]
    for k, msg in enumerate(markers):
        msg.points = [cls(*_sentinel(k))]
    data = serialize(make("visualization_msgs/msg/MarkerArray", markers=list(markers)),
                     "visualization_msgs/msg/MarkerArray")
    pieces, done = [], 0
    for k, array in enumerate(points):
        at = data.index(_sentinel(k).astype("<f8").tobytes(), done)
        count = at - 4 if data[at - 4:at] == b"\x01\x00\x00\x00" else at - 8
        array = np.ascontiguousarray(np.asarray(array, dtype="<f8").reshape(-1, 3))
        pieces += [data[done:count], _U32.pack(len(array)), data[count + 4:at],
                   array.reshape(-1).view(np.uint8)]
        done = at + 24
    return b"".join([*pieces, data[done:]])  # one copy of the points


def mesh_corners(vertices, faces) -> np.ndarray:
    """The (3 m, 3) corners of a mesh's m faces, in order: a TRIANGLE_LIST's points."""
    return np.asarray(vertices, float)[np.asarray(faces).reshape(-1)]
