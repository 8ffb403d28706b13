"""`report.md`: the Markdown of a `summarise` dict (the plan, the phases, the whole dive, the
timing and the files written)."""

from __future__ import annotations

from drake_auv.mission.ocean_summary import ocean_markdown


def _fmt(value, spec: str, unit: str = "") -> str:
    """A table cell: "-" where the quantity does not apply."""
    return "-" if value is None else f"{value:{spec}}{unit}"


FILE_NOTES = {"plan.png": "the coverage plan", "mission.html": "Meshcat recording"}


def _angle(mean, sd) -> str:
    return "" if mean is None else f" (viewing angle {mean:.1f} deg, sd {sd:.1f})"


def _distance_line(d: dict) -> str:
    """The true (and on-line map) distance to the target; the survey's only where it had
    samples."""
    near = "" if d["near_m"] is None else f" within {d['near_m']:g} m"
    parts = [] if d["mean_m"] is None else [
        f"over {d['samples']} survey samples{near}: mean {d['mean_m']:.2f} m, sd "
        f"{d['sd_m']:.2f} m"]
    line = "- True distance to the target: " + "; ".join(
        parts + [f"minimum over the dive {d['min_m']:.2f} m"]) + "."
    if d["map_mean_m"] is not None:
        line += f" Against the on-line map: mean {d['map_mean_m']:.2f} m, sd {d['map_sd_m']:.2f} m."
    return line


def exploration_markdown(section: dict | None) -> list[str]:
    """The report's line on an exploration (`exploration_summary`); none without one."""
    if section is None:
        return []
    stopped = ("nothing more worth seeing" if section["stopped"] == "gain"
               else "its time ran out")
    return [f"- Exploration (next views by {section['strategy']}): "
            f"{section['viewpoints']} viewpoints; the planner believed "
            f"{100 * section['believed_coverage']:.1f} % of the mapped surface covered when "
            f"it stopped ({stopped})."]


def report_markdown(summary: dict, files=()) -> str:
    """The report as Markdown; `files`: the names of the files written beside it, listed at the
    end. Quantities that do not apply (no survey sample, nothing seen) are left out."""
    m, c, d = summary["mission"], summary["coverage"], summary["distance_to_target"]
    lines = [f"# Mission report: {m['name']}", "",
             f"Site `{m['site']}`, seed {m['seed']}; "
             + ("every leg flown." if m["completed"] else "**stopped by the time cap**.")
             + " One dive: the vehicle, its navigation error and the on-line map carry "
             "across the phases.", ""]
    plan = summary["plan"]
    if plan is not None:
        lines += ["## Off-line plan (on the prior map)", "", "| quantity | value |",
                  "| --- | --- |",
                  f"| path length | {plan['length_m']:.1f} m ("
                  + ", ".join(f"{k} {v:.1f} m" for k, v in plan["length_by_label_m"].items())
                  + ") |",
                  f"| planned duration | {plan['planned_duration_s']:.0f} s |",
                  f"| Omega | {plan['omega_m']:g} m |",
                  "| true distance of the nominal path to the target | "
                  + ("" if plan["nominal_true_distance_mean_m"] is None else
                     f"mean {plan['nominal_true_distance_mean_m']:.2f} m, ")
                  + f"min {plan['nominal_true_distance_min_m']:.2f} m |"]
        if "planned_coverage_prior" in plan:
            lines += [f"| high-slope regions | {plan['high_slope_regions']} |",
                      f"| viewing angle on the prior map | {plan['planned_view_mean_deg']:.1f}"
                      f" deg (sd {plan['planned_view_sd_deg']:.1f}) |",
                      f"| coverage of the prior map | "
                      f"{100 * plan['planned_coverage_prior']:.1f} % |"]
        lines.append("")
    lines += ["## Phases (true state, true surface)", "",
              "| phase | start (s) | end (s) | length (m) | min distance to target (m) | "
              "min clearance (m) | max navigation error (m) | legs |",
              "| --- | --- | --- | --- | --- | --- | --- | --- |"]
    for p in summary["phases"]:
        lines.append(f"| {p['name']} | {p['start_s']:.0f} | {p['end_s']:.0f} | "
                     f"{_fmt(p.get('length_m'), '.1f')} | {_fmt(p.get('distance_min_m'), '.2f')}"
                     f" | {_fmt(p.get('clearance_min_m'), '.2f')} | "
                     f"{_fmt(p.get('navigation_error_max_m'), '.2f')} | "
                     + ", ".join(f"{k} ({o})" for k, o in zip(p["legs"], p["outcomes"])) + " |")
    lines += ["", "## Whole dive", "",
              f"- Target surface: {m['target_area_m2']:.0f} m^2. Covered by the multibeam: "
              f"**{100 * c['multibeam']:.1f} %**"
              f"{_angle(c['multibeam_angle_mean_deg'], c['multibeam_angle_sd_deg'])}; by the "
              f"camera: **{100 * c['camera']:.1f} %**"
              f"{_angle(c['camera_angle_mean_deg'], c['camera_angle_sd_deg'])}.",
              _distance_line(d),
              coverage_time_line(summary["coverage_vs_time"]),
              f"- Minimum signed clearance to anything (negative: inside the world or out "
              f"of the water): {summary['min_clearance_m']:.2f} m: "
              + ("**contact**." if summary["contact"] else "no contact.")
              + f" Largest navigation error: {summary['navigation_error_max_m']:.2f} m.",
              *exploration_markdown(summary.get("exploration")),
              *ocean_markdown(summary.get("ocean")),
              "", "## Timing (wall clock: varies with the machine and its load)", ""]
    t = summary["timing"]
    lines.append(f"- {t['sim_s']:.0f} s simulated in {t['wall_s']:.1f} s wall: "
                 f"{t['real_time_factor']:.0f}x real time.")
    if "outputs_s" in t:
        setup = "" if t.get("setup_s") is None else f"setup {t['setup_s']:.1f} s, "
        lines.append(f"- End to end {t['total_s']:.1f} s: {setup}simulation "
                     f"{t['simulation_s']:.1f} s, outputs {t['outputs_s']:.1f} s (of which the "
                     f"reconstruction {t['reconstruction_s']:.1f} s); peak memory "
                     f"{t['peak_rss_mb']:.0f} MiB.")
    if "replan_steps" in t:
        lines.append(f"- {t['replan_steps']} replanning steps: median "
                     f"{t['replan_median_ms']:.1f} ms, 95th percentile {t['replan_p95_ms']:.1f}"
                     " ms.")
    if files:
        lines += ["", "Files: " + ", ".join(
            f"`{name}`" + (f" ({FILE_NOTES[name]})" if name in FILE_NOTES else "")
            for name in files) + "."]
    return "\n".join(lines) + "\n"


def coverage_time_line(curve: dict) -> str:
    """The report's line on when each sensor reached the `COVERAGE_LEVELS`."""
    parts = []
    for name in ("multibeam", "camera"):
        reached = ", ".join(f"{level} % never" if t is None else f"{level} % at {t:.0f} s"
                            for level, t in curve["time_to_s"][name].items())
        parts.append(f"{name} {reached}")
    return "- Coverage against time (`coverage_vs_time.png`): " + "; ".join(parts) + "."
