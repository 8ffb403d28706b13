"""The documentation's marked numbers (`<!-- report:KEY:FORMAT -->`) agree with the committed
demo report, docs/demo_report.json; `make docs` (scripts/update_docs.py) rewrites them."""

import json
import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "scripts"))
from update_docs import REPORT, documents, markers, render, rewrite  # noqa: E402


def test_marked_numbers_equal_the_committed_report():
    report = json.loads(REPORT.read_text())
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


def _ablation(name):
    rows = json.loads((DOCS / name).read_text())
    return {o: [r for r in rows if r["optimizer"] == o] for o in ("stomp", "none")}


def test_replanning_ablation_tables_are_the_committed_rows():
    """docs/replanning.md's stomp / none tables, recomputed from the rows the ablation wrote
    (`bench_replanning.py --ablation 10 --json docs/replanning_ablation.json`)."""
    text = (DOCS / "replanning.md").read_text()
    runs = _ablation("replanning_ablation.json")
    for name, rows in runs.items():
        mean = {k: np.mean([r[k] for r in rows]) for k in rows[0] if
                isinstance(rows[0][k], float)}
        contacts = sum(r["contact"] for r in rows)
        survey = sum(r["survey_clearance_m"] <= 1.0 for r in rows)
        line = (f"| {name} | {mean['mean_m']:.2f} | {mean['sd_m']:.2f} | {mean['min_m']:.2f} / "
                f"{min(r['min_m'] for r in rows):.2f} | {mean['abs_error_m']:.2f} | "
                f"{mean['map_mean_m']:.2f} / {mean['map_sd_m']:.2f} | {contacts} / {survey} of "
                f"{len(rows)} | {mean['multibeam']:.3f} | {mean['camera']:.3f} |")
        assert line in text, line
    for stomp, none in zip(runs["stomp"], runs["none"]):
        cells = [f"{r['mean_m']:.2f} / {r['sd_m']:.2f} / {r['min_m']:.2f}, {r['abs_error_m']:.2f}"
                 for r in (stomp, none)]
        line = (f"| {stomp['seed']} | {cells[0]} | {cells[1]} | {stomp['multibeam']:.3f} / "
                f"{none['multibeam']:.3f} | {stomp['camera']:.3f} / {none['camera']:.3f} |")
        assert line in text, line


def test_replanning_second_seed_set_prose_is_the_committed_rows():
    text = " ".join((DOCS / "replanning.md").read_text().split())
    runs = _ablation("replanning_ablation_seeds10-19.json")
    stomp, none = runs["stomp"], runs["none"]
    at_least = sum(s["multibeam"] >= n["multibeam"] for s, n in zip(stomp, none))
    for phrase in (
            f"closest {min(r['min_m'] for r in stomp):.2f} m to the target, "
            f"{min(r['min_clearance_m'] for r in stomp):.2f} m to anything",
            f"none: {sum(r['contact'] for r in none)} of 10 dives within 1 m",
            f"mean abs(d - Omega) {np.mean([r['abs_error_m'] for r in stomp]):.2f} m against "
            f"{np.mean([r['abs_error_m'] for r in none]):.2f} m",
            f"multibeam {np.mean([r['multibeam'] for r in stomp]):.3f} against "
            f"{np.mean([r['multibeam'] for r in none]):.3f}",
            f"at least none's in {at_least} of these 10 seeds"):
        assert phrase in text, phrase
    assert not any(r["contact"] for r in stomp)


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
