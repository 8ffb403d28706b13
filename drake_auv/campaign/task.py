"""The task a Dask worker runs: one mission (a plain mapping) in, one metrics row out.

The Diagram is built inside the task (Drake Diagrams do not pickle). Every random draw of a
mission is keyed by its seed, so a row depends only on the mission mapping, never on the
worker or on what it ran before, except the wall-clock columns (`TIMING`). Any exception of
the run becomes a row with `status` "failed" and its one-line error.
"""

from __future__ import annotations

import time
import warnings

METRICS = ("coverage_multibeam", "coverage_camera", "min_clearance_m", "contact",
           "distance_mean_m", "distance_min_m", "completed", "aborted", "responses",
           "first_response_s", "sim_s")
TIMING = ("wall_s", "real_time_factor")  # vary with the machine and its load
ERROR_CHARS = 300


def one_line(err: BaseException) -> str:
    """`Type: message` on one line, at most `ERROR_CHARS` characters."""
    text = " ".join(f"{type(err).__name__}: {err}".split())
    return text if len(text) <= ERROR_CHARS else text[:ERROR_CHARS - 3] + "..."


def metrics_row(summary: dict) -> dict:
    """The campaign's metrics of a mission report's `summarise` dict."""
    timing = summary["timing"]
    responses = summary["responses"]
    return dict(
        coverage_multibeam=summary["coverage"]["multibeam"],
        coverage_camera=summary["coverage"]["camera"],
        min_clearance_m=summary["min_clearance_m"], contact=summary["contact"],
        distance_mean_m=summary["distance_to_target"]["mean_m"],
        distance_min_m=summary["distance_to_target"]["min_m"],
        completed=summary["mission"]["completed"],
        aborted=summary["mission"]["aborted"],
        responses=";".join(f"{r['response']}@{r['start_s']:g}s({r['cause']})"
                           for r in responses),
        first_response_s=responses[0]["start_s"] if responses else None,
        sim_s=timing["sim_s"], wall_s=timing["wall_s"],
        real_time_factor=timing["real_time_factor"])


def run_task(mission: dict, row=metrics_row) -> dict:
    """Flies `mission` (a `mission_to_dict` mapping, absolute paths) and returns its row:
    `status` "ok" with the metrics `row` takes from the report's `summarise` dict (default
    `METRICS` and `TIMING`), or "failed" with `error`; never raises an `Exception` (a worker
    killed mid-run is Dask's to retry)."""
    start = time.perf_counter()
    try:
        from drake_auv.mission.config import mission_from_dict
        from drake_auv.mission.report.summary import summarise
        from drake_auv.mission.runner import run_mission

        spec = mission_from_dict(mission, "/", label=str(mission.get("name", "mission")))
        with warnings.catch_warnings():  # empty statistics of a short run are reported as null
            warnings.simplefilter("ignore", RuntimeWarning)
            metrics = row(summarise(run_mission(spec, progress=False)))
        return dict(status="ok", error="", **metrics)
    except Exception as err:  # noqa: BLE001 - a failed run is a row, never a lost campaign
        return dict(status="failed", error=one_line(err),
                    wall_s=round(time.perf_counter() - start, 3))
