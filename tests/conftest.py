"""Test-suite settings: property tests draw the same examples on every run and worker (a
failure is reproducible, CI cannot pass or fail by luck); `broken_open3d`, an Open3D that is
installed but does not load; `small_tif`, a small UTM GeoTIFF with a wall for `drake-auv plan`."""

import sys

import numpy as np
import pytest
from hypothesis import settings

settings.register_profile("deterministic", derandomize=True, print_blob=True)
settings.load_profile("deterministic")


@pytest.fixture()
def broken_open3d(tmp_path, monkeypatch):
    """An `open3d` that is installed but whose import fails as a missing system library does."""
    from drake_auv.reconstruction.surface import retry_open3d

    package = tmp_path / "site" / "open3d"
    package.mkdir(parents=True)
    (package / "__init__.py").write_text(
        "raise ImportError('libusb-1.0.so.0: cannot open shared object file: No such file or "
        "directory')\n")
    for name in [m for m in sys.modules if m == "open3d" or m.startswith("open3d.")]:
        monkeypatch.delitem(sys.modules, name)
    monkeypatch.syspath_prepend(str(tmp_path / "site"))
    retry_open3d()
    yield
    retry_open3d()


@pytest.fixture()
def small_tif(tmp_path):
    """A 50 x 60 m GeoTIFF (1 m cells, EPSG:32631) of a gentle slope with a wall of slope 0.9."""
    from drake_auv.terrain.bathymetry import Bathymetry
    from drake_auv.terrain.readers import write_geotiff

    yy, xx = np.mgrid[0:60, 0:50] * 1.0
    z = -40.0 + 0.05 * yy + np.clip(xx - 20.0, 0.0, 12.0) * 0.9  # a wall of slope 0.9
    path = tmp_path / "small.tif"
    write_geotiff(Bathymetry(z, (1.0, 1.0), (1000.0, 2000.0), "EPSG:32631"), path)
    return path
