"""The tutorial notebook (examples/tutorial_bring_your_own_site.ipynb) runs from start to end
in a fresh working folder, as `make docs` runs it: a site from a GeoTIFF and a structure mesh,
its plan, a capped dive watched in Meshcat (headless) and its report."""

import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "scripts"))
from update_docs import TUTORIAL, execute_notebook  # noqa: E402


def test_tutorial_executes_and_writes_the_dive_report(tmp_path):
    nb = execute_notebook(TUTORIAL, tmp_path, timeout_s=300)
    errors = [o for cell in nb.cells if cell.cell_type == "code"
              for o in cell.get("outputs", []) if o.output_type == "error"]
    assert not errors
    for name in ("world.ply", "structure.ply", "mission.yaml"):
        assert (tmp_path / "my_site" / name).stat().st_size > 0, name
    report = json.loads((tmp_path / "my_dive" / "report.json").read_text())
    assert report["mission"]["name"] == "my_site"
    assert 0.0 < report["coverage"]["multibeam"] <= 1.0  # the dive saw the structure
    assert not report["contact"]
    assert (tmp_path / "my_dive" / "mission.html").stat().st_size > 0
    assert (tmp_path / TUTORIAL.name).is_file()  # the executed copy, with its outputs
    assert any("Meshcat: http://localhost:" in o.get("text", "") for cell in nb.cells
               if cell.cell_type == "code" for o in cell.get("outputs", []))
