"""The vectorised fixed-point text equals C's printf byte for byte, the hard cases included."""

import csv
import io

import numpy as np
import pytest

from drake_auv.fixed_decimal import fixed_decimal_fields, fixed_decimal_rows
from drake_auv.planning import PlannedPath


def _hard_values():
    rng = np.random.default_rng(7)
    ties = (np.arange(-50, 50) + 0.5) * 1e-6  # halves of the last place, as decimals
    binary_ties = np.array([1, 3, 5, 127, 1001]) / 128.0  # exact halves of the sixth decimal
    near = np.repeat([0.0000005, 2.5e-6, 9.9999995, 123456.0000005], 5)
    near = near + np.tile(np.arange(-2, 3), 4) * np.spacing(near)
    return np.concatenate([
        rng.normal(0.0, 1000.0, 20000), rng.normal(0.0, 1.0, 20000),
        rng.uniform(-1.0, 1.0, 5000) * 1e-6, np.round(rng.normal(0, 100, 5000), 6) + 5e-7,
        ties, binary_ties, -binary_ties, near, -near,
        [0.0, -0.0, 1e-300, -1e-300, 4.5e9, -4.5e9, 2.0 ** 49 / 1e6, 1e15, -1e15, 1e300,
         np.inf, -np.inf, np.nan]])


@pytest.mark.parametrize("decimals", [1, 3, 6, 9])
def test_fields_equal_printf(decimals):
    values = _hard_values()
    fields = fixed_decimal_fields(values, decimals)
    assert fields.shape[1] == len(values)
    for value, column in zip(values.tolist(), fields.T):
        assert bytes(column[column != 0]) == b"%.*f" % (decimals, value), value


def test_rows_equal_the_row_format():
    rng = np.random.default_rng(3)
    values = rng.normal(0.0, 300.0, (500, 4))
    values[7, 2] = -0.0
    tails = np.array([b",a\r\n", b',"b,c"\r\n'])[rng.integers(0, 2, 500)]
    want = "".join(("%.6f,%.6f,%.6f,%.6f" % tuple(r)) + t.decode()
                   for r, t in zip(values.tolist(), tails))
    assert fixed_decimal_rows(values, 6, tails) == want.encode()
    assert fixed_decimal_rows(np.zeros((0, 4)), 6, np.zeros(0, dtype="S4")) == b""


def test_decimals_out_of_range_are_refused():
    with pytest.raises(ValueError, match=r"\[1, 9\]"):
        fixed_decimal_fields(np.zeros(3), 0)


def test_path_csv_is_what_csv_writer_writes(tmp_path):
    rng = np.random.default_rng(5)
    n = 3000
    points = rng.normal(0.0, 500.0, (n, 3))
    labels = np.array(["planar", "slice", "transit", 'odd,"label'], dtype=object)[
        rng.integers(0, 4, n)]
    path = PlannedPath(points, rng.uniform(-np.pi, np.pi, n), rng.normal(size=(n, 3)), labels)
    path.to_csv(tmp_path / "p.csv", chunk=1000)
    buf = io.StringIO(newline="")
    writer = csv.writer(buf)
    writer.writerow(["x", "y", "z", "heading", "sensor_x", "sensor_y", "sensor_z", "label"])
    for p, h, d, lab in zip(path.points, path.heading, path.sensor_dir, path.labels):
        writer.writerow(["%.6f" % v for v in (*p, h, *d)] + [lab])
    assert (tmp_path / "p.csv").read_bytes() == buf.getvalue().encode()
