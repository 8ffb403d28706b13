"""Regenerates the documentation's demo figures from one run of the demo (`make docs`).

Runs `drake-auv demo` into `--out`, copies its `report.json` to `docs/demo_report.json` (without
the wall-clock `timing`, so that the committed copy changes only when the results do) and its
figures to `docs/demo_<name>.png`, then rewrites every marked number in README.md and
docs/*.md from the report. A marked number reads

    <!-- report:results.mission.multibeam_coverage:pct -->96.3 %<!-- /report -->

that is a dotted key into report.json, a format (see FORMATS), and the text between the two
comments, which is replaced. `tests/test_docs.py` checks that the committed text agrees with
the committed report.

    python scripts/update_docs.py [--out out/docs] [--no-run]
"""

from __future__ import annotations

import argparse
import json
import re
import shutil
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
REPORT = ROOT / "docs" / "demo_report.json"
FIGURES = ("plan", "coverage", "distance")
MACHINE_DEPENDENT = ("timing",)  # top-level keys of report.json left out of the committed copy
MARKER = re.compile(
    r"(<!-- report:(?P<key>[\w.]+):(?P<fmt>\w+) -->)(?P<text>.*?)(<!-- /report -->)", re.DOTALL)
FORMATS = {
    "pct": lambda v: f"{100 * v:.1f} %",  # a fraction as a percentage
    "m": lambda v: f"{v:.2f} m",
    "contact": lambda v: "contact" if v else "no contact",
}


def documents() -> list[Path]:
    """The files whose markers `make docs` rewrites."""
    return [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]


def lookup(report: dict, key: str):
    """The value at dotted `key` ("results.mission.contact") in `report`."""
    value = report
    for part in key.split("."):
        if not isinstance(value, dict) or part not in value:
            raise KeyError(f"report has no {key!r} (no {part!r})")
        value = value[part]
    return value


def render(report: dict, key: str, fmt: str) -> str:
    """The text of one marked number."""
    if fmt not in FORMATS:
        raise ValueError(f"unknown report format {fmt!r}; allowed: {', '.join(FORMATS)}")
    return FORMATS[fmt](lookup(report, key))


def markers(text: str) -> list[tuple[str, str, str]]:
    """(key, format, current text) of every marked number in `text`."""
    return [(m["key"], m["fmt"], m["text"]) for m in MARKER.finditer(text)]


def rewrite(text: str, report: dict) -> str:
    """`text` with every marked number rendered from `report`."""
    return MARKER.sub(lambda m: m[1] + render(report, m["key"], m["fmt"]) + m[5], text)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="out/docs",
                        help="where the demo writes (default out/docs)")
    parser.add_argument("--no-run", action="store_true",
                        help="use the report and figures already in --out")
    args = parser.parse_args(argv)
    out = Path(args.out)
    if not args.no_run:
        from drake_auv.cli import main as drake_auv

        if drake_auv(["demo", "--out", str(out), "--quiet"]) != 0:
            return 1
    report_file = out / "report.json"
    if not report_file.exists():
        raise FileNotFoundError(f"{report_file}: no demo report (run without --no-run)")
    report = json.loads(report_file.read_text())
    committed = {k: v for k, v in report.items() if k not in MACHINE_DEPENDENT}
    REPORT.write_text(json.dumps(committed, indent=2) + "\n")
    for name in FIGURES:
        shutil.copyfile(out / f"{name}.png", ROOT / "docs" / f"demo_{name}.png")
    for doc in documents():
        text = doc.read_text()
        new = rewrite(text, report)
        if new != text:
            doc.write_text(new)
            print(f"updated {doc.relative_to(ROOT)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
