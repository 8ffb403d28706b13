"""Test-suite settings: property tests draw the same examples on every run and worker (a
failure is reproducible, CI cannot pass or fail by luck); `broken_open3d`, an Open3D that is
installed but does not load."""

import sys

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
