"""The view planner's paths: its grid search + STOMP against OMPL, on the
path queries of real exploration dives (results: docs/exploration_paths.md).

`record` flies a mission (default `boulder_explore`) for each seed of `--seeds` (`A:B`),
`limits.max_time_s` set to `--max-time`, with `drake_auv.exploration.planner.plan_path` and
`candidate_viewpoints` wrapped in this process only: every path query writes
`<out>/seed<S>_q<NNNN>.npz` with the `TravelField`'s inputs (every field of its `LabelGrid`,
the `PathCost`'s clearance and weights, `passable`, the start), the goal, STOMP's seed, the
path returned (none: `solved` false), the call's wall time and the step's candidate
viewpoints. Drake is needed (the project venv):

    .venv/bin/python benchmarks/bench_view_paths.py record --seeds 0:8 --out out/view_paths

`compare` replays the recorded queries. Each query's `TravelField` is rebuilt from the grid
and start (and checked equal to the recorded `passable`); every planner gets the same
validity, `paths.path_clear`'s rule at a point: inside the grid, on a passable cell (the
goal's cell exempt, as `path_clear` exempts the last point; the start's cell valid whatever
it holds, as `path_clear` skips the first point and OMPL needs a valid start), `KEEP`
clearances from occupied cell centres (the distance field read at the point's cell) and half
a clearance above the region's floor. Planners:
- `ours`: `paths.plan_path` (Dijkstra's grid path, STOMP-smoothed, accepted by `path_clear`
  on its points), re-run for its time (the `TravelField` given, as in the planner, which
  builds it once per step for every candidate; its build time reported apart);
- OMPL (when `ompl` imports; not in the project venv): a `RealVectorStateSpace(3)` bounded by
  the grid, the validity above as a Python callback, motions checked every `--check-step`
  (0.25 m); RRTConnect + `simplifySolution`, and BITstar with the path-length objective for
  a fixed time (`--planners NAME:ms,...`). Solve time: setup + solve (+ simplify), wall.
Per planner: success, solve time median / p95, path length over ours (the queries both
solved), and on the path resampled every 0.1 m: the least distance to an occupied cell
centre and to an occupied or unknown one (median, worst), the share of paths valid
throughout (and by the rock part of the rule alone), the paths nearer rock than `KEEP`
clearances and than their own start; and the share passing `path_clear` on their own points.
Then, on `--candidate-steps` steps, what OMPL needs for what the one Dijkstra gives (every
candidate's travel length): one RRTConnect solve per candidate, and one PRM roadmap queried
per candidate. `--markdown` writes the tables with the machine line. With no command,
`record` then `compare` run with their defaults (`make bench`).

    python3.13 -m venv /tmp/ompl313 && /tmp/ompl313/bin/pip install ompl==2.0.1 numpy scipy
    /tmp/ompl313/bin/python benchmarks/bench_view_paths.py compare --queries out/view_paths
"""

from __future__ import annotations

import argparse
import dataclasses
import importlib
import importlib.metadata
import math
import os
import sys
import time
from pathlib import Path

import numpy as np
from scipy.spatial import cKDTree

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
# numpy/scipy only below: `compare` runs in a Python without Drake
from _reference import machine  # noqa: E402
from drake_auv.exploration.frontiers import OCCUPIED, UNKNOWN, LabelGrid  # noqa: E402
from drake_auv.exploration.paths import KEEP, PathCost, TravelField, plan_path  # noqa: E402
from drake_auv.planning.polyline import length, resample  # noqa: E402

COST_FIELDS = ("clearance", "rock_weight", "unknown_weight", "depth_weight")
CHECK_STEP, SAMPLE_STEP = 0.25, 0.1  # m: OMPL's motion checks, the metrics' resampling
DEFAULT_PLANNERS = "RRTConnect:1000,BITstar:50,BITstar:200"


@dataclasses.dataclass(frozen=True)
class Query:
    """One recorded `plan_path` call: its `TravelField` (rebuilt), goal (3,) m, STOMP's seed,
    the path it returned ((N, 3) m, or None), the call's wall time, ms, the step's candidate
    viewpoints (c, 3) m and how many of the nearest reachable the planner gain-scores."""

    travel: TravelField
    goal: np.ndarray
    seed: int
    path: np.ndarray | None
    ms: float
    candidates: np.ndarray
    max_candidates: int


def save_query(file, travel: TravelField, goal, seed: int, path, ms: float,
               candidates=np.empty((0, 3)), max_candidates: int = 0) -> None:
    """Writes one `plan_path` call to `file` (.npz): see the module; `candidates` (c, 3) m:
    the step's candidate viewpoints, of which the planner gain-scores the `max_candidates`
    nearest reachable."""
    grid, cost = travel.cost.grid, travel.cost
    arrays = {f"grid_{f.name}": np.asarray(getattr(grid, f.name))
              for f in dataclasses.fields(grid) if getattr(grid, f.name) is not None}
    arrays.update({f"cost_{name}": np.float64(getattr(cost, name)) for name in COST_FIELDS})
    np.savez_compressed(file, **arrays, passable=travel.passable, start=travel.start,
                        goal=np.asarray(goal, float)[:3], seed=np.int64(seed),
                        solved=np.bool_(path is not None),
                        path=np.empty((0, 3)) if path is None else np.asarray(path, float),
                        ms=np.float64(ms), candidates=np.asarray(candidates, float),
                        max_candidates=np.int64(max_candidates))


def load_query(file) -> Query:
    """Reads a `save_query` file; its `TravelField` is rebuilt and must give the recorded
    passable cells (else this `paths.py` is not the one that recorded it)."""
    try:
        with np.load(file) as data:
            fields = {k[5:]: data[k] for k in data.files if k.startswith("grid_")}
            grid = LabelGrid(**{k: v.item() if v.ndim == 0 else v for k, v in fields.items()})
            cost = PathCost(grid, **{n: float(data[f"cost_{n}"]) for n in COST_FIELDS})
            start, passable, goal, seed, solved, path, ms, candidates, limit = (
                data[k] for k in ("start", "passable", "goal", "seed", "solved", "path", "ms",
                                  "candidates", "max_candidates"))
    except (OSError, ValueError, KeyError, TypeError) as err:
        raise ValueError(f"{file}: not a bench_view_paths query ({err}); allowed: a file "
                         "written by `bench_view_paths.py record`") from None
    travel = TravelField.build(cost, start)
    if not np.array_equal(travel.passable, passable):
        raise ValueError(f"{file}: the rebuilt TravelField's passable cells differ from the "
                         "recorded ones (recorded by another paths.py?)")
    return Query(travel, goal, int(seed), path if bool(solved) else None, float(ms),
                 candidates, int(limit))


def record(mission: str, seeds, max_time: float, out: Path) -> int:
    """Flies `mission` for `seeds`, `plan_path` wrapped to `save_query` every call (with the
    step's candidate viewpoints: `candidate_viewpoints` wrapped too); returns the number of
    queries written."""
    import drake_auv.exploration.planner as planner
    from drake_auv.mission.config import load_mission
    from drake_auv.mission.runner import run_mission

    originals = planner.plan_path, planner.candidate_viewpoints
    limit = planner.ExploreParameters.__dataclass_fields__["max_candidates"].default
    total = 0
    out.mkdir(parents=True, exist_ok=True)
    for seed in seeds:
        for old in out.glob(f"seed{seed}_q*.npz"):  # a shorter dive leaves none behind
            old.unlink()
        calls, step = [], {}

        def candidates(*args, **kwargs):
            step["candidates"] = originals[1](*args, **kwargs)
            return step["candidates"]

        def recording(travel, goal, *args, **kwargs):
            t = time.perf_counter()
            path = originals[0](travel, goal, *args, **kwargs)
            ms = 1e3 * (time.perf_counter() - t)
            save_query(out / f"seed{seed}_q{len(calls):04d}.npz", travel, goal,
                       kwargs.get("seed", 0), path, ms, step["candidates"].positions, limit)
            calls.append(ms)
            return path

        spec = load_mission(mission, seed=seed, overrides=[f"limits.max_time_s={max_time}"])
        planner.plan_path, planner.candidate_viewpoints = recording, candidates
        t = time.perf_counter()
        try:
            run_mission(spec, progress=False)
        finally:
            planner.plan_path, planner.candidate_viewpoints = originals
        print(f"seed {seed}: {len(calls)} queries, dive {time.perf_counter() - t:.0f} s wall",
              flush=True)
        total += len(calls)
    return total


class Validity:
    """`path_clear`'s rule at a point (see the module), for the `TravelField` of a query with
    `goal`: `points(p)` vectorised, `__call__(state)` one OMPL state."""

    def __init__(self, travel: TravelField, goal):
        cost, grid = travel.cost, travel.cost.grid
        rock_ok = cost.rock >= travel.keep.reshape(grid.labels.shape) - 1e-9
        self.ok = travel.passable.reshape(grid.labels.shape) & rock_ok
        for p, rule in ((goal, rock_ok), (travel.start, np.ones_like(rock_ok))):
            idx, inside = grid.index(np.asarray(p, float)[:3])
            if inside:  # path_clear excepts the goal from passable, the start from all
                self.ok[tuple(idx)] = rule[tuple(idx)]
        self.grid, self.floor = grid, float(grid.region[2] + 0.5 * cost.clearance)
        self._o, self._c, self._n = grid.origin.tolist(), grid.cell, grid.labels.shape

    def points(self, points) -> np.ndarray:
        """(...) whether each of `points` (..., 3) is valid."""
        points = np.asarray(points, float)
        idx, inside = self.grid.index(points)
        return inside & self.ok[tuple(np.moveaxis(idx, -1, 0))] & (points[..., 2] >= self.floor)

    def __call__(self, s) -> bool:
        (ox, oy, oz), c, (nx, ny, nz) = self._o, self._c, self._n
        i, j, k = math.floor((s[0] - ox) / c), math.floor((s[1] - oy) / c), math.floor(
            (s[2] - oz) / c)
        return bool(0 <= i < nx and 0 <= j < ny and 0 <= k < nz and s[2] >= self.floor
                    and self.ok[i, j, k])


def min_clearance(grid: LabelGrid, path, labels=(OCCUPIED,)) -> float:
    """Least distance (m) from `path` (N, 3), resampled every 0.1 m, to a cell centre of
    `grid` labelled one of `labels` (inf when none is)."""
    occupied = grid.centres(np.argwhere(np.isin(grid.labels, labels)))
    if not len(occupied):
        return math.inf
    return float(cKDTree(occupied).query(resample(np.asarray(path, float), SAMPLE_STEP))[0].min())


def encroaches(grid: LabelGrid, path, keep: float) -> bool:
    """Whether `path` (N, 3), resampled every 0.1 m, comes after its start nearer an occupied
    cell centre than both `keep` m and its start is (a vehicle already too near rock is
    not the path's fault)."""
    occupied = grid.centres(np.argwhere(grid.labels == OCCUPIED))
    if not len(occupied):
        return False
    d = cKDTree(occupied).query(resample(np.asarray(path, float), SAMPLE_STEP))[0]
    return bool(d[1:].min() < min(keep, d[0]) - 1e-9) if len(d) > 1 else False


def path_valid(validity: Validity, path) -> bool:
    """Whether `path` (N, 3) resampled every 0.1 m is valid after its start."""
    return bool(validity.points(resample(np.asarray(path, float), SAMPLE_STEP)[1:]).all())


def _setup(travel: TravelField, goal, check_step: float):
    """(SimpleSetup, state space) in the grid's box, the query's validity, its start and
    `goal`."""
    from ompl import base as ob, geometric as og

    grid = travel.cost.grid
    space = ob.RealVectorStateSpace(3)
    bounds = ob.RealVectorBounds(3)
    hi = grid.origin + np.array(grid.labels.shape) * grid.cell
    for k in range(3):
        bounds.setLow(k, float(grid.origin[k]))
        bounds.setHigh(k, float(hi[k]))
    space.setBounds(bounds)
    ss = og.SimpleSetup(space)
    ss.setStateValidityChecker(Validity(travel, goal))
    ss.getSpaceInformation().setStateValidityCheckingResolution(
        check_step / space.getMaximumExtent())
    ss.setStartAndGoalStates(_state(space, travel.start), _state(space, goal))
    return ss, space


def _state(space, point):
    state = space.allocState()
    for k in range(3):
        state[k] = float(point[k])
    return state


def _path(ss) -> np.ndarray:
    p = ss.getSolutionPath()
    return np.array([[p.getState(i)[k] for k in range(3)] for i in range(p.getStateCount())])


def ompl_plan(travel: TravelField, goal, planner: str, limit_s: float,
              check_step: float = CHECK_STEP):
    """One OMPL solve: (path (P, 3) m or None, wall s of setup + solve + simplify), motions
    checked every `check_step` m."""
    from ompl import base as ob, geometric as og

    t = time.perf_counter()
    ss, _ = _setup(travel, goal, check_step)
    si = ss.getSpaceInformation()
    if planner != "RRTConnect":
        ss.setOptimizationObjective(ob.PathLengthOptimizationObjective(si))
    ss.setPlanner(getattr(og, planner)(si))
    ss.solve(limit_s)
    path = None
    if ss.haveExactSolutionPath():
        if planner == "RRTConnect":
            ss.simplifySolution()
        path = _path(ss)
    return path, time.perf_counter() - t


def prm_all(travel: TravelField, goals, grow_s: float, limit_s: float,
            check_step: float = CHECK_STEP):
    """One PRM roadmap for a step, grown `grow_s` from the start, then one query per goal of
    `goals` (g, 3) on it (each `limit_s` at most): ((g,) solved, (g,) path length m (nan:
    none), wall s in all)."""
    from ompl import geometric as og

    t = time.perf_counter()
    ss, space = _setup(travel, goals[0], check_step)
    prm = og.PRM(ss.getSpaceInformation())
    ss.setPlanner(prm)
    ss.setup()
    prm.growRoadmap(grow_s)
    solved, lengths = [], []
    for goal in goals:
        prm.clearQuery()
        ss.getProblemDefinition().clearSolutionPaths()
        ss.setGoalState(_state(space, goal))
        ss.solve(limit_s)
        solved.append(ss.haveExactSolutionPath())
        lengths.append(length(_path(ss)) if solved[-1] else math.nan)
    return np.array(solved, bool), np.array(lengths), time.perf_counter() - t


def rock_clear(travel: TravelField, path) -> bool:
    """Whether `path` (N, 3) resampled every 0.1 m keeps `KEEP` clearances from occupied cell
    centres after its start (the rock part of the validity alone)."""
    rock, _ = travel.cost.distances(resample(np.asarray(path, float), SAMPLE_STEP)[1:])
    return bool(np.all(rock >= KEEP * travel.cost.clearance))


def metrics(query: Query, path, ours) -> tuple[float, float, float, bool, bool, bool]:
    """(length over ours (nan when either is missing), min clearance to occupied and to
    occupied or unknown cells m, valid at 0.1 m, rock clear at 0.1 m, `encroaches` on
    `KEEP` clearances) of `path` for `query`; (nan, nan, nan, False, False, False) when there
    is none."""
    if path is None:
        return math.nan, math.nan, math.nan, False, False, False
    cost = query.travel.cost
    ratio = length(path) / length(ours) if ours is not None and length(ours) > 0 else math.nan
    return (ratio, min_clearance(cost.grid, path),
            min_clearance(cost.grid, path, (OCCUPIED, UNKNOWN)),
            path_valid(Validity(query.travel, query.goal), path), rock_clear(query.travel, path),
            encroaches(cost.grid, path, KEEP * cost.clearance))


def _stats(x, fmt="{:.1f}") -> str:
    x = np.asarray([v for v in x if np.isfinite(v)], float)
    if not len(x):
        return "-"
    return f"{fmt.format(np.median(x))} / {fmt.format(np.percentile(x, 95))}"


def compare(queries: list[Query], planners: list[tuple[str, float]],
            check_step: float = CHECK_STEP) -> list[str]:
    """The table's rows (markdown) for ours and each (OMPL planner, time limit s)."""
    from drake_auv.exploration.paths import path_clear

    build, rerun, same, chord = [], [], 0, 0
    for q in queries:
        chord += path_valid(Validity(q.travel, q.goal), [q.travel.start, q.goal])
        t = time.perf_counter()
        TravelField.build(q.travel.cost, q.travel.start)
        build.append(1e3 * (time.perf_counter() - t))
        t = time.perf_counter()
        again = plan_path(q.travel, q.goal, seed=q.seed)
        rerun.append(1e3 * (time.perf_counter() - t))
        same += (again is None) == (q.path is None) and (again is None or np.allclose(again,
                                                                                      q.path))
    runs = {"ours (grid search + STOMP)": ([q.path for q in queries], rerun)}
    for name, limit in planners:
        paths, times = [], []
        for q in queries:
            path, wall = ompl_plan(q.travel, q.goal, name, limit, check_step)
            paths.append(path)
            times.append(1e3 * wall)
        label = (f"OMPL {name} {1e3 * limit:.0f} ms, checks every {check_step:g} m"
                 + (" + simplify" if name == "RRTConnect" else ", path length"))
        runs[label] = (paths, times)
    rows = [f"{len(queries)} queries, the straight line valid in {chord}; ours re-run gives "
            f"the recorded path in {same}; "
            f"TravelField.build (the Dijkstra for every candidate, once a step) ms median / "
            f"p95 {_stats(build)}; recorded plan_path ms {_stats([q.ms for q in queries])}", "",
            "| planner | success | solve ms median / p95 | length / ours median / p95 | "
            "min clearance m median / worst | to rock or unknown m median / worst | "
            "valid at 0.1 m | rock-clear at 0.1 m | nearer rock than KEEP clearances and its "
            "start | path_clear on its points |", "| --- " * 10 + "|"]
    for label, (paths, times) in runs.items():
        m = np.array([metrics(q, p, q.path) for q, p in zip(queries, paths)], float)
        ok = np.array([p is not None for p in paths])
        clear = np.mean([path_clear(q.travel, p) for q, p in zip(queries, paths) if p is not None])
        near = [f"{np.median(m[ok, k]):.2f} / {m[ok, k].min():.2f}" if ok.any() else "-"
                for k in (1, 2)]
        rows.append(f"| {label} | {ok.mean():.0%} ({ok.sum()}/{len(ok)}) | {_stats(times)} | "
                    f"{_stats(m[:, 0], '{:.3f}')} | {near[0]} | {near[1]} | "
                    f"{m[ok, 3].mean():.0%} | {m[ok, 4].mean():.0%} | {m[ok, 5].sum():.0f} | "
                    f"{clear:.0%} |")
    return rows


def all_candidates(queries: list[Query], limit_s: float, check_step: float = CHECK_STEP,
                   grow_s: float = 0.3):
    """What OMPL needs where the planner's one Dijkstra gives every candidate's travel
    length: rows (markdown) over `queries`, each step's candidates (the `max_candidates`
    nearest reachable and every unreachable one) solved by RRTConnect one at a time with
    `limit_s`, and by one PRM roadmap grown `grow_s`, queried per candidate (`limit_s`)."""
    rows = []
    for q in queries:
        lengths = q.travel.lengths(q.candidates)
        reach = np.flatnonzero(np.isfinite(lengths))
        reach = reach[np.argsort(lengths[reach], kind="stable")[:q.max_candidates]]
        unreach = np.flatnonzero(~np.isfinite(lengths))
        t = time.perf_counter()
        TravelField.build(q.travel.cost, q.travel.start)
        dijkstra = 1e3 * (time.perf_counter() - t)
        solved, wall = [], []
        for k in np.concatenate([reach, unreach]):
            path, w = ompl_plan(q.travel, q.candidates[k], "RRTConnect", limit_s, check_step)
            solved.append(path is not None)
            wall.append(1e3 * w)
        solved, wall = np.array(solved, bool), np.array(wall)
        n = len(reach)
        prm_ok, _, prm_wall = prm_all(q.travel, q.candidates[np.concatenate([reach, unreach])],
                                      grow_s, limit_s, check_step)
        rows.append((n, len(unreach), solved[:n].sum(), solved[n:].sum(), dijkstra,
                     wall[:n].sum(), wall[n:].sum(), prm_ok[:n].sum(), prm_ok[n:].sum(),
                     1e3 * prm_wall))
    r = np.array(rows, float)
    share = max(r[:, 0].sum(), 1)
    return [f"| {len(r)} steps | {np.median(r[:, 0]):.0f} / {np.median(r[:, 1]):.0f} | "
            f"{_stats(r[:, 4])} | {r[:, 2].sum() / share:.0%} / {r[:, 3].sum():.0f} | "
            f"{_stats(r[:, 5])} | {_stats(r[:, 6])} | {_stats(r[:, 5] + r[:, 6])} | "
            f"{r[:, 7].sum() / share:.0%} / {r[:, 8].sum():.0f} | {_stats(r[:, 9])} |"]


def _planners(text: str) -> list[tuple[str, float]]:
    out = []
    for part in text.split(","):
        name, _, ms = part.partition(":")
        try:
            limit = float(ms) / 1e3
        except ValueError:
            limit = -1.0
        if not name or limit <= 0:
            raise ValueError(f"--planners: {part!r} is not NAME:ms; allowed: comma-separated "
                             f"OMPL geometric planners with a time limit > 0 ms, e.g. "
                             f"{DEFAULT_PLANNERS}")
        out.append((name, limit))
    return out


def _record(args) -> list[str]:
    try:  # Drake and the mission's packages
        for name in ("drake_auv.exploration.planner", "drake_auv.mission.runner"):
            importlib.import_module(name)
        from drake_auv.campaign.grid import parse_seeds
    except ImportError as err:
        raise ValueError(f"record needs the project's Python with Drake ({err})") from None
    if not args.max_time > 0:
        raise ValueError(f"--max-time: {args.max_time} s; allowed: > 0")
    seeds = parse_seeds(args.seeds)
    return [f"{record(args.mission, seeds, args.max_time, args.out)} queries in {args.out}"]


def _compare(args) -> list[str]:
    files = sorted(args.queries.glob("*.npz"))
    if not files:
        raise FileNotFoundError(f"--queries: no .npz in {args.queries}; allowed: a folder "
                                "written by `bench_view_paths.py record`")
    planners = _planners(args.planners)
    for name, value, low in (("--check-step", args.check_step, 0.0),
                             ("--candidate-limit-ms", args.candidate_limit_ms, 0.0)):
        if not value > low:
            raise ValueError(f"{name}: {value}; allowed: > {low:g}")
    if args.candidate_steps < 0:
        raise ValueError(f"--candidate-steps: {args.candidate_steps}; allowed: >= 0")
    try:
        from ompl import util as ou

        ou.setLogLevel(ou.LOG_ERROR)
        ou.RNG.setSeed(args.seed + 1)  # time-limited solves still vary run to run
        versions = f"ompl {importlib.metadata.version('ompl')}"
    except ImportError:
        planners, versions = [], "ompl not importable in this Python: ours only"
    queries = [load_query(f) for f in files]
    rows = [machine(), f"{versions}, numpy {np.__version__}; queries from {args.queries}",
            ""] + compare(queries, planners, args.check_step)
    if planners and args.candidate_steps:
        pick = np.unique(np.linspace(0, len(queries) - 1, args.candidate_steps).round())
        rows += ["", f"Every candidate of a step (ms per step, median / p95), against the "
                 f"one Dijkstra: one RRTConnect solve each ({args.candidate_limit_ms:g} ms "
                 f"limit), and one PRM roadmap grown 300 ms then queried per candidate "
                 f"({args.candidate_limit_ms:g} ms limit); checks every "
                 f"{args.check_step:g} m:", "",
                 "| steps | candidates reachable / not (Dijkstra) | Dijkstra ms | "
                 "RRTConnect solved: reachable / unreachable | RRTConnect ms, reachable | "
                 "on unreachable | total | PRM solved: reachable / unreachable | PRM ms "
                 "(grow + queries) |", "| --- " * 9 + "|"]
        rows += all_candidates([queries[int(k)] for k in pick],
                               args.candidate_limit_ms / 1e3, args.check_step)
    if args.markdown is not None:
        args.markdown.write_text("\n".join(rows) + "\n")
    return rows


def main(argv=None) -> int:
    """`record`, `compare`, or with no command both with their defaults (`make bench`)."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command")
    rec = sub.add_parser("record", help="fly dives and record the view planner's path queries")
    rec.add_argument("--mission", default="boulder_explore")
    rec.add_argument("--seeds", default="0:1", help="A:B, seeds A .. B-1 (default 0:1)")
    rec.add_argument("--max-time", type=float, default=1800.0,
                     help="limits.max_time_s (1800)")
    rec.add_argument("--out", type=Path, default=Path("out/view_paths"))
    cmp = sub.add_parser("compare", help="replay the recorded queries with each planner")
    cmp.add_argument("--queries", type=Path, default=Path("out/view_paths"))
    cmp.add_argument("--planners", default=DEFAULT_PLANNERS,
                     help=f"OMPL NAME:ms,... (default {DEFAULT_PLANNERS}); none without ompl")
    cmp.add_argument("--check-step", type=float, default=CHECK_STEP,
                     help=f"OMPL's motion check spacing, m ({CHECK_STEP})")
    cmp.add_argument("--candidate-steps", type=int, default=10,
                     help="steps (evenly drawn queries) whose every candidate RRTConnect "
                          "and PRM solve (10; 0: none)")
    cmp.add_argument("--candidate-limit-ms", type=float, default=100.0,
                     help="time limit per candidate, ms (100)")
    cmp.add_argument("--seed", type=int, default=0, help="OMPL's seed of seeds (0)")
    cmp.add_argument("--markdown", type=Path, default=None)
    args = parser.parse_args(argv)
    runs = [args] if args.command else [parser.parse_args(["record"]),
                                        parser.parse_args(["compare"])]
    try:
        for run in runs:
            print("\n".join(_record(run) if run.command == "record" else _compare(run)),
                  flush=True)
    except (ValueError, FileNotFoundError) as err:
        print(f"bench_view_paths: {err}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    status = main()
    sys.stdout.flush()
    os._exit(status)  # nanobind reports OMPL objects still held at interpreter exit as leaks
