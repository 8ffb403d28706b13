"""The coverage path: ordered 3D samples with heading, sensor direction and segment label.

A `PlannedPath` is what every planner returns and what the vehicle diagrams consume. It is pure numpy;
the conversion to a Drake trajectory imports pydrake lazily so planning never needs Drake.
Frames: world, z up, metres; heading is the yaw of the body x axis about world z, radians.
"""

from __future__ import annotations

import csv
import io
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from drake_auv.fixed_decimal import fixed_decimal_rows
from drake_auv.output_files import open_replacing
from drake_auv.planning.polyline import arc_length
from drake_auv.resources import map_chunks

_CSV_FIELDS = ("x", "y", "z", "heading", "sensor_x", "sensor_y", "sensor_z", "label")


@dataclass(frozen=True)
class PlannedPath:
    """Ordered samples of a path in the world frame.

    Attributes:
        points: (N, 3) positions, m.
        heading: (N,) yaw of the body x axis, rad. Independent of the direction of motion:
            a hovering vehicle can look one way and move another.
        sensor_dir: (N, 3) unit vectors, the payload sensor axis in the world frame.
        labels: (N,) segment labels such as "planar", "slice", "transit".
    """

    points: np.ndarray
    heading: np.ndarray
    sensor_dir: np.ndarray
    labels: np.ndarray = field(default=None)

    def __post_init__(self):
        self._validate(copy=True)

    @classmethod
    def adopt(cls, points, heading, sensor_dir, labels) -> "PlannedPath":
        """A PlannedPath that takes ownership of freshly built, full-shape arrays without copying
        them (they become read-only): for planners assembling millions of samples."""
        path = cls.__new__(cls)
        for name, value in (("points", points), ("heading", heading),
                            ("sensor_dir", sensor_dir), ("labels", labels)):
            object.__setattr__(path, name, value)
        path._validate(copy=False)
        return path

    def _validate(self, copy: bool) -> None:
        points = np.array(self.points, dtype=float, copy=copy or None)
        if points.ndim != 2 or points.shape[1] != 3:
            raise ValueError(f"PlannedPath.points must have shape (N, 3), got {points.shape}")
        n = len(points)
        if n < 1:
            raise ValueError("PlannedPath.points is empty: a path needs at least one sample")

        def full(value, shape, dtype):
            value = np.asarray(value, dtype=dtype)
            if not copy and value.shape == shape:
                return value
            return np.broadcast_to(value, shape).copy()

        heading = full(self.heading, (n,), float)
        sensor_dir = full(self.sensor_dir, (n, 3), float)
        labels = full(self.labels if self.labels is not None else "path", (n,), object)
        if not (np.all(np.isfinite(points)) and np.all(np.isfinite(heading))):
            raise ValueError("PlannedPath.points and PlannedPath.heading must be finite (no NaN or inf)")
        norms = np.linalg.norm(sensor_dir, axis=1)
        if np.any(~np.isfinite(norms)) or np.any(norms < 1e-9):
            raise ValueError("PlannedPath.sensor_dir must hold finite non-zero vectors")
        sensor_dir /= norms[:, None]
        for name, value in (("points", points), ("heading", heading),
                            ("sensor_dir", sensor_dir), ("labels", labels)):
            value.setflags(write=False)
            object.__setattr__(self, name, value)

    def __len__(self) -> int:
        return len(self.points)

    def __deepcopy__(self, memo):
        return self  # immutable: frozen, read-only arrays (a Drake source's copies are free)

    @classmethod
    def concatenate(cls, paths: list["PlannedPath"]) -> "PlannedPath":
        """Joins paths end to start, in order."""
        paths = [p for p in paths if p is not None and len(p) > 0]
        if not paths:
            raise ValueError("PlannedPath.concatenate needs at least one non-empty path")
        return cls(np.vstack([p.points for p in paths]),
                   np.concatenate([p.heading for p in paths]),
                   np.vstack([p.sensor_dir for p in paths]),
                   np.concatenate([p.labels for p in paths]))

    def segment_lengths(self) -> np.ndarray:
        """(N - 1,) Euclidean distances between consecutive samples, m (read-only, computed
        once: the path is immutable, and the metrics and reports ask for them many times)."""
        seg = self.__dict__.get("_segment_lengths")
        if seg is None:
            seg = np.linalg.norm(np.diff(self.points, axis=0), axis=1)
            seg.setflags(write=False)
            object.__setattr__(self, "_segment_lengths", seg)
        return seg

    def arc_length(self) -> np.ndarray:
        """(N,) cumulative distance along the path from its first sample, m."""
        return arc_length(self.points)

    @property
    def length(self) -> float:
        """Total length, m."""
        return float(self.segment_lengths().sum())

    def length_by_label(self) -> dict[str, float]:
        """Length of the segments per label, m; a segment takes the label of its end sample."""
        seg = self.segment_lengths()
        return {str(lab): float(seg[self.labels[1:] == lab].sum())
                for lab in dict.fromkeys(self.labels.tolist())}

    def label_codes(self) -> tuple[list[str], np.ndarray]:
        """(names, codes): the distinct labels in sorted order and (N,) each sample's index
        into them (what `np.unique(labels, return_inverse=True)` gives, without sorting the
        samples' strings)."""
        names = sorted(set(self.labels.tolist()))
        codes = np.zeros(len(self.labels), dtype=np.intp)
        for k, name in enumerate(names[1:], start=1):
            codes[self.labels == name] = k
        return names, codes

    def select(self, mask) -> "PlannedPath":
        """The samples where `mask` (booleans, or indices) selects, in order."""
        mask = np.asarray(mask)
        return PlannedPath(self.points[mask], self.heading[mask], self.sensor_dir[mask], self.labels[mask])

    def resample(self, spacing: float) -> "PlannedPath":
        """Samples every `spacing` metres along the path, keeping every original vertex.

        Headings are interpolated on the unit circle, sensor directions linearly then
        normalised; a new sample takes the label of the segment's end vertex.
        """
        if not spacing > 0:
            raise ValueError(f"resample spacing must be > 0 m, got {spacing}")
        if len(self) < 2:
            return self
        seg = self.segment_lengths()
        counts = np.maximum(np.ceil(seg / spacing).astype(int), 1)
        starts = np.repeat(np.arange(len(seg)), counts)
        offsets = np.concatenate([np.arange(c) / c for c in counts])
        idx0, idx1, t = starts, starts + 1, offsets
        points = self.points[idx0] + t[:, None] * (self.points[idx1] - self.points[idx0])
        dh = np.angle(np.exp(1j * (self.heading[idx1] - self.heading[idx0])))
        heading = self.heading[idx0] + t * dh
        sensor = self.sensor_dir[idx0] + t[:, None] * (self.sensor_dir[idx1] - self.sensor_dir[idx0])
        degenerate = np.linalg.norm(sensor, axis=1) < 1e-9
        sensor[degenerate] = self.sensor_dir[idx1][degenerate]
        labels = np.where(t == 0, self.labels[idx0], self.labels[idx1])
        return PlannedPath(np.vstack([points, self.points[-1]]), np.append(heading, self.heading[-1]),
                    np.vstack([sensor, self.sensor_dir[-1]]), np.append(labels, self.labels[-1]))

    def times(self, speed: float, yaw_rate: float = np.radians(15.0)) -> np.ndarray:
        """(N,) arrival time at each sample, s, at constant `speed` (m/s).

        A segment takes the longer of its travel time and the time to turn the heading at
        `yaw_rate` (rad/s), so a turn in place is not commanded instantaneously.
        """
        if not speed > 0:
            raise ValueError(f"speed must be > 0 m/s, got {speed}")
        if not yaw_rate > 0:
            raise ValueError(f"yaw_rate must be > 0 rad/s, got {yaw_rate}")
        dh = np.abs(np.angle(np.exp(1j * np.diff(self.heading))))
        dt = np.maximum(self.segment_lengths() / speed, dh / yaw_rate)
        dt = np.maximum(dt, 1e-3)  # coincident samples still need increasing times
        return np.concatenate([[0.0], np.cumsum(dt)])

    def unwrapped_heading(self) -> np.ndarray:
        """(N,) heading without 2 pi jumps, for interpolation."""
        return np.unwrap(self.heading)

    def to_trajectory(self, speed: float, yaw_rate: float = np.radians(15.0),
                      yaw0: float | None = None):
        """A Drake `PiecewisePolynomial` of [x, y, z, yaw] through the samples (first-order
        hold), timed by `times` from t = 0 (`shiftRight` moves it; a single sample is held 1 s).

        The yaw is unwrapped, and with `yaw0` (rad) shifted by whole turns to start nearest it
        (so a trajectory joined after another does not spin). Feed it to
        `TrajectorySource(traj, output_derivative_order=1)` to get the 8-vector reference
        [x, y, z, yaw, vx, vy, vz, yaw_rate] the tracker takes.
        """
        from pydrake.trajectories import PiecewisePolynomial

        t = self.times(speed, yaw_rate)
        yaw = self.unwrapped_heading()
        if yaw0 is not None:
            yaw = yaw + 2.0 * np.pi * np.round((yaw0 - yaw[0]) / (2.0 * np.pi))
        samples = np.vstack([self.points.T, yaw])
        if len(t) == 1:
            t = np.array([t[0], t[0] + 1.0])
            samples = np.hstack([samples, samples])
        return PiecewisePolynomial.FirstOrderHold(t, samples)

    @classmethod
    def chain_trajectory(cls, paths: list["PlannedPath"], speed: float,
                         yaw_rate: float = np.radians(15.0)):
        """One `PiecewisePolynomial` of [x, y, z, yaw] through `paths` in order, from t = 0:
        each path's own trajectory (`to_trajectory`) shifted to where the one before ends,
        joined by the segment from its last sample to the next one's first (timed like any
        segment), the yaw continuous across the joins. The same timing as `to_trajectory` of
        the concatenated path, built from the pieces' trajectories."""
        pieces = [paths[0]]
        for a, b in zip(paths, paths[1:]):
            pieces += [cls.concatenate([a.select([-1]), b.select([0])]), b]
        pieces = [p for p in pieces if len(p) >= 2] or pieces[:1]
        trajectory = pieces[0].to_trajectory(speed, yaw_rate)
        for piece in pieces[1:]:
            end = trajectory.end_time()
            part = piece.to_trajectory(speed, yaw_rate, yaw0=float(trajectory.value(end)[3, 0]))
            part.shiftRight(end)
            trajectory.ConcatenateInTime(part)
        return trajectory

    def to_csv(self, filename, chunk: int = 65536) -> None:
        """Writes one row per sample with the columns x, y, z, heading, sensor_x/y/z, label
        (numbers with 6 decimals; the bytes `csv.writer` writes), `chunk` rows at a time on
        the usable cores (`fixed_decimal.fixed_decimal_rows`: numpy's digits, not a Python
        call per number)."""
        values = np.column_stack([self.points, self.heading, self.sensor_dir])
        names, code = self.label_codes()
        tails = []
        for name in names:  # ",label\r\n" as csv.writer quotes the label
            buf = io.StringIO()
            csv.writer(buf).writerow(["", name])
            tails.append(buf.getvalue().encode())
        tails = np.array(tails, dtype=bytes)
        rows = map_chunks(lambda k: fixed_decimal_rows(values[k], 6, tails[code[k]]),
                          len(values), chunk)
        with open_replacing(filename, "wb") as f:
            f.write((",".join(_CSV_FIELDS) + "\r\n").encode())
            f.writelines(rows)

    @classmethod
    def from_csv(cls, filename) -> "PlannedPath":
        """Reads a file written by `to_csv`; names the file and row of any malformed entry."""
        filename = Path(filename)
        if not filename.is_file():
            raise FileNotFoundError(f"path CSV not found: {filename}")
        with open(filename, newline="") as f:
            reader = csv.reader(f)
            header = next(reader, None)
            if header is None or tuple(header) != _CSV_FIELDS:
                raise ValueError(f"{filename}: header must be {','.join(_CSV_FIELDS)}, "
                                 f"got {header}")
            rows = list(reader)
        values, labels = [], []
        for i, row in enumerate(rows, start=2):
            if len(row) != len(_CSV_FIELDS):
                raise ValueError(f"{filename}:{i}: expected {len(_CSV_FIELDS)} columns, "
                                 f"got {len(row)}")
            try:
                values.append([float(v) for v in row[:7]])
            except ValueError as err:
                raise ValueError(f"{filename}:{i}: {err}") from None
            labels.append(row[7])
        if not values:
            raise ValueError(f"{filename}: no samples")
        values = np.array(values)
        return cls(values[:, :3], values[:, 3], values[:, 4:7], np.array(labels, dtype=object))
