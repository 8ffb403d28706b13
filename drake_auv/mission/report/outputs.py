"""Writing a flown mission's files (`write_outputs`: the report, its figures, the trajectory, the
Diagram and the data products) and the process's peak memory for its timing."""

from __future__ import annotations

import csv
import resource
import time
from pathlib import Path

from drake_auv.mission.report.figures import fig_coverage, fig_coverage_vs_time, fig_distance
from drake_auv.mission.report.markdown import report_markdown
from drake_auv.mission.report.summary import rounded, summarise
from drake_auv.mission.runner import MissionResult
from drake_auv.output_files import open_replacing, replacing, write_json, write_text
from drake_auv.planning.figures import fig_path3d
from drake_auv.progress import RunProgress
from drake_auv.reconstruction.products import (SURFACE_STAGES, products_markdown,
                                               write_products)
from drake_auv.signals import VehicleState, Water


def write_trajectory(result: MissionResult, filename) -> None:
    """`t`, the true pose (`signals.VehicleState`'s `x y z roll pitch yaw`) and the navigation's
    position (`est_x est_y est_z`), in the site's own horizontal coordinates, and the water's
    velocity at the true position (`current_x current_y current_z`, world frame: x east,
    y north, z up, m/s; zeros in still water)."""
    state, estimated = VehicleState(result.log.state), VehicleState(result.log.estimated)
    true_xyz = result.site.to_site(state.position)
    est_xyz = result.site.to_site(estimated.position)
    pose = VehicleState.get_fields()[:6]  # position and attitude
    current = Water(result.log.water).velocity
    with open_replacing(filename, "w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(["t", *pose, *(f"est_{name}" for name in pose[:3]),
                         "current_x", "current_y", "current_z"])
        for t, p, a, e, c in zip(result.log.times, true_xyz, state.attitude, est_xyz, current):
            writer.writerow([f"{t:.2f}", *(f"{v:.3f}" for v in p), *(f"{v:.5f}" for v in a),
                             *(f"{v:.3f}" for v in e), *(f"{v:.4f}" for v in c)])


def peak_rss_mb() -> float:
    """Peak resident memory of this process so far, MiB (`getrusage`: KiB on Linux)."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def write_outputs(result: MissionResult, outdir, dpi: int = 110, setup_s: float | None = None,
                  finish=None, progress: RunProgress | None = None) -> dict:
    """Writes report.json, report.md, coverage.png, coverage_vs_time.png, distance.png, plan.png
    (coverage plans), trajectory.csv, diagram.dot and the data products (points.ply;
    reconstruction.ply and .png with Open3D, `reconstruction.products`) into `outdir`; returns
    the summary.

    `finish(outdir)` (the Meshcat recording, which reads the products) runs after the other
    files and before the report, so that `timing.outputs_s` counts it; `setup_s` is the
    caller's wall time before the simulation (see the module for the `timing` keys).
    `progress`: the run's display, whose `outputs` phase this runs, a step per file (or group
    of files) written."""
    start = time.perf_counter()
    out = Path(outdir)
    out.mkdir(parents=True, exist_ok=True)
    names = ["coverage.png", "distance.png", "coverage_vs_time.png",
             *(["plan.png"] if result.plan.coverage is not None else [])]
    files = [*names, "trajectory.csv", "diagram.dot", *(["mission.html"] if finish else [])]
    progress = progress if progress is not None else RunProgress.off()
    surface = len(SURFACE_STAGES) + 1 if result.spec.outputs.reconstruction else 0
    progress.start("outputs", total=len(files) + 3 + surface, note="summary")
    with progress.step("summary"):
        summary = summarise(result)
    products = time.perf_counter()
    summary["reconstruction"] = rounded(write_products(
        result.mapping.scan_log, result.site, out, dpi,
        surface=result.spec.outputs.reconstruction, progress=progress))
    reconstruction_s = time.perf_counter() - products
    makers = {"coverage.png": lambda: fig_coverage(result),
              "distance.png": lambda: fig_distance(result),
              "coverage_vs_time.png": lambda: fig_coverage_vs_time(
                  result, summary["coverage_vs_time"]),
              "plan.png": lambda: fig_path3d(result.plan.coverage)}
    for name in names:
        with progress.step(name), replacing(out / name) as temporary:
            makers[name]().savefig(temporary, dpi=dpi, bbox_inches="tight")
    with progress.step("trajectory.csv"):
        write_trajectory(result, out / "trajectory.csv")
    with progress.step("diagram.dot"):
        write_text(out / "diagram.dot", result.run.diagram_dot)
    if finish is not None:
        with progress.step("mission.html"):
            finish(out)
    with progress.step("report"):
        outputs_s = time.perf_counter() - start
        summary["timing"].update(rounded(dict(
            setup_s=setup_s, outputs_s=outputs_s, reconstruction_s=reconstruction_s,
            total_s=(setup_s or 0.0) + result.run.wall_s + outputs_s, peak_rss_mb=peak_rss_mb())))
        write_json(out / "report.json", summary)
        write_text(out / "report.md",
                   report_markdown(summary, files) + "\n"
                   + products_markdown(summary["reconstruction"]))
    progress.finish(note=f"written to {out}")
    return summary
