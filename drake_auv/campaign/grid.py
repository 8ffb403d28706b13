"""The runs of a campaign: `--seeds A:B` x the Cartesian product of the `--vary` values. Pure.

Every run is validated here, in the client, by loading the mission with its overrides, so a
bad key or value fails before anything is submitted; a run carries its mission as the plain
mapping `mission_to_dict` gives (Drake Diagrams do not pickle: the worker builds the Diagram).
A run's key is its seed and the varied values as typed (`results.csv` holds them as such).
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

from drake_auv.mission.config import MissionFileError, load_mission, mission_to_dict

MAX_RUNS = 100_000  # runs of one campaign or envelope: a year of dives on one core


def check_run_count(count: int, what: str) -> None:
    """ValueError (one line) when `what` gives more than `MAX_RUNS` runs, before any is built
    (`--seeds 0:1000000000` once listed a billion runs and never started)."""
    if count > MAX_RUNS:
        raise ValueError(f"{what} gives {count} runs; allowed: at most {MAX_RUNS} runs in one "
                         "campaign")


@dataclass(frozen=True)
class CampaignRun:
    """One run: `seed`, `values` ((key, value text) per varied key, in `--vary` order) and
    `mission`, the validated mission as a plain mapping (absolute paths)."""

    seed: int
    values: tuple
    mission: dict

    @property
    def key(self) -> tuple:
        """(seed text, value texts...): the row's identity in results.csv."""
        return (str(self.seed), *(text for _, text in self.values))


def parse_seeds(text: str) -> list[int]:
    """`A:B` -> seeds A, A+1, ..., B-1 (B excluded, as a Python range); `A` -> [A]."""
    allowed = "A:B with integers 0 <= A < B (seeds A..B-1), or one integer"
    try:
        if ":" in text:
            a, b = (int(part) for part in text.split(":"))
        else:
            a = int(text)
            b = a + 1
    except ValueError:
        raise ValueError(f"--seeds: {text!r} is not A:B; allowed: {allowed}") from None
    if not 0 <= a < b:
        raise ValueError(f"--seeds: {text!r} is empty or negative; allowed: {allowed}")
    check_run_count(b - a, f"--seeds {text}")
    return list(range(a, b))


def split_values(text: str) -> list[str]:
    """`V1,V2,...` split on the commas outside YAML brackets and quotes, so a value may be a
    flow list or mapping: `[{name: M2, amplitude_mps: 0.1}],none` is two values."""
    parts, depth, quote, start = [], 0, None, 0
    for i, char in enumerate(text):
        if quote:
            quote = None if char == quote else quote
        elif char in "'\"":
            quote = char
        elif char in "[{":
            depth += 1
        elif char in "]}":
            depth -= 1
        elif char == "," and depth == 0:
            parts.append(text[start:i])
            start = i + 1
    return [*parts, text[start:]]


def parse_vary(items) -> list[tuple[str, list[str]]]:
    """`KEY=V1,V2,...` strings -> [(key, [value texts])] (values split on the commas outside
    brackets and quotes, as typed)."""
    out = []
    for item in items:
        key, sep, values = item.partition("=")
        key = key.strip()
        texts = [v.strip() for v in split_values(values)]
        if not sep or not key or not all(texts):
            raise ValueError(f"--vary: {item!r} is not KEY=V1,V2,...; allowed: a dotted key "
                             "of the mission file and comma-separated values, e.g. "
                             "site.prior_error_m=0,2.5,5")
        if key in (k for k, _ in out):
            raise ValueError(f"--vary: {key} is given twice; allowed: each key once")
        if key == "seed":
            raise ValueError("--vary: seed is set by --seeds; allowed: any other dotted key")
        if len(set(texts)) != len(texts):
            raise ValueError(f"--vary: {key} repeats a value in {values!r}; allowed: distinct "
                             "values")
        out.append((key, texts))
    return out


def expand_runs(mission, seeds, vary, overrides=()) -> list[CampaignRun]:
    """Every (seed, variant) run of `mission` (a file or built-in name) with the fixed
    `overrides` and the `vary` lists of `parse_vary`; raises `MissionFileError` naming the
    first bad key or value."""
    check_run_count(len(seeds) * math.prod(len(texts) for _, texts in vary),
                    "--seeds x --vary")
    runs = []
    for combo in itertools.product(*(texts for _, texts in vary)):
        values = tuple((key, text) for (key, _), text in zip(vary, combo))
        sets = [*overrides, *(f"{key}={text}" for key, text in values)]
        try:
            spec = load_mission(mission, seed=seeds[0], overrides=sets)
        except MissionFileError as err:
            raise MissionFileError(err.label.replace("(--set)", "(--vary)"), err.where,
                                   err.what, err.allowed) from None
        base = mission_to_dict(spec)
        for seed in seeds:
            runs.append(CampaignRun(seed, values, {**base, "seed": seed}))
    return runs
