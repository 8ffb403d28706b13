"""The documentation's marked numbers (`<!-- report:KEY:FORMAT -->`) agree with the committed
demo report, docs/demo_report.json; `make docs` (scripts/update_docs.py) rewrites them."""

import json
import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "scripts"))
from update_docs import (REPORT, documented_report, documents, markers, render,  # noqa: E402
                         rewrite)


def test_marked_numbers_equal_the_committed_report():
    report = documented_report()
    found = 0
    for doc in documents():
        for key, fmt, text in markers(doc.read_text()):
            assert text == render(report, key, fmt), \
                f"{doc.name}: {key} reads {text!r}, the report says {render(report, key, fmt)!r}"
            found += 1
    assert found >= 4  # the README's headline numbers at least


def test_rewrite_replaces_only_the_marked_text():
    report = {"coverage": {"multibeam": 0.9634}, "contact": True}
    text = ("covers <!-- report:coverage.multibeam:pct -->1 %<!-- /report --> of it "
            "(<!-- report:contact:contact -->no contact<!-- /report -->)")
    assert rewrite(text, report) == (
        "covers <!-- report:coverage.multibeam:pct -->96.3 %<!-- /report --> of it "
        "(<!-- report:contact:contact -->contact<!-- /report -->)")
    with pytest.raises(KeyError, match="coverage.camera"):
        rewrite("<!-- report:coverage.camera:pct -->1 %<!-- /report -->", report)
    with pytest.raises(ValueError, match="format"):
        rewrite("<!-- report:contact:yes -->1<!-- /report -->", report)


DOCS = Path(__file__).resolve().parents[1] / "docs"


def test_campaign_table_is_the_committed_results():
    """docs/campaigns.md's breakwater table, recomputed from its results.csv."""
    import csv
    import re

    rows = list(csv.DictReader((DOCS / "campaigns" / "breakwater" / "results.csv").open()))
    text = (DOCS / "campaigns.md").read_text()
    table = {line.split("|")[1].strip(): re.sub(r" \([^)]*CI[^)]*\)", "", line.replace("**", ""))
             for line in text.splitlines() if re.match(r"\| (all|[\d.]+) \| \d+ / \d+ \|", line)}
    for error in ("0", "1.25", "2.5", "3.75", "5", "all"):
        cells = [error]
        for replanning in ("true", "false"):
            mine = [r for r in rows if r["steps.1.survey.replanning"] == replanning
                    and error in ("all", r["site.prior_error_m"])]
            clearance = np.array([float(r["min_clearance_m"]) for r in mine])
            cells += [f"{sum(r['contact'] == 'True' for r in mine)} / {len(mine)}",
                      f"{np.median(clearance):.2f} ({clearance.min():.2f}) m",
                      f"{100 * np.median([float(r['coverage_multibeam']) for r in mine]):.1f} %"]
        assert table[error] == "| " + " | ".join(cells) + " |"


def key_paths(value, prefix: str = "") -> set[str]:
    """Dotted paths of every key of `value`'s dicts, recursively; the elements of a list merge
    under `name[]`."""
    out = set()
    if isinstance(value, dict):
        for key, item in value.items():
            out |= {prefix + key} | key_paths(item, f"{prefix}{key}.")
    elif isinstance(value, list):
        for item in value:
            out |= key_paths(item, prefix[:-1] + "[].")
    return out


def test_key_paths():
    assert key_paths({"a": {"b": 1, "c": [{"d": 1}, {"e": None}]}, "f": []}) == {
        "a", "a.b", "a.c", "a.c[].d", "a.c[].e", "f"}


def test_the_committed_report_has_the_keys_the_code_writes(tmp_path):
    """The demo's mission capped at 20 s (seconds of setup and simulation) writes the keys of
    the full demo, but for the reconstruction's own, which a 20 s dive has too few returns to
    build, the wall-clock `timing` left out of the committed copy, and the `_null_reason` a
    figure gains where it is not finite. Fails when
    docs/demo_report.json predates the code: `make docs` regenerates it."""
    from update_docs import MACHINE_DEPENDENT

    from drake_auv.cli import main

    out = tmp_path / "demo"
    assert main(["demo", "-o", str(out), "--quiet", "--no-html",
                 "--set", "limits.max_time_s=20"]) == 0
    written = json.loads((out / "report.json").read_text())
    committed = json.loads(REPORT.read_text())
    assert not set(MACHINE_DEPENDENT) & set(committed) and "timing" in written
    for report in (written, committed):
        assert isinstance(report.pop("reconstruction")["built"], bool)
        for key in MACHINE_DEPENDENT:
            report.pop(key, None)
    # A figure that is not finite in one run is null with KEY_null_reason beside it.
    mine, theirs = ({k for k in key_paths(r) if not k.endswith("_null_reason")}
                    for r in (written, committed))
    assert mine == theirs, (f"docs/demo_report.json lacks {sorted(mine - theirs)} and has "
                            f"{sorted(theirs - mine)} the code no longer writes: make docs")


def test_the_readmes_demo_figures_are_all_marked():
    """Every measured figure of the README's demo paragraph is a marked number, which
    `test_marked_numbers_equal_the_committed_report` checks against the committed report."""
    import re

    from update_docs import MARKER, ROOT

    text = (ROOT / "README.md").read_text()
    start = text.index("With the default seed")
    paragraph = text[start:text.index("\n\n", start)]
    assert len(markers(paragraph)) >= 4
    unmarked = re.findall(r"\d+\.\d+ ?(?:%|m\b)", MARKER.sub("", paragraph))
    assert unmarked == [], f"the README's demo paragraph quotes {unmarked} without a marker"
