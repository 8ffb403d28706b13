"""Runs a campaign's missing runs on a Dask distributed cluster, writing rows as they finish.

`connect` gives a `Client`: by default on a `LocalCluster` of this machine's cores (worker
processes, one thread each: a mission is single-threaded Python and Drake), or on a user's
scheduler (`tcp://HOST:8786`). `run_campaign` submits one task per run not yet in
`results.csv`; the client appends each row when its task completes. A worker that dies
mid-run has its task rescheduled by the scheduler on another worker (up to
`distributed.scheduler.allowed-failures` times, then the row is "failed" with the error), and
since only this process writes, no row is lost or written twice.
"""

from __future__ import annotations

import logging
import os

from tqdm import tqdm

from drake_auv.campaign.results import ResultsFile
from drake_auv.campaign.task import one_line, run_task

CONNECT_TIMEOUT_S = 10.0


class CampaignError(ValueError):
    """A campaign that cannot start (an unreachable scheduler, a bad worker count)."""


def connect(workers: int | None = None, scheduler: str | None = None):
    """(client, cluster): a Client on `scheduler`, or on a new LocalCluster of `workers`
    processes (default: this machine's cores), cluster None for a user's scheduler."""
    from distributed import Client, LocalCluster

    if scheduler is not None:
        try:
            return Client(scheduler, timeout=CONNECT_TIMEOUT_S), None
        except (OSError, TimeoutError, ValueError) as err:
            raise CampaignError(f"cannot reach the Dask scheduler at {scheduler} "
                                f"({one_line(err)}); allowed: the address of a running "
                                "scheduler, e.g. tcp://HOST:8786 (see docs/campaigns.md)"
                                ) from None
    workers = workers if workers is not None else (os.cpu_count() or 1)
    if workers < 1:
        raise CampaignError(f"--workers {workers}: allowed: an integer >= 1")
    cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                           dashboard_address=":0", silence_logs=logging.ERROR)
    return Client(cluster), cluster


def run_campaign(runs, results: ResultsFile, client, progress: bool = True,
                 retries: int = 1) -> dict:
    """Runs the `runs` (`CampaignRun`) whose key is not in `results`, on `client`; returns
    counts {total, skipped, ok, failed}. `retries`: resubmissions of a task that raised
    (the task itself turns a mission's errors into failed rows)."""
    from distributed import as_completed

    done = results.done()
    todo = [run for run in runs if run.key not in done]
    counts = dict(total=len(runs), skipped=len(runs) - len(todo), ok=0, failed=0, contact=0)
    if not todo:
        return counts
    futures = {client.submit(run_task, run.mission, pure=False, retries=retries): run
               for run in todo}
    bar = tqdm(total=len(todo), unit="run", desc="campaign", disable=not progress)
    try:
        for future in as_completed(futures):
            run = futures.pop(future)
            if future.status == "finished":
                row = future.result()
            else:  # e.g. KilledWorker after too many worker deaths
                row = dict(status="failed", error=one_line(future.exception()))
            results.append(run.key, row)
            counts[row["status"]] += 1
            counts["contact"] += bool(row.get("contact"))
            bar.update(1)
            bar.set_postfix(failed=counts["failed"], contact=counts["contact"])
            future.release()
    finally:
        bar.close()
        client.cancel(list(futures))
    return counts
