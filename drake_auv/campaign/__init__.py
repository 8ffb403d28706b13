"""Campaigns: seeded Monte Carlo runs of one mission over errors and faults, on Dask.

`grid` expands `--seeds` and `--vary` into runs (validated missions as plain dicts), `task`
flies one run into a metrics row (the function a Dask worker calls), `results` keeps
`results.csv` crash-safe and one row per run, `folder` checks and locks the output folder,
`engine` probes a scheduler and submits the missing runs to a Dask cluster, writing the rows
as they finish, `summary` aggregates them into summary.md/json and plots.
"""

from drake_auv.campaign.engine import (CampaignError, check_workers, connect, probe_scheduler,
                                      run_campaign)
from drake_auv.campaign.folder import check_output, locked
from drake_auv.campaign.grid import CampaignRun, expand_runs, parse_seeds, parse_vary
from drake_auv.campaign.results import ResultsFile, columns
from drake_auv.campaign.summary import wilson_interval, write_summary
from drake_auv.campaign.task import run_task

__all__ = ["CampaignError", "CampaignRun", "ResultsFile", "check_output", "check_workers",
           "columns", "connect", "expand_runs", "locked", "parse_seeds", "parse_vary",
           "probe_scheduler", "run_campaign", "run_task", "wilson_interval", "write_summary"]
