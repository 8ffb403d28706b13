"""docs/architecture.md's port and builder tables are the code's: `scripts/port_table.py`
regenerates them from the systems of a mission Diagram, so a port added (or renamed, or
removed) without its row in the doc fails here."""

import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "scripts"))
from port_table import DOC, PORTS, _block, meanings, render  # noqa: E402

from drake_auv.replanning.replanner import Replanner  # noqa: E402


@pytest.fixture(scope="module")
def doc():
    return DOC.read_text()


def _table(text):
    return _block(text, PORTS).group(1).splitlines()


def test_the_doc_tables_are_the_code_tables(doc):
    fresh = render(doc)
    missing = sorted(set(_table(fresh)) - set(_table(doc)))
    stale = sorted(set(_table(doc)) - set(_table(fresh)))
    assert fresh == doc, (f"docs/architecture.md is not the code's (run scripts/port_table.py "
                          f"and write the meanings): new rows {missing}, stale rows {stale}")


def test_every_port_has_a_meaning(doc):
    known = meanings(doc)
    assert len(known) > 60  # every system of a mission
    assert all(known.values()), [key for key, meaning in known.items() if not meaning]


def test_a_port_added_without_its_row_fails(doc, monkeypatch):
    declare = Replanner.__init__

    def with_extra_port(self, *args, **kwargs):
        declare(self, *args, **kwargs)
        self.DeclareVectorOutputPort("extra", 1, lambda context, output: None)

    monkeypatch.setattr(Replanner, "__init__", with_extra_port)
    fresh = render(doc)
    assert fresh != doc
    added = [row for row in _table(fresh) if "`extra`" in row]
    assert added == ["| `Replanner` | replanner | out | `extra` | 1 |  |"]


def test_the_package_table_names_every_package_and_module(doc):
    """Every first-level package (a folder with an `__init__.py`) and module of drake_auv has
    its row in the package table."""
    root = Path(__file__).resolve().parents[1] / "drake_auv"
    names = sorted({p.parent.name for p in root.glob("*/__init__.py")}
                   | {p.stem for p in root.glob("*.py") if p.stem != "__init__"})
    assert names and all(f"| `drake_auv.{name}` |" in doc for name in names), [
        name for name in names if f"| `drake_auv.{name}` |" not in doc]
