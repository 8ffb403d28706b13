"""The recorded point cloud of a dive: every sonar return with its sensor origin, time and source.

Built from the mapper's `ScanLog`, so in the NAVIGATION frame (where the vehicle believed the
returns were, drift included), metres, seconds. Files: binary little-endian PLY (`write_ply`,
`read_ply`, which also reads ASCII and big-endian PLY of other tools) with vertex properties
`x y z` (float64), `origin_x origin_y origin_z` (float64), `time` (float64, s) and `source`
(uint8, index into the cloud's `source_names`, which a header comment lists: `comment drake_auv
sonar returns; source: 0 multibeam, 1 profiler, 2 dvl, ...`); LAS/LAZ through the optional `laspy`
(`write_las`, `read_las`). Pure numpy, no Drake.
"""

from __future__ import annotations

import importlib
import itertools
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from drake_auv.mapping.scan_log import ScanLog
from drake_auv.output_files import open_replacing, replacing
from drake_auv.sonar.sensor import BUILT_IN

POSITION = ("x", "y", "z")
ORIGIN = ("origin_x", "origin_y", "origin_z")
_PLY_TYPES = {"char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1", "short": "i2",
              "int16": "i2", "ushort": "u2", "uint16": "u2", "int": "i4", "int32": "i4",
              "uint": "u4", "uint32": "u4", "float": "f4", "float32": "f4", "double": "f8",
              "float64": "f8"}
_PLY_FORMATS = {"binary_little_endian": "<", "binary_big_endian": ">", "ascii": None}
_SOURCES_COMMENT = "drake_auv sonar returns; source: "


@dataclass(frozen=True, eq=False)
class PointCloud:
    """n sonar returns.

    Attributes:
        points: (n, 3) return positions, m. origins: (n, 3) sensor origin of each return, m
            (NaN rows when unknown, e.g. a PLY of another tool). times: (n,) s (NaN unknown).
        sources: (n,) uint8 index into `source_names`.
        source_names: the sensors' names (a `ScanLog`'s `sources`: the built-in ones, 0
            multibeam, 1 profiler, 2 dvl, then a mission's configured sensors).
    """

    points: np.ndarray
    origins: np.ndarray
    times: np.ndarray
    sources: np.ndarray
    source_names: tuple = BUILT_IN

    def __post_init__(self):
        n = len(self.points)
        if np.shape(self.points) != (n, 3) or np.shape(self.origins) != (n, 3) \
                or np.shape(self.times) != (n,) or np.shape(self.sources) != (n,):
            raise ValueError("PointCloud: points and origins must be (n, 3), times and sources "
                             f"(n,); got {np.shape(self.points)}, {np.shape(self.origins)}, "
                             f"{np.shape(self.times)}, {np.shape(self.sources)}")
        if not np.all(np.isfinite(self.points)):
            raise ValueError("PointCloud: point positions must be finite (no NaN or inf)")

    def __len__(self) -> int:
        return len(self.points)

    @property
    def has_origins(self) -> bool:
        return len(self) > 0 and bool(np.all(np.isfinite(self.origins)))

    def subset(self, mask) -> "PointCloud":
        """The returns selected by a boolean mask or index array."""
        return PointCloud(self.points[mask], self.origins[mask], self.times[mask],
                          self.sources[mask], self.source_names)

    def shifted(self, convert) -> "PointCloud":
        """The cloud with points and origins mapped by `convert` ((n, 3) -> (n, 3)), e.g.
        `site.to_site` from the local frame to the site's coordinates."""
        return PointCloud(convert(self.points), convert(self.origins), self.times, self.sources,
                          self.source_names)

    def crop(self, lo, hi, margin: float = 0.0) -> "PointCloud":
        """The returns inside the axis-aligned box [lo - margin, hi + margin], m."""
        lo, hi = np.asarray(lo, float) - margin, np.asarray(hi, float) + margin
        return self.subset(np.all((self.points >= lo) & (self.points <= hi), axis=1))

    def thin(self, voxel: float) -> "PointCloud":
        """One return per cube of side `voxel` m (the earliest), keeping its origin and time.
        The cubes are a grid fixed in the frame, so thinning parts of a cloud and then their
        union gives the thinned whole."""
        if not voxel > 0:
            raise ValueError(f"thin: voxel must be > 0 m, got {voxel}")
        keys = np.floor(self.points / voxel).astype(np.int64)
        _, first = np.unique(keys, axis=0, return_index=True)
        return self.subset(np.sort(first))


def from_scan_log(log: ScanLog, sources=None) -> PointCloud:
    """The returns (beams with a finite range) of every batch in `log` from the named
    `sources` (None: all of the log's), in the log's frame (navigation)."""
    wanted = {log.sources.index(s) for s in (log.sources if sources is None else sources)}
    parts = []
    for batch in log.batches():
        if batch.source not in wanted:
            continue
        hit = np.isfinite(batch.ranges)
        n = int(hit.sum())
        if n:
            parts.append((batch.points(), np.broadcast_to(batch.origin, (n, 3)),
                          np.full(n, batch.time), np.full(n, batch.source, np.uint8)))
    if not parts:
        return PointCloud(np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0), np.zeros(0, np.uint8),
                          log.sources)
    points, origins, times, srcs = (np.concatenate(p) for p in zip(*parts))
    return PointCloud(points.astype(float), origins.astype(float), times, srcs, log.sources)


def write_ply(cloud: PointCloud, filename) -> None:
    """Writes `cloud` as a binary little-endian PLY (vertex properties in the module doc)."""
    write_ply_chunks([cloud], len(cloud), filename, cloud.source_names)


def write_ply_chunks(clouds, count: int, filename, source_names=BUILT_IN) -> None:
    """Writes the `clouds` (an iterable of `PointCloud`, `count` points in all, indexing
    `source_names`) one after the other as one binary little-endian PLY, holding one chunk in
    memory at a time."""
    dtype = np.dtype([(name, "<f8") for name in POSITION + ORIGIN + ("time",)]
                     + [("source", "u1")])
    header = ["ply", "format binary_little_endian 1.0",
              "comment " + _SOURCES_COMMENT + ", ".join(
                  f"{k} {s}" for k, s in enumerate(source_names)),
              f"element vertex {count}"]
    header += [f"property double {name}" for name in POSITION + ORIGIN + ("time",)]
    header += ["property uchar source", "end_header"]
    written = 0
    with open_replacing(filename, "wb") as f:
        f.write(("\n".join(header) + "\n").encode("ascii"))
        for cloud in clouds:
            data = np.empty(len(cloud), dtype)
            for k, name in enumerate(POSITION):
                data[name] = cloud.points[:, k]
                data[ORIGIN[k]] = cloud.origins[:, k]
            data["time"], data["source"] = cloud.times, cloud.sources
            f.write(data.tobytes())
            written += len(cloud)
        if written != count:
            raise ValueError(f"{filename}: {written} points written, the header says {count}")


def _ply_header(f, filename):
    """(format, [(element, count, [(type, name)])], lines, source names) of a PLY header,
    `lines` the number of header lines, the source names those of its sources comment
    (`BUILT_IN` without one); `f` left after it."""
    if f.readline().strip() != b"ply":
        raise ValueError(f"{filename}: not a PLY file (no 'ply' magic line)")
    fmt, elements, lines, names = None, [], 1, BUILT_IN
    while True:
        line = f.readline()
        lines += 1
        if not line:
            raise ValueError(f"{filename}: corrupt PLY, the header has no end_header")
        text = line.decode("ascii", errors="replace")
        words = text.split()
        if words[:1] == ["comment"] and _SOURCES_COMMENT in text:
            names = tuple(item.split()[-1] for item in
                          text.split(_SOURCES_COMMENT, 1)[1].split(","))
        if not words or words[0] in ("comment", "obj_info"):
            continue
        if words[0] == "end_header":
            break
        if words[0] == "format" and len(words) >= 2 and words[1] in _PLY_FORMATS:
            fmt = words[1]
        elif words[0] == "element" and len(words) == 3 and words[2].isdigit():
            elements.append((words[1], int(words[2]), []))
        elif words[0] == "property" and elements and len(words) == 3 \
                and words[1] in _PLY_TYPES:
            elements[-1][2].append((_PLY_TYPES[words[1]], words[2]))
        elif words[0] == "property" and elements and words[1] == "list":
            elements[-1][2].append(("list", words[-1]))
        else:
            raise ValueError(f"{filename}: line {lines}: corrupt PLY header line "
                             f"{line.decode('ascii', errors='replace').strip()!r}")
    if fmt is None:
        raise ValueError(f"{filename}: the PLY header has no (known) format line")
    return fmt, elements, lines, names


def _ascii_rows(f, path, n: int, width: int, first_line: int) -> np.ndarray:
    """(n, width) values of the next n lines of an ASCII PLY body (file line `first_line` on);
    ValueError naming the file and line of the first short, long or non-numeric row."""
    lines = list(itertools.islice(f, n))
    if len(lines) < n:
        raise ValueError(f"{path}: corrupt or truncated PLY, {len(lines)} vertex rows where the "
                         f"header says {n}")
    try:
        return np.loadtxt(lines, ndmin=2).reshape(n, width)
    except ValueError:
        pass  # find the offending row for the message
    for k, line in enumerate(lines):
        line = line.decode("ascii", errors="replace")
        words = line.split()
        try:
            values = [float(w) for w in words]
        except ValueError:
            raise ValueError(f"{path}: line {first_line + k}: vertex row {k} holds a value that "
                             f"is not a number: {line.strip()[:80]!r}") from None
        if len(values) != width:
            raise ValueError(f"{path}: line {first_line + k}: vertex row {k} has {len(values)} "
                             f"values, the header's properties are {width}")
    raise ValueError(f"{path}: the ASCII vertex rows do not parse")


def read_ply(filename) -> PointCloud:
    """Reads the `vertex` element of a PLY file (binary either endianness or ASCII): positions
    `x y z` are required; `origin_*`, `time` and `source` are read when present (NaN origins
    and times, source 0 otherwise). The header's vertex count is checked against the file's
    size before anything is allocated."""
    path = Path(filename)
    if not path.is_file():
        raise FileNotFoundError(f"point cloud {path} does not exist")
    with open(path, "rb") as f:
        fmt, elements, header_lines, source_names = _ply_header(f, path)
        if not elements or elements[0][0] != "vertex":
            raise ValueError(f"{path}: the PLY's first element must be 'vertex', got "
                             f"{[e[0] for e in elements]}")
        _, n, props = elements[0]
        names = [name for _, name in props]
        missing = [c for c in POSITION if c not in names]
        if missing:
            raise ValueError(f"{path}: the PLY's vertices have no position property "
                             f"{', '.join(missing)} (properties: {', '.join(names) or 'none'})")
        if any(t == "list" for t, _ in props):
            raise ValueError(f"{path}: list properties in the vertex element are not supported")
        body = path.stat().st_size - f.tell()
        # An ASCII value takes at least 2 bytes (a digit and a separator).
        row_bytes = 2 * len(props) if fmt == "ascii" else \
            np.dtype([(name, t) for t, name in props]).itemsize
        if n * row_bytes > body:
            raise ValueError(f"{path}: corrupt or truncated PLY, the header says {n} vertices "
                             f"({n * row_bytes} bytes at least) but the file has {body} bytes "
                             "after it")
        if fmt == "ascii":
            rows = _ascii_rows(f, path, n, len(props), header_lines + 1) if n \
                else np.zeros((0, len(props)))
            column = {name: rows[:, k] for k, name in enumerate(names)}
        else:
            dtype = np.dtype([(name, _PLY_FORMATS[fmt] + t) for t, name in props])
            data = np.frombuffer(f.read(n * dtype.itemsize), dtype)
            column = {name: data[name].astype(float) for name in names}

    def stack(keys):
        if all(k in column for k in keys):
            return np.column_stack([column[k] for k in keys])
        return np.full((n, 3), np.nan)

    points = stack(POSITION)
    if not np.all(np.isfinite(points)):
        raise ValueError(f"{path}: the PLY has non-finite vertex positions")
    return PointCloud(points, stack(ORIGIN), column.get("time", np.full(n, np.nan)),
                      column.get("source", np.zeros(n)).astype(np.uint8), source_names)


def optional_module(name: str, needed_for: str, package: str):
    """`import name`, a package of the reconstruct extra. ValueError, one line: to install it
    when it is missing; its own import error (e.g. a system library it links) when it is
    installed but does not load, since reinstalling would change nothing then."""
    try:
        return importlib.import_module(name)
    except ModuleNotFoundError as err:
        if err.name == name:
            raise ValueError(f"{needed_for} needs the optional {package} package, which is not "
                             "installed: pip install 'drake_auv[reconstruct]'") from None
        error = err
    except Exception as err:  # anything its import raises makes it unusable: say what
        error = err
    raise ValueError(f"{needed_for}: {name} is installed but does not import: "
                     f"{type(error).__name__}: {' '.join(str(error).split())}")


def _laspy():
    return optional_module("laspy", "LAS/LAZ files", "laspy")


def write_las(cloud: PointCloud, filename, scale: float = 1e-3) -> None:
    """Writes `cloud` as LAS 1.4 (point format 6; `.laz` needs laspy's lazrs backend):
    positions at `scale` m resolution, `gps_time` the time, `point_source_id` the source, and
    extra dimensions origin_x, origin_y, origin_z (float64)."""
    laspy = _laspy()
    header = laspy.LasHeader(point_format=6, version="1.4")
    header.offsets = np.floor(cloud.points.min(axis=0)) if len(cloud) else np.zeros(3)
    header.scales = np.full(3, scale)
    header.add_extra_dims([laspy.ExtraBytesParams(name=name, type=np.float64)
                           for name in ORIGIN])
    las = laspy.LasData(header)
    las.x, las.y, las.z = cloud.points.T
    las.gps_time = cloud.times
    las.point_source_id = cloud.sources.astype(np.uint16)
    for k, name in enumerate(ORIGIN):
        las[name] = cloud.origins[:, k]
    with replacing(filename) as temporary:
        las.write(str(temporary))


def read_las(filename) -> PointCloud:
    """Reads a LAS/LAZ file written by `write_las` (or any LAS: origins NaN when absent)."""
    laspy = _laspy()
    path = Path(filename)
    if not path.is_file():
        raise FileNotFoundError(f"point cloud {path} does not exist")
    try:
        las = laspy.read(str(path))
    except Exception as err:  # laspy raises its own error types for corrupt files
        raise ValueError(f"{path}: not a readable LAS/LAZ file ({err})") from err
    n = len(las.points)
    extra = set(las.point_format.extra_dimension_names)
    origins = (np.column_stack([np.asarray(las[name], float) for name in ORIGIN])
               if extra.issuperset(ORIGIN) else np.full((n, 3), np.nan))
    times = (np.asarray(las.gps_time, float) if "gps_time" in las.point_format.dimension_names
             else np.full(n, np.nan))
    return PointCloud(np.column_stack([np.asarray(las.x), np.asarray(las.y), np.asarray(las.z)]),
                      origins, times, np.asarray(las.point_source_id).astype(np.uint8))


def read_point_cloud(filename) -> PointCloud:
    """`read_ply` or `read_las` by the file's extension (.ply, .las, .laz)."""
    suffix = Path(filename).suffix.lower()
    if suffix in (".las", ".laz"):
        return read_las(filename)
    if suffix == ".ply":
        return read_ply(filename)
    raise ValueError(f"{filename}: unknown point-cloud extension {suffix!r} "
                     "(use .ply, .las or .laz)")


def write_point_cloud(cloud: PointCloud, filename) -> None:
    """`write_ply` or `write_las` by the file's extension (.ply, .las, .laz)."""
    suffix = Path(filename).suffix.lower()
    if suffix in (".las", ".laz"):
        write_las(cloud, filename)
    elif suffix == ".ply":
        write_ply(cloud, filename)
    else:
        raise ValueError(f"{filename}: unknown point-cloud extension {suffix!r} "
                         "(use .ply, .las or .laz)")
