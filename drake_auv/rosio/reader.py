"""A recorded log's vehicle poses, TF tree and sonar returns, read back as the mapper's rays.

`open_log(path, topics)` reads a ROS 1 bag, a rosbag2 folder (sqlite3 or MCAP storage) or an
MCAP file (rosbags' `AnyReader`) once, whole, and checks it before anything is built: the
odometry topic (`nav_msgs/Odometry`, or `geometry_msgs/PoseStamped` of `base_frame`) and at
least one returns topic (`sensor_msgs/PointCloud2` or `LaserScan`) present with those types,
every return's frame linked to the world (the odometry's frame) by the TF tree (`/tf`,
`/tf_static`) and the odometry at its stamp, and the file readable to its end. It keeps the
poses and the transforms (small); `iter_batches` then reads the returns again, one message
at a time, as `ScanBatch`es in the world frame, in the order they were logged (messages of
one log time in the mapper's source order: multibeam, profiler, DVL).

A transform at a stamp between two samples is interpolated (linear position, spherical
rotation), at a sample it is that sample exactly; outside the samples there is none (as tf2,
no extrapolation). A cloud with the `range` and `beam_x beam_y beam_z` fields of
`rosio.messages` gives every beam, those without an echo included; any other cloud gives its
finite points as returns seen from the frame's origin. A `LaserScan` gives its beams in its
frame's x-y plane; a range outside [range_min, range_max] that is +inf is a beam without an
echo, any other is dropped (REP 117).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Iterator

import numpy as np

from drake_auv.mapping.scan_log import ScanBatch
from drake_auv.rosio.messages import rotation_matrix
from drake_auv.sonar.sensor import BUILT_IN

# the odometry and the built-in sources' returns (`rosio.recorder.points_topic`)
DEFAULT_TOPICS = dict(odometry="/odometry/navigation",
                      **{name: f"/sonar/{name}/points" for name in BUILT_IN})
ODOMETRY_TYPES = ("nav_msgs/msg/Odometry", "geometry_msgs/msg/PoseStamped")
RETURNS_TYPES = ("sensor_msgs/msg/PointCloud2", "sensor_msgs/msg/LaserScan")
TF_TOPICS = ("/tf", "/tf_static")
DEFAULT_MAX_RANGE = 20.0  # m, of a sensor whose log states none
_POINT_TYPES = {1: "i1", 2: "u1", 3: "i2", 4: "u2", 5: "i4", 6: "u4", 7: "f4", 8: "f8"}


def parse_topics(text: str | None) -> tuple[dict, set]:
    """`odometry=/a,multibeam=/b,...` over `DEFAULT_TOPICS`; returns (topics, the names
    given)."""
    topics, given = dict(DEFAULT_TOPICS), set()
    for item in (text or "").split(","):
        if not item.strip():
            continue
        key, sep, value = (s.strip() for s in item.partition("="))
        if not sep or key not in DEFAULT_TOPICS or not value:
            raise ValueError(f"--topics takes NAME=/topic pairs with NAME one of "
                             f"{', '.join(DEFAULT_TOPICS)}, got {item.strip()!r}")
        topics[key], _ = value, given.add(key)
    return topics, given


def _frame(name: str) -> str:
    return name.lstrip("/")  # ROS 1 frames may carry a leading slash


def _ns(stamp) -> int:
    return int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec)


@dataclass
class Track:
    """Poses of a frame over time: `times` (n,) ns ascending, `positions` (n, 3),
    `quaternions` (n, 4) (x, y, z, w)."""

    times: np.ndarray
    positions: np.ndarray
    quaternions: np.ndarray

    @classmethod
    def of(cls, samples: list) -> "Track":
        samples = sorted(samples, key=lambda s: s[0])
        times = np.array([s[0] for s in samples], dtype=np.int64)
        return cls(times, np.array([s[1] for s in samples], dtype=float).reshape(-1, 3),
                   np.array([s[2] for s in samples], dtype=float).reshape(-1, 4))

    def covers(self, ns: np.ndarray) -> np.ndarray:
        return (ns >= self.times[0]) & (ns <= self.times[-1]) if len(self.times) else \
            np.zeros(len(ns), bool)

    def at(self, ns: int) -> tuple[np.ndarray, np.ndarray]:
        """(position, R) at `ns` (a sample's exactly, else interpolated; `covers` first)."""
        k = int(np.searchsorted(self.times, ns))
        if k < len(self.times) and self.times[k] == ns:
            return self.positions[k], rotation_matrix(self.quaternions[k])
        t0, t1 = self.times[k - 1], self.times[k]
        w = (ns - t0) / (t1 - t0)
        q0, q1 = self.quaternions[k - 1], self.quaternions[k]
        q1 = -q1 if np.dot(q0, q1) < 0 else q1
        angle = np.arccos(np.clip(np.dot(q0, q1) / np.linalg.norm(q0) / np.linalg.norm(q1),
                                  -1.0, 1.0))
        q = ((1 - w) * q0 + w * q1 if angle < 1e-9 else
             (np.sin((1 - w) * angle) * q0 + np.sin(w * angle) * q1) / np.sin(angle))
        return ((1 - w) * self.positions[k - 1] + w * self.positions[k], rotation_matrix(q))


@dataclass
class LogIndex:
    """What `open_log` read: `world` and `base` frames, the base's `track` in the world,
    the TF edges ({child: (parent, Track or a static (position, R))}), each source's
    topic, frame(s), message type and count, the log's `metadata` (MCAP only) and its
    `max_ranges` ({source: m})."""

    path: Path
    world: str
    base: str
    track: Track
    edges: dict
    sources: dict  # source -> dict(topic, type, count, frames)
    metadata: dict = field(default_factory=dict)
    max_ranges: dict = field(default_factory=dict)

    def sensor_pose(self, frame: str, ns: int) -> tuple[np.ndarray, np.ndarray]:
        """(origin, R_world_frame) of `frame` at `ns` (checked by `open_log`)."""
        position, rotation = np.zeros(3), np.eye(3)
        while frame not in (self.world, self.base):
            parent, edge = self.edges[frame]
            p, r = edge.at(ns) if isinstance(edge, Track) else edge
            position, rotation = p + r @ position, r @ rotation
            frame = parent
        if frame == self.base:
            p, r = self.track.at(ns)
            position, rotation = p + r @ position, r @ rotation
        return position, rotation

    def _chain(self, frame: str) -> list | None:
        """The TF edges from `frame` up to the world or the base (None: no path)."""
        chain, seen = [], set()
        while frame not in (self.world, self.base):
            if frame not in self.edges or frame in seen:
                return None
            seen.add(frame)
            parent, edge = self.edges[frame]
            chain.append(edge)
            frame = parent
        return chain + ([self.track] if frame == self.base else [])


def _reader_errors():
    from rosbags.highlevel import AnyReaderError
    from rosbags.rosbag1 import ReaderError as Bag1Error
    from rosbags.rosbag2 import ReaderError as Bag2Error

    import struct
    return (AnyReaderError, Bag1Error, Bag2Error, EOFError, struct.error, KeyError,
            IndexError, AssertionError, OSError, ValueError)


def _open(path: Path):
    from rosbags.highlevel import AnyReader

    if not path.exists():
        raise FileNotFoundError(f"{path}: no such log (a ROS 1 .bag, a rosbag2 folder or an "
                                f".mcap file)")
    reader = AnyReader([path])
    try:
        reader.open()
    except _reader_errors() as err:
        raise ValueError(f"{path}: not a readable ROS 1 bag, rosbag2 folder or MCAP file "
                         f"({' '.join(str(err).split()) or type(err).__name__})") from None
    return reader


def _mcap_metadata(path: Path) -> dict:
    """The MCAP file's metadata records ({name: {key: value}}), {} for other logs."""
    if not (path.is_file() and path.suffix == ".mcap"):
        return {}
    from mcap.reader import make_reader

    with open(path, "rb") as f:
        try:
            return {m.name: dict(m.metadata) for m in make_reader(f).iter_metadata()}
        except Exception:  # a damaged summary: the messages' pass reports it
            return {}


def open_log(path, topics: dict | None = None, given=(), base_frame: str = "base_link",
             max_range: float | None = None) -> LogIndex:
    """Reads and checks the log at `path` (module doc); `topics` as `DEFAULT_TOPICS` (those
    in `given` must be present; of the others, the present ones are used). `max_range`: the
    sonars' range, m (default: the log's metadata, the LaserScan's range_max, else 20)."""
    path = Path(path)
    topics = dict(DEFAULT_TOPICS if topics is None else topics)
    reader = _open(path)
    try:
        return _index(reader, path, topics, set(given), _frame(base_frame), max_range)
    except _reader_errors() as err:
        if isinstance(err, (ValueError, FileNotFoundError)) and str(err).startswith(str(path)):
            raise
        raise ValueError(f"{path}: unreadable past its start, truncated or damaged "
                         f"({' '.join(str(err).split()) or type(err).__name__})") from None
    finally:
        reader.close()


def _index(reader, path, topics, given, base_frame, max_range) -> LogIndex:
    by_topic: dict[str, list] = {}
    for c in reader.connections:
        by_topic.setdefault(c.topic, []).append(c)
    available = ", ".join(sorted(by_topic)) or "none"

    def typed(name, allowed):
        topic = topics[name]
        conns = by_topic.get(topic)
        if not conns:
            return None
        kinds = {c.msgtype for c in conns}
        if not kinds <= set(allowed):
            raise ValueError(f"{path}: {name} topic {topic} carries {', '.join(sorted(kinds))}"
                             f", not {' or '.join(allowed)}")
        return conns

    odometry = typed("odometry", ODOMETRY_TYPES)
    if odometry is None:
        raise ValueError(f"{path}: no odometry topic {topics['odometry']} (nav_msgs/Odometry "
                         f"or geometry_msgs/PoseStamped); topics in the log: {available}; "
                         f"name it with --topics odometry=TOPIC")
    returns = {}
    for name in BUILT_IN:
        conns = typed(name, RETURNS_TYPES)
        if conns is None and name in given:
            raise ValueError(f"{path}: no {name} topic {topics[name]}; topics in the log: "
                             f"{available}")
        if conns is not None:
            returns[name] = conns
    if not returns:
        raise ValueError(f"{path}: no returns topic ({', '.join(topics[s] for s in BUILT_IN)}: "
                         f"sensor_msgs/PointCloud2 or LaserScan); topics in the log: "
                         f"{available}; name them with --topics multibeam=TOPIC,...")
    tf = [c for t in TF_TOPICS for c in by_topic.get(t, [])
          if c.msgtype == "tf2_msgs/msg/TFMessage"]
    source_of = {c.id: name for name, conns in returns.items() for c in conns}
    odometry_ids = {c.id for c in odometry}
    poses, world, base = [], None, base_frame
    static, dynamic = {}, {}
    stamps = {name: [] for name in returns}
    frames = {name: set() for name in returns}
    types = {name: conns[0].msgtype for name, conns in returns.items()}
    counts = dict.fromkeys(returns, 0)
    max_ranges = {}
    for conn, _, raw in reader.messages(connections=odometry + tf + sum(returns.values(), [])):
        msg = reader.deserialize(raw, conn.msgtype)
        if conn.id in odometry_ids:
            pose = msg.pose.pose if conn.msgtype == ODOMETRY_TYPES[0] else msg.pose
            if conn.msgtype == ODOMETRY_TYPES[0]:
                base = _frame(msg.child_frame_id) or base
            world = world or _frame(msg.header.frame_id)
            poses.append((_ns(msg.header.stamp), (pose.position.x, pose.position.y,
                                                  pose.position.z),
                          (pose.orientation.x, pose.orientation.y, pose.orientation.z,
                           pose.orientation.w)))
        elif conn.id in source_of:
            name = source_of[conn.id]
            if conn.msgtype == RETURNS_TYPES[0]:
                _check_cloud(msg, f"{path}: {conn.topic} message {counts[name] + 1}")
            stamps[name].append(_ns(msg.header.stamp))
            frames[name].add(_frame(msg.header.frame_id))
            counts[name] += 1
            if conn.msgtype == RETURNS_TYPES[1]:
                max_ranges[name] = float(msg.range_max)
        else:
            for t in msg.transforms:
                child, parent = _frame(t.child_frame_id), _frame(t.header.frame_id)
                sample = (_ns(t.header.stamp), (t.transform.translation.x,
                                                t.transform.translation.y,
                                                t.transform.translation.z),
                          (t.transform.rotation.x, t.transform.rotation.y,
                           t.transform.rotation.z, t.transform.rotation.w))
                if conn.topic == "/tf_static":
                    static[child] = (parent, sample)
                else:
                    dynamic.setdefault(child, (parent, []))[1].append(sample)
    if not poses:
        raise ValueError(f"{path}: the odometry topic {topics['odometry']} has no message")
    if not any(counts.values()):
        raise ValueError(f"{path}: the returns topics ({', '.join(topics[s] for s in returns)})"
                         f" have no message")
    edges = {child: (parent, (np.array(s[1], float), rotation_matrix(s[2])))
             for child, (parent, s) in static.items()}
    edges.update({child: (parent, Track.of(samples)) for child, (parent, samples)
                  in dynamic.items() if child not in (base, world)})
    index = LogIndex(path, world, base, Track.of(poses), edges, {}, _mcap_metadata(path))
    sensors = index.metadata.get("sensors", {})
    for name in returns:
        for frame in frames[name]:
            chain = index._chain(frame)
            if chain is None:
                raise ValueError(f"{path}: {topics[name]} returns in frame {frame!r} have no "
                                 f"transform to the world frame {world!r} (no TF path to it "
                                 f"or to {base!r})")
            ns = np.array(stamps[name], dtype=np.int64)
            for edge in chain:
                if isinstance(edge, Track) and not edge.covers(ns).all():
                    bad = int(ns[~edge.covers(ns)][0])
                    raise ValueError(f"{path}: {topics[name]} returns at {bad / 1e9:.3f} s in "
                                     f"frame {frame!r} have no transform to {world!r} at their"
                                     f" stamp (poses from {edge.times[0] / 1e9:.3f} to "
                                     f"{edge.times[-1] / 1e9:.3f} s)")
        index.sources[name] = dict(topic=topics[name], type=types[name], count=counts[name],
                                   frames=sorted(frames[name]))
        logged = sensors.get(f"{name}_max_range_m")
        index.max_ranges[name] = float(max_range if max_range is not None
                                       else logged if logged is not None
                                       else max_ranges.get(name, DEFAULT_MAX_RANGE))
    return index


_FLOAT_TYPES = (7, 8)  # PointField FLOAT32, FLOAT64


def _check_cloud(msg, where: str) -> None:
    """Raises ValueError (one line, starting with `where`) unless the `PointCloud2` `msg` is
    one `cloud_beams` reads: fields `x y z` (and `range beam_x beam_y beam_z` when there)
    floating point (PointField 7 FLOAT32 or 8 FLOAT64), count 1; every field of a known
    datatype (1-8) and inside `point_step`; `row_step` >= `width * point_step`; `data` of
    `height * row_step` bytes; `is_bigendian` a boolean."""
    names = {f.name: f for f in msg.fields}
    width, height = int(msg.width), int(msg.height)
    step, row = int(msg.point_step), int(msg.row_step)
    problem = None
    missing = [n for n in ("x", "y", "z") if n not in names]
    beams = [n for n in ("range", "beam_x", "beam_y", "beam_z") if n in names]
    if missing:
        problem = f"no field {', '.join(missing)} (x, y, z are needed)"
    elif msg.is_bigendian not in (True, False, 0, 1):
        problem = f"is_bigendian {msg.is_bigendian!r} is not a boolean"
    for f in msg.fields:
        if problem:
            break
        if f.datatype not in _POINT_TYPES:
            problem = f"field {f.name} has datatype {f.datatype}, not one of 1-8"
        elif f.name in ("x", "y", "z", *beams) and (f.datatype not in _FLOAT_TYPES
                                                     or f.count != 1):
            problem = (f"field {f.name} is datatype {f.datatype} count {f.count}, not "
                       f"FLOAT32 (7) or FLOAT64 (8) count 1")
        elif f.offset + np.dtype(_POINT_TYPES[f.datatype]).itemsize * max(f.count, 1) > step:
            problem = f"field {f.name} at offset {f.offset} overruns point_step {step}"
    if not problem and row < width * step:
        problem = f"row_step {row} < width {width} x point_step {step}"
    if not problem and len(msg.data) != height * row:
        problem = (f"data has {len(msg.data)} bytes, not height {height} x row_step {row} = "
                   f"{height * row}")
    if problem:
        raise ValueError(f"{where}: a PointCloud2 whose layout cannot be read: {problem}")


def cloud_beams(msg) -> tuple[np.ndarray, np.ndarray]:
    """(directions (n, 3) unit, ranges (n,) m, NaN: no echo) of a `PointCloud2` in its own
    frame (module doc)."""
    order = ">" if msg.is_bigendian else "<"
    names = {f.name: f for f in msg.fields}
    dtype = np.dtype({"names": list(names), "formats": [
        order + _POINT_TYPES[f.datatype] for f in names.values()],
        "offsets": [f.offset for f in names.values()], "itemsize": msg.point_step})
    n = int(msg.width) * int(msg.height)
    data = np.frombuffer(np.asarray(msg.data, np.uint8).tobytes(), dtype, count=n,
                         offset=0) if msg.row_step == msg.width * msg.point_step else \
        np.concatenate([np.frombuffer(np.asarray(msg.data, np.uint8)[
            r * msg.row_step:r * msg.row_step + msg.width * msg.point_step].tobytes(), dtype)
            for r in range(msg.height)])
    if {"range", "beam_x", "beam_y", "beam_z"} <= names.keys():
        directions = np.column_stack([data["beam_x"], data["beam_y"], data["beam_z"]])
        return directions.astype(float), data["range"].astype(float)
    points = np.column_stack([data["x"], data["y"], data["z"]]).astype(float)
    ranges = np.linalg.norm(points, axis=1)
    keep = np.isfinite(ranges) & (ranges > 0)
    return points[keep] / ranges[keep, None], ranges[keep]


def scan_beams(msg) -> tuple[np.ndarray, np.ndarray]:
    """(directions (n, 3), ranges (n,), NaN: no echo) of a `LaserScan` in its frame."""
    ranges = np.asarray(msg.ranges, dtype=float)
    angles = msg.angle_min + msg.angle_increment * np.arange(len(ranges))
    hit = (ranges >= msg.range_min) & (ranges <= msg.range_max)
    keep = hit | (ranges == np.inf)
    directions = np.column_stack([np.cos(angles), np.sin(angles), np.zeros(len(angles))])
    return directions[keep], np.where(hit, ranges, np.nan)[keep]


def iter_batches(index: LogIndex, multibeam_stride: int = 1) -> Iterator[ScanBatch]:
    """The log's returns as `ScanBatch`es in the world frame (module doc), every
    `multibeam_stride`-th multibeam beam (as the mapper records them)."""
    reader = _open(index.path)
    try:
        wanted = {c.id: name for c in reader.connections for name, s in index.sources.items()
                  if c.topic == s["topic"]}
        group, group_time = [], None
        for conn, log_time, raw in reader.messages(
                connections=[c for c in reader.connections if c.id in wanted]):
            if group and log_time != group_time:
                yield from _batches(index, group, multibeam_stride)
                group = []
            group_time = log_time
            group.append((BUILT_IN.index(wanted[conn.id]), len(group),
                          reader.deserialize(raw, conn.msgtype)))
        yield from _batches(index, group, multibeam_stride)
    finally:
        reader.close()


def _batches(index, group, stride) -> Iterator[ScanBatch]:
    for source, _, msg in sorted(group, key=lambda g: g[:2]):
        name = BUILT_IN[source]
        directions, ranges = (scan_beams(msg) if hasattr(msg, "angle_min")
                              else cloud_beams(msg))
        if name == "multibeam":
            directions, ranges = directions[::stride], ranges[::stride]
        if not len(ranges):
            continue
        ns = _ns(msg.header.stamp)
        origin, rotation = index.sensor_pose(_frame(msg.header.frame_id), ns)
        yield ScanBatch.make(ns / 1e9, name, origin, directions @ rotation.T, ranges,
                             index.max_ranges[name])
