"""Runs a campaign's missing runs on a Dask distributed cluster, writing rows as they finish.

`connect` gives a `Client`: by default on a `LocalCluster` of this machine's cores (worker
processes, one thread each: a mission is single-threaded Python and Drake; the cluster listens
on 127.0.0.1 only), or on a user's scheduler (`tcp://HOST:8786`), which `probe_scheduler` first
asks for its identity within `CONNECT_TIMEOUT_S`: a port that is not Dask's (a dashboard's HTTP
port, a service sending a banner) would otherwise hang `Client()` or make it read the banner
as a frame length. `run_campaign` submits one task per run not yet in `results.csv`; the
client appends each row when its task completes; a row that cannot be written stops the
campaign (the other tasks cancelled, the rows written kept). A worker that dies
mid-run has its task rescheduled by the scheduler on another worker (up to
`distributed.scheduler.allowed-failures` times, then the row is "failed" with the error), and
since only this process writes, no row is lost or written twice.
"""

from __future__ import annotations

import asyncio
import logging


from drake_auv.campaign.results import ResultsFile
from drake_auv.campaign.task import one_line, run_task
from drake_auv.progress import RunProgress
from drake_auv.resources import usable_cores

CONNECT_TIMEOUT_S = 10.0


class CampaignError(ValueError):
    """A campaign that cannot start (an unreachable scheduler, a bad worker count)."""


def require_dask() -> None:
    """CampaignError (one line: the import's own error) when Dask's `distributed` does not
    load: it comes with the `campaign` extra, not with the core install."""
    try:
        import distributed  # noqa: F401
    except ImportError as err:
        raise CampaignError(f"campaigns run on Dask, which does not load ({one_line(err)}); "
                            "allowed: an install with the campaign extra, "
                            "pip install 'drake_auv[campaign]'") from None


def check_workers(workers: int | None) -> int:
    """The local worker count (default: the usable cores); CampaignError outside [1, twice the
    usable cores]: a dive is CPU-bound, more processes than that only add memory and start-up
    (1000 workers leaked semaphores and never finished a 12 s campaign)."""
    cores = usable_cores()
    workers = workers if workers is not None else cores
    if not 1 <= workers <= 2 * cores:
        raise CampaignError(f"--workers {workers}: this machine has {cores} usable core(s); "
                            f"allowed: an integer in [1, {2 * cores}] (or --scheduler for a "
                            "cluster)")
    return workers


async def _identity(address: str) -> dict:
    from distributed.comm import connect as comm_connect

    comm = await comm_connect(address, timeout=CONNECT_TIMEOUT_S)
    try:
        await comm.write({"op": "identity"})
        return await comm.read()
    finally:
        comm.abort()


def probe_scheduler(address: str) -> dict:
    """The identity of the Dask scheduler at `address`, asked within `CONNECT_TIMEOUT_S` s
    (the handshake included); CampaignError (one line) for anything else there."""
    allowed = ("allowed: the address of a running Dask scheduler, e.g. tcp://HOST:8786 (not "
               "its dashboard's HTTP port; see docs/campaigns.md)")
    try:
        reply = asyncio.run(asyncio.wait_for(_identity(address), CONNECT_TIMEOUT_S))
    except (TimeoutError, asyncio.TimeoutError):
        raise CampaignError(f"cannot reach the Dask scheduler at {address} (no Dask answer "
                            f"within {CONNECT_TIMEOUT_S:g} s: nothing listening there, or not "
                            f"Dask); {allowed}") from None
    except MemoryError:  # a banner's bytes read as a frame's length
        raise CampaignError(f"cannot reach the Dask scheduler at {address} (it answered, but "
                            f"not in Dask's protocol); {allowed}") from None
    except Exception as err:  # noqa: BLE001 - refused, unknown protocol, a malformed answer
        raise CampaignError(f"cannot reach the Dask scheduler at {address} ({one_line(err)});"
                            f" {allowed}") from None
    if not isinstance(reply, dict) or reply.get("type") != "Scheduler":
        raise CampaignError(f"cannot reach the Dask scheduler at {address} (it answered, but "
                            f"is no scheduler: {str(reply)[:80]!r}); {allowed}")
    return reply


def connect(workers: int | None = None, scheduler: str | None = None):
    """(client, cluster): a Client on `scheduler` (probed first), or on a new LocalCluster of
    `workers` processes on 127.0.0.1 (default: this machine's cores), cluster None for a
    user's scheduler."""
    from distributed import Client, LocalCluster

    if scheduler is not None:
        probe_scheduler(scheduler)
        try:
            return Client(scheduler, timeout=CONNECT_TIMEOUT_S), None
        except (OSError, TimeoutError, ValueError) as err:
            raise CampaignError(f"cannot reach the Dask scheduler at {scheduler} "
                                f"({one_line(err)}); allowed: the address of a running "
                                "scheduler, e.g. tcp://HOST:8786 (see docs/campaigns.md)"
                                ) from None
    cluster = LocalCluster(n_workers=check_workers(workers), threads_per_worker=1,
                           processes=True, host="127.0.0.1", dashboard_address="127.0.0.1:0",
                           silence_logs=logging.ERROR)
    return Client(cluster), cluster


def run_campaign(runs, results: ResultsFile, client, progress: bool = True,
                 retries: int = 1, task=run_task, desc: str = "campaign") -> dict:
    """Runs the `runs` (`CampaignRun`) whose key is not in `results`, on `client`; returns
    counts {total, skipped, ok, failed, contact}. `retries`: resubmissions of a task that
    raised (the task itself turns a mission's errors into failed rows); `task`: the function
    a worker calls on a run's mission (default `run_task`); `desc`: the progress display's phase name.
    A row that cannot be written raises CampaignError (one line) once the other tasks are
    cancelled."""
    from distributed import as_completed

    done = results.done()
    todo = [run for run in runs if run.key not in done]
    counts = dict(total=len(runs), skipped=len(runs) - len(todo), ok=0, failed=0, contact=0)
    if not todo:
        return counts
    futures = {client.submit(task, run.mission, pure=False, retries=retries): run
               for run in todo}
    display = RunProgress((desc,), enabled=progress)
    display.start(desc, len(todo), f"{len(todo)} runs")
    finished = False
    try:
        for future in as_completed(futures):
            run = futures.pop(future)
            if future.status == "finished":
                row = future.result()
            else:  # e.g. KilledWorker after too many worker deaths
                row = dict(status="failed", error=one_line(future.exception()))
            try:
                results.append(run.key, row)
            except OSError as err:
                client.cancel(list(futures))
                futures.clear()
                written = counts["ok"] + counts["failed"]
                raise CampaignError(
                    f"{results.path}: cannot write the row of run {', '.join(run.key)} "
                    f"({one_line(err)}); the campaign stopped: {written} row(s) written now "
                    f"kept, {len(todo) - written} run(s) not written; allowed: a writable "
                    "results.csv (rerun the same command to run the rest)") from None
            counts[row["status"]] += 1
            counts["contact"] += bool(row.get("contact"))
            display.advance(1, f"{counts['ok'] + counts['failed']}/{len(todo)} runs, "
                               f"{counts['failed']} failed, {counts['contact']} in contact")
            future.release()
        finished = True
    finally:
        display.close(completed=finished)
        client.cancel(list(futures))
    return counts
