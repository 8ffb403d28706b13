"""The `drake-auv plan` output folder: path.csv (world frame, `PlannedPath.to_csv`), the
`--export` formats (`registry.EXPORTS`), report.md and report.json (`planning.report`) and the
PNG figures (`planning.figures`).
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from dataclasses import replace
from pathlib import Path

from drake_auv.formats import ExportOptions
from drake_auv.formats.registry import EXPORTS, check_exports, export_notes, export_warnings
from drake_auv.output_files import write_json, write_text
from drake_auv.planning.report import mission_time, report_dict, report_markdown
from drake_auv.progress import RunProgress, phase_display
from drake_auv.resources import paused_gc


def output_stages(exports: tuple[str, ...], figures: bool = True, metrics_3d=True,
                  grid_metrics: bool = False) -> int:
    """The stages `write_outputs` counts on its progress display: path.csv, each export, each
    figure, the grid and the 3D metrics (when computed here; they run beside the other
    stages) and the reports."""
    from drake_auv.planning.figures import PLAN_VIEWS, VIEWS_3D

    return (2 + len(exports) + (metrics_3d is True) + bool(grid_metrics)
            + (len(PLAN_VIEWS) + len(VIEWS_3D) if figures else 0))


def write_outputs(plan, outdir, figures: bool = True, progress: bool | RunProgress = False,
                  exports: tuple[str, ...] | None = None, origin_lonlat=None,
                  surge_velocity: float = 0.5, tolerance_xy: float = 1.0,
                  metrics_3d=True, max_items: int = 700, ardusub_frames: str = "terrain",
                  heave_in_3d: bool = False, reference_table: bool = False,
                  current: dict | None = None, grid_metrics: bool = False) -> list[Path]:
    """Writes path.csv (world frame), report.md, report.json, the `exports` and (with
    `figures`) the PNG figures into `outdir`; returns the files written.

    Args:
        progress: show the progress over the `output_stages`, or a caller's `RunProgress`
            to show it on (its "outputs" phase: one display that ends when the last file is
            written).
        exports: names of `registry.EXPORTS`: "cola2" (mission.xml), "qgc" (mission.plan, or
            mission_1.plan, ... past `max_items`; report.json gains exports.qgc), "geojson"
            (path.geojson: the route and the waypoints of the vehicle files written with it;
            lawnmower.geojson; WGS 84); None: "geojson" when the grid is georeferenced (a CRS
            or `origin_lonlat`), else none. Written in the table's order.
        origin_lonlat: WGS 84 (lon, lat) of the world origin, for grids without a CRS.
        surge_velocity, tolerance_xy, max_items, ardusub_frames, heave_in_3d: the exports'
            `ExportOptions` (`surge_velocity` is also the report's mission time).
        metrics_3d: add the occluded 3D metrics (`planning.metrics3d`) to the report: True
            computes them, a dict of `evaluate_plan_3d` is used as it is, False skips them.
        grid_metrics: compute the grid metrics (`planning.metrics.evaluate_plan`) of a plan
            made without them (`compute_metrics=False`) for the report. The metrics computed
            here run on threads beside path.csv, the exports and the figures (their time is
            mostly Embree's, the KD-trees', the compiled kernels' and numpy's, outside the
            GIL): the plan command plans without the grid metrics and has them computed
            here.
        reference_table: add the reference's Table 3 (the Santorini caldera) to the reports.
        current: `vehicle.current_feasibility.current_report` of the path, added to report.json
            (`current`) and report.md.
    """
    options = ExportOptions(surge_velocity, tolerance_xy, max_items, ardusub_frames,
                            heave_in_3d)
    exports, geo = check_exports(plan.bathy, exports, origin_lonlat, options)
    mission_time(plan, surge_velocity)  # the speed, checked before any file is written
    outdir = Path(outdir)
    outdir.mkdir(parents=True, exist_ok=True)
    written, extras, missions = [], {}, ()
    grid_metrics = bool(grid_metrics and plan.metrics is None and plan.lawnmower is not None)
    # the metrics on threads beside the writers; the pool waits for them before the GC resumes
    with (phase_display(progress, "outputs",
                        output_stages(exports, figures, metrics_3d, grid_metrics),
                        "path.csv") as display, paused_gc(),
          ThreadPoolExecutor(2, thread_name_prefix="drake_auv-metrics") as background):
        m3d = metrics_3d if isinstance(metrics_3d, dict) else None
        if metrics_3d is True:
            from drake_auv.planning.metrics3d import evaluate_plan_3d

            m3d_job = background.submit(evaluate_plan_3d, plan)
        if grid_metrics:
            from drake_auv.planning.metrics import evaluate_plan

            grid_job = background.submit(evaluate_plan, plan)
        with display.step("path.csv"):
            plan.path.to_csv(outdir / "path.csv")
        written.append(outdir / "path.csv")
        for fmt in EXPORTS.values():
            if fmt.name not in exports:
                continue
            with display.step(fmt.stage):
                exported = fmt.write(plan, geo, outdir, options, missions)
            written += exported.files
            if exported.figures is not None:
                extras[fmt.name] = exported.figures
            missions += exported.missions
        pictures = []
        if figures:
            from drake_auv.planning.figures import write_figures

            pictures = write_figures(plan, outdir, progress=display, geo=geo)
        if grid_metrics:
            with display.step("grid metrics"):
                plan = replace(plan, metrics=grid_job.result())
        if metrics_3d is True:
            with display.step("3D metrics"):
                m3d = m3d_job.result()
        with display.step("reports"):
            rep = report_dict(plan, m3d, surge_velocity, reference_table, extras)
            markdown = report_markdown(plan, rep, m3d, export_warnings(rep),
                                       export_notes(rep))
            if current is not None:
                from drake_auv.vehicle.current_feasibility import current_markdown

                markdown = markdown.rstrip("\n") + "\n\n" + current_markdown(current)
                rep["current"] = current
            write_text(outdir / "report.md", markdown)
            write_json(outdir / "report.json", rep)
        written += [outdir / "report.md", outdir / "report.json"] + pictures
    return written
