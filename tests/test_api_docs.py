"""The API reference: pdoc builds it from the docstrings of every module without a warning
(`make docs` builds it the same way, scripts/update_docs.py), with a page per package that
carries its docstrings; a warning fails the build."""

import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "scripts"))
from update_docs import build_api  # noqa: E402

import drake_auv  # noqa: E402

PACKAGE = Path(drake_auv.__file__).parent


def test_api_reference_builds_without_warnings_a_page_per_module(tmp_path):
    out = tmp_path / "api"
    assert build_api(out).is_file()
    modules = [p.relative_to(PACKAGE.parent).with_suffix("") for p in PACKAGE.rglob("*.py")]
    modules = [m.parent if m.name == "__init__" else m for m in modules]
    missing = [str(m) for m in modules if not (out / m).with_suffix(".html").is_file()]
    assert not missing, f"no page for {missing}"
    page = (out / "drake_auv" / "mission" / "runner.html").read_text()
    assert "run_mission" in page and "Flies" in page  # the function and its docstring


def test_a_warning_fails_the_build(tmp_path, monkeypatch):
    (tmp_path / "api_docs_probe.py").write_text(
        '"""A module whose __all__ names what it lacks."""\n__all__ = ["absent"]\n')
    monkeypatch.syspath_prepend(str(tmp_path))
    with pytest.raises(RuntimeError, match="absent"):
        build_api(tmp_path / "api", modules=("api_docs_probe",))
