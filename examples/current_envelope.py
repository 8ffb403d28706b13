"""The operating envelope of the breakwater in a current, with and without realtime replanning.

Runs `drake-auv envelope` twice on the built-in `breakwater_current` mission (the breakwater
contour in a tidal cross-shore current with turbulence and a 1 m swell; the envelope replaces
its mean current by each speed x direction of the grid and keeps the rest of its sea): once
flown with the replanner (`steps.1.survey.replanning=true`, the mission's own) and once
nominal-only (`false`). Written to `--out`: each mode's folder (`replanning/`, `nominal/`:
envelope.csv, envelope.png, envelope.md, envelope.json), `current_envelope.png` (the two
envelopes side by side: contact rate, least clearance and coverage against speed and
direction, one row per mode), `current_envelope.csv` (every run of both, with a `mode`
column) and `current_envelope.md` (both verdicts). A rerun into the same folder runs only the
missing rows.

The defaults are small (still water and 0.3 m/s from 4 directions, 1 seed: 10 dives, a few
minutes on 2 workers); the full grid:

    .venv/bin/python examples/current_envelope.py --speeds 0:0.6:0.1 --directions 8 \\
        --seeds 0:5 --workers 2 --out out/current_envelope
"""

from __future__ import annotations

import argparse
import csv
import sys
from pathlib import Path

from matplotlib.figure import Figure

from drake_auv import cli
from drake_auv.campaign.envelope import (COLUMNS, READING, envelope_axes, envelope_verdict,
                                         verdict_line)
from drake_auv.output_files import open_replacing, replacing, write_text

MODES = (("replanning", "true"), ("nominal", "false"))


def parse_args(argv=None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--mission", default="breakwater_current",
                        help="a mission whose step 1 is a survey (default breakwater_current)")
    parser.add_argument("--speeds", default="0:0.3:0.3", help="A:B:STEP m/s")
    parser.add_argument("--directions", type=int, default=4)
    parser.add_argument("--seeds", default="0:1", help="A:B (seeds A..B-1)")
    parser.add_argument("--set", dest="overrides", action="append", default=[],
                        metavar="KEY=VALUE", help="a fixed override for every run")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--scheduler", default=None, help="a running Dask scheduler instead")
    parser.add_argument("--out", default="out/current_envelope")
    return parser.parse_args(argv)


def read_rows(path) -> list[dict]:
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def main(argv=None) -> int:
    args = parse_args(argv)
    out = Path(args.out)
    where = (["--scheduler", args.scheduler] if args.scheduler else
             ["--workers", str(args.workers)])
    rows = {}
    for mode, replanning in MODES:
        code = cli.main(["envelope", args.mission, "--speeds", args.speeds, "--directions",
                         str(args.directions), "--seeds", args.seeds,
                         *(x for o in args.overrides for x in ("--set", o)),
                         "--set", f"steps.1.survey.replanning={replanning}", *where, "--quiet",
                         "-o", str(out / mode)])
        if code:
            return code
        rows[mode] = read_rows(out / mode / "envelope.csv")
    verdicts = {mode: envelope_verdict(r) for mode, r in rows.items()}
    clearances = [c["least_clearance_m"] for v in verdicts.values() for c in v["cells"]
                  if c["least_clearance_m"] is not None]
    shared = (min(clearances), max(clearances)) if clearances else (None, None)
    fig = Figure(figsize=(17, 12))
    for k, (mode, verdict) in enumerate(verdicts.items()):
        envelope_axes(fig, verdict, rows=len(verdicts), row=k, label=mode,
                      clearance_range=shared)
    seeds = len(verdicts["replanning"]["seeds"])
    fig.suptitle(f"Operating envelope of {args.mission}, with and without realtime "
                 f"replanning, {seeds} seed(s)\n{READING}", fontsize=11)
    with replacing(out / "current_envelope.png") as temporary:
        fig.savefig(temporary, dpi=100, bbox_inches="tight")
    with open_replacing(out / "current_envelope.csv", newline="") as f:
        writer = csv.DictWriter(f, ["mode", *COLUMNS])
        writer.writeheader()
        writer.writerows({"mode": mode, **row} for mode, r in rows.items() for row in r)
    lines = {mode: verdict_line(f"{args.mission} ({mode})", v) for mode, v in verdicts.items()}
    safe = {mode: v["safe_mps"] for mode, v in verdicts.items()}
    wider = (safe["replanning"] is not None and
             (safe["nominal"] is None or safe["replanning"] >= safe["nominal"]))
    text = {mode: "no speed" if v is None else f"{v:g} m/s" for mode, v in safe.items()}
    comparison = (f"Replanning's envelope is {'at least as wide as' if wider else 'narrower than'}"
                  f" nominal's: {text['replanning']} against {text['nominal']} from every "
                  "direction.")
    write_text(out / "current_envelope.md", "\n".join(
        [f"# Operating envelope of {args.mission}: replanning and nominal", "",
         *(f"- {line}" for line in lines.values()), "", comparison, "",
         "Plot: `current_envelope.png`; runs: `current_envelope.csv`.", ""]))
    print(*lines.values(), comparison, f"written to {out}", sep="\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
