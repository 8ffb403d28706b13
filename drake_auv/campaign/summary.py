"""A campaign's summary: summary.json, summary.md and plots, from the rows of results.csv.

Per variant (one combination of the varied values) and over all runs: runs, failures, the
contact rate with its 95 % Wilson score interval, quantiles of coverage and minimum clearance,
and the real-time factors. Failed runs count in `runs` and `failed` only.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from drake_auv.output_files import replacing, write_json, write_text

QUANTILES = (0.0, 0.05, 0.5, 0.95, 1.0)
Z95 = 1.959964  # standard normal quantile of 0.975
VEHICLE_RADIUS_M = 1.0  # drake_auv.mission.runner.VEHICLE_RADIUS, the contact threshold


def wilson_interval(k: int, n: int, z: float = Z95) -> tuple[float, float]:
    """The Wilson score interval of a proportion of `k` successes in `n` trials ((0, 1) when
    n = 0)."""
    if n == 0:
        return 0.0, 1.0
    p = k / n
    denom = 1.0 + z * z / n
    centre = (p + z * z / (2 * n)) / denom
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / denom
    return max(0.0, centre - half), min(1.0, centre + half)


def _floats(rows, column) -> np.ndarray:
    values = [float(r[column]) for r in rows if r.get(column) not in (None, "")]
    return np.asarray(values, dtype=float)


def _quantiles(values: np.ndarray) -> dict | None:
    if len(values) == 0:
        return None
    return {f"p{round(q * 100)}": round(float(np.quantile(values, q)), 4) for q in QUANTILES}


def group_stats(rows: list[dict]) -> dict:
    """Statistics of a list of result rows (text, as read from results.csv)."""
    ok = [r for r in rows if r["status"] == "ok"]
    contacts = sum(r["contact"] == "True" for r in ok)
    low, high = wilson_interval(contacts, len(ok))
    rtf = _floats(ok, "real_time_factor")
    return dict(
        runs=len(rows), ok=len(ok), failed=len(rows) - len(ok), contacts=contacts,
        contact_rate=round(contacts / len(ok), 4) if ok else None,
        contact_rate_95=[round(low, 4), round(high, 4)],
        aborted=sum(r.get("aborted") == "True" for r in ok),
        with_response=sum(bool(r.get("responses")) for r in ok),
        coverage_multibeam=_quantiles(_floats(ok, "coverage_multibeam")),
        coverage_camera=_quantiles(_floats(ok, "coverage_camera")),
        min_clearance_m=_quantiles(_floats(ok, "min_clearance_m")),
        distance_mean_m=_quantiles(_floats(ok, "distance_mean_m")),
        real_time_factor=dict(median=round(float(np.median(rtf)), 2),
                              min=round(float(rtf.min()), 2),
                              max=round(float(rtf.max()), 2)) if len(rtf) else None)


def variants(rows: list[dict], vary_keys) -> dict[tuple, list[dict]]:
    """Rows grouped by their varied values, in order of first appearance."""
    groups: dict[tuple, list[dict]] = {}
    for row in rows:
        groups.setdefault(tuple(row[k] for k in vary_keys), []).append(row)
    return groups


def summarise_campaign(rows: list[dict], vary_keys, meta: dict) -> dict:
    """summary.json's content: `meta` (mission, seeds, ...), `overall` and `variants`."""
    groups = variants(rows, vary_keys)
    return {**meta, "vary_keys": list(vary_keys), "overall": group_stats(rows),
            "variants": [dict(values=dict(zip(vary_keys, values)), **group_stats(group))
                         for values, group in groups.items()]}


def _spread(q: dict | None, scale: float, spec: str, least: bool = False) -> str:
    """A table cell: the median [5th-95th percentile] of quantiles `q` times `scale` (and
    their minimum with `least`); "-" where no run gave the quantity (every run failed)."""
    if q is None:
        return "-"
    cell = f"{scale * q['p50']:{spec}} [{scale * q['p5']:{spec}}-{scale * q['p95']:{spec}}]"
    return cell + (f" ({scale * q['p0']:{spec}})" if least else "")


def summary_markdown(summary: dict) -> str:
    """summary.md: one table row per variant (when there are varied keys) and one over all
    runs."""
    keys = summary["vary_keys"]
    head = ["variant" if not keys else " | ".join(f"`{k}`" for k in keys)]
    lines = [f"# Campaign: {summary['mission']}", "",
             f"Seeds {summary['seeds']}; {summary['overall']['runs']} runs "
             f"({summary['overall']['failed']} failed). Contact: true signed clearance <= "
             f"{VEHICLE_RADIUS_M:g} m (negative inside the world or out of the water). Rates "
             "with 95 % Wilson intervals; coverage and clearance as median [5th-95th "
             "percentile] (min); real-time factor: median.", "",
             "| " + " | ".join(head + ["runs", "failed", "contacts", "contact rate (95 %)",
                                       "multibeam coverage %", "camera coverage %",
                                       "min clearance m", "responses", "real-time factor"])
             + " |",
             "| " + " | ".join(["---"] * (len(keys or [1]) + 9)) + " |"]
    # Without --vary the one variant is every run: its row is the "all" row.
    entries = [(s["values"], s) for s in summary["variants"]] if keys else []
    entries.append(({k: "**all**" for k in keys} if keys else {"": "**all**"},
                    summary["overall"]))
    for values, s in entries:
        cells = list(values.values())
        rate = ("-" if s["contact_rate"] is None else
                f"{100 * s['contact_rate']:.0f} % ({100 * s['contact_rate_95'][0]:.0f}-"
                f"{100 * s['contact_rate_95'][1]:.0f} %)")
        cov, cam, clr = s["coverage_multibeam"], s["coverage_camera"], s["min_clearance_m"]
        rtf = s["real_time_factor"]
        cells += [str(s["runs"]), str(s["failed"]), str(s["contacts"]), rate,
                  _spread(cov, 100, ".1f"), _spread(cam, 100, ".1f"),
                  _spread(clr, 1, ".2f", least=True),
                  f"{s['with_response']} ({s['aborted']} aborted)",
                  "-" if rtf is None else f"{rtf['median']:.0f}x"]
        lines.append("| " + " | ".join(cells) + " |")
    lines += ["", "Plots: `coverage.png` (coverage distribution per variant), `clearance.png` "
              "(minimum-clearance histogram), `variants.png` (per-variant comparison).", ""]
    return "\n".join(lines)


def _label(values: tuple, keys) -> str:
    return ", ".join(f"{k.split('.')[-1]}={v}" for k, v in zip(keys, values)) or "all"


def _axis(texts: list[str]) -> list:
    """The varied values as numbers when they all are (a numeric axis), else as text."""
    try:
        return [float(t) for t in texts]
    except ValueError:
        return texts


def figures(rows: list[dict], vary_keys) -> dict[str, Figure]:
    """coverage.png, clearance.png and variants.png."""
    groups = {v: [r for r in g if r["status"] == "ok"]
              for v, g in variants(rows, vary_keys).items()}
    labels = [_label(v, vary_keys) for v in groups]
    cover = Figure(figsize=(max(6, 0.8 * len(groups) + 2), 4.5))
    ax = cover.add_subplot()
    data = [100 * _floats(g, "coverage_multibeam") for g in groups.values()]
    ax.boxplot([d if len(d) else [np.nan] for d in data], showfliers=True)
    ax.set_xticks(range(1, len(labels) + 1), labels, rotation=45, ha="right", fontsize=7)
    ax.set(ylabel="multibeam coverage of the target (%)",
           title="Coverage distribution per variant")
    clear = Figure(figsize=(7, 4.5))
    ax = clear.add_subplot()
    values = _floats([r for g in groups.values() for r in g], "min_clearance_m")
    ax.hist(values, bins=30, color="tab:blue")
    ax.axvline(VEHICLE_RADIUS_M, color="tab:red", label="contact (vehicle radius)")
    ax.set(xlabel="minimum true signed clearance of a dive (m; < 0: inside the world or out "
                  "of the water)", ylabel="runs",
           title=f"Minimum clearance, {len(values)} runs")
    ax.legend()
    comparison = Figure(figsize=(11, 4.5))
    first = vary_keys[0] if vary_keys else None
    lines: dict[tuple, list] = {}
    for values, group in groups.items():
        lines.setdefault(values[1:], []).append((values[0] if first else "all", group))
    for k, (name, unit, column) in enumerate((("median multibeam coverage", "%",
                                               "coverage_multibeam"),
                                              ("median minimum clearance", "m",
                                               "min_clearance_m"),
                                              ("contact rate", "%", "contact"))):
        ax = comparison.add_subplot(1, 3, k + 1)
        for rest, points in lines.items():
            xs = _axis([p[0] for p in points])
            if column == "contact":
                ys = [100 * np.mean([r["contact"] == "True" for r in g]) if g else np.nan
                      for _, g in points]
            else:
                ys = [np.median(_floats(g, column)) * (100 if unit == "%" else 1)
                      if g else np.nan for _, g in points]
            ax.plot(xs, ys, marker="o", label=_label(rest, vary_keys[1:]))
        ax.set(xlabel=first or "", ylabel=f"{name} ({unit})", title=name)
        if column == "contact":
            ax.set_ylim(-2, 102)
        if len(lines) > 1:
            ax.legend(fontsize=7)
    comparison.tight_layout()
    return {"coverage.png": cover, "clearance.png": clear, "variants.png": comparison}


def write_summary(rows: list[dict], vary_keys, out, meta: dict, dpi: int = 110) -> dict:
    """Writes summary.json, summary.md and the plots into `out`; returns the summary."""
    out = Path(out)
    summary = summarise_campaign(rows, vary_keys, meta)
    write_json(out / "summary.json", summary)
    write_text(out / "summary.md", summary_markdown(summary))
    for name, fig in figures(rows, vary_keys).items():
        with replacing(out / name) as temporary:
            fig.savefig(temporary, dpi=dpi, bbox_inches="tight")
    return summary
