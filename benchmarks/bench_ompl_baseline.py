"""A peer baseline for the replanning step: can an OMPL planner, its state validity
a Python callback on the on-line map, plan one replanning section within the step budget
(map query + planning: median <= 10 ms, p95 <= 25 ms)?

Setting (the breakwater mission, simplified): a 5 x 5 x 10 m block (x, y in [-2.5, 2.5], z in
[-10, 0]) and a neighbour at x in [-12.5, -7.5]; the on-line map is 0.5 m voxel centres on
their side faces and on the seabed (z = -10). The contour is the U at 6 m (horizontal) offset
round the block's east end, at z = -5. A section (seeded): start at the vehicle on the
contour, goal 5-10 m ahead along it, waypoints every 1 m; a second set on a contour at 4 m (a
prior map 2 m off towards the block), where the straight chord of a corner section passes
within the 3 m clearance. Per section:
- map query: the voxels within the planning box widened by 7 m horizontally / 3 m in depth,
  a 3D cKDTree of them (clearance) and a 2D one of the depth band |z + 5| <= 1.5 (offset);
- validity: clearance >= 3 m, `tree.query(p, distance_upper_bound=3.0)` per state, a Python
  callback (also `SliceMap.clearance` per single point, the replanner's batched query);
- RRTConnect in a RealVectorStateSpace(3) bounded by the section's points +- 6 m horizontally,
  +- 4 m in depth, motions checked every 0.25 m, then `simplifySolution()`;
- an optimising planner (RRTstar, BITstar) with the objective integral of |d - 6| ds (d: the
  horizontal distance to the band's voxels, 0.5 m steps along each motion, numpy-vectorised
  in a Python `OptimizationObjective`: OMPL's StateCostIntegralObjective does not call a
  Python stateCost), given 25 ms (and 8 ms, what the median budget leaves, and 250 ms);
- for comparison, this repository's step (`replan_section`, STOMP, cold: no warm start, its
  end free) on the same voxels.
Reported: us per validity check (callback alone), checks per solve, step and solve times
median/p95 (ms, wall), success rate, and for every path the mean |d - 6| (m, path resampled
every 0.1 m) against the section's contour polyline (at the offset) and its straight chord.

Needs the `ompl` wheel (2.0.1 on Python 3.11 measured), not in the project venv (`make bench`
prints one line and moves on):

    python3.11 -m venv /tmp/ompl_venv && /tmp/ompl_venv/bin/pip install ompl numpy scipy
    /tmp/ompl_venv/bin/python benchmarks/bench_ompl_baseline.py [--sections 50] [--seed 0]
"""

from __future__ import annotations

import argparse
import importlib.metadata
import os
import sys
import time

try:
    from ompl import base as ob, geometric as og, util as ou
except ImportError:
    print("bench_ompl_baseline: skipped, `ompl` is not importable in this Python (python3.11 -m "
          "venv /tmp/ompl_venv && /tmp/ompl_venv/bin/pip install ompl numpy scipy)")
    sys.exit(0)

import numpy as np
from scipy.spatial import cKDTree

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
# numpy/scipy only: they import in a Python without Drake
from _reference import machine  # noqa: E402
from drake_auv.planning.polyline import resample  # noqa: E402
from drake_auv.replanning.fields import SliceMap  # noqa: E402
from drake_auv.replanning.parameters import ReplanningParameters  # noqa: E402
from drake_auv.replanning.section import replan_section  # noqa: E402

OMEGA, CLEARANCE, DEPTH, BAND, VOXEL = 6.0, 3.0, -5.0, 1.5, 0.5  # m
CHECK_STEP, COST_STEP = 0.25, 0.5  # m, motion validity / motion cost spacing


def voxels() -> np.ndarray:
    """(N, 3) voxel centres, m: both blocks' side faces, z in [-10, 0], and the seabed."""
    g = np.arange(-2.5, 2.5 + 1e-9, VOXEL)
    z = np.arange(-10.0, 0.0 + 1e-9, VOXEL)
    faces = []
    for cx in (0.0, -10.0):
        for s in (-2.5, 2.5):
            u, w = np.meshgrid(g, z, indexing="ij")
            faces += [np.c_[np.full(u.size, cx + s), u.ravel(), w.ravel()],
                      np.c_[cx + u.ravel(), np.full(u.size, s), w.ravel()]]
    x, y = np.meshgrid(np.arange(-25.0, 20.0 + 1e-9, VOXEL), np.arange(-20.0, 20.0 + 1e-9, VOXEL))
    bed = np.c_[x.ravel(), y.ravel(), np.full(x.size, -10.0)]
    under = (np.abs(bed[:, 1]) < 2.5) & ((np.abs(bed[:, 0]) < 2.5)
                                         | (np.abs(bed[:, 0] + 10) < 2.5))
    return np.unique(np.vstack(faces + [bed[~under]]).round(6), axis=0)


def contour(r: float = OMEGA, step: float = 0.05) -> np.ndarray:
    """(M, 3) the U at offset r round the block's east end, from (-9.5, -2.5 - r) to
    (-9.5, 2.5 + r), m."""
    a = 2.5
    leg = np.arange(-9.5, a, step)
    t = np.arange(-np.pi / 2, np.pi / 2, step / r)
    t1, t2 = t[t < 0], t[t >= 0]
    m = int(2 * a / step)
    xy = np.vstack([np.c_[leg, np.full(leg.size, -a - r)],
                    np.c_[a + r * np.cos(t1), -a + r * np.sin(t1)],
                    np.c_[np.full(m, a + r), np.linspace(-a, a, m)],
                    np.c_[a + r * np.cos(t2), a + r * np.sin(t2)],
                    np.c_[leg[::-1], np.full(leg.size, a + r)]])
    return np.c_[xy, np.full(len(xy), DEPTH)]


def arclength(p: np.ndarray) -> np.ndarray:
    return np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))])


def sections(n: int, seed: int, r: float = OMEGA) -> list[np.ndarray]:
    """n sections (K, 3): points 1 m apart on the contour at offset r from a seeded start,
    5-10 m long."""
    rng = np.random.default_rng(seed)
    c = contour(r)
    s = arclength(c)
    out = []
    for s0, length in zip(rng.uniform(0.0, s[-1] - 10.0, n), rng.uniform(5.0, 10.0, n)):
        q = np.append(np.arange(s0, s0 + length, 1.0), s0 + length)
        out.append(np.column_stack([np.interp(q, s, c[:, k]) for k in range(3)]))
    return out


def offset_error(band: cKDTree, path: np.ndarray) -> tuple[float, float]:
    """Mean |d - OMEGA| (m) along `path` resampled every 0.1 m, and its integral (m^2)."""
    p = resample(path, 0.1)
    e = np.abs(band.query(p[:, :2])[0] - OMEGA)
    return float(e.mean()), float(e.mean() * arclength(p)[-1])


class OffsetObjective(ob.OptimizationObjective):
    """Integral of |d - OMEGA| ds, d the horizontal distance to the band's voxels (m^2)."""

    def __init__(self, si, band: cKDTree):
        super().__init__(si)
        self.band, self.calls = band, 0

    def stateCost(self, s):
        self.calls += 1
        return ob.Cost(abs(self.band.query((s[0], s[1]))[0] - OMEGA))

    def motionCost(self, a, b):
        self.calls += 1
        pa, pb = np.array([a[0], a[1], a[2]]), np.array([b[0], b[1], b[2]])
        length = float(np.linalg.norm(pb - pa))
        w = np.linspace(0.0, 1.0, max(2, int(np.ceil(length / COST_STEP)) + 1))[:, None]
        e = np.abs(self.band.query((pa[:2] + w * (pb[:2] - pa[:2])))[0] - OMEGA)
        return ob.Cost(float((e[1:] + e[:-1]).sum() * 0.5 * length / (len(e) - 1)))


def min_clearance(occupied: np.ndarray, path: np.ndarray) -> float:
    """Smallest 3D distance (m) from `path`, resampled every 0.1 m, to any voxel."""
    return float(cKDTree(occupied).query(resample(path, 0.1))[0].min())


def map_query(occupied: np.ndarray, lo: np.ndarray, hi: np.ndarray):
    """The voxels near the planning box: a 3D tree (clearance) and a 2D one of the band."""
    pad = np.array([OMEGA + 1.0, OMEGA + 1.0, CLEARANCE])
    local = occupied[np.all((occupied >= lo - pad) & (occupied <= hi + pad), axis=1)]
    in_band = np.abs(local[:, 2] - DEPTH) <= BAND
    return local, cKDTree(local), cKDTree(local[in_band, :2])


def plan(section, tree, band, planner: str, time_limit: float, checker=None):
    """One solve: (solved exactly, path (P, 3), validity checks in solve / simplify, solve s,
    simplify s, objective calls)."""
    lo = section.min(axis=0) - [6.0, 6.0, 4.0]
    hi = section.max(axis=0) + [6.0, 6.0, 4.0]
    space = ob.RealVectorStateSpace(3)
    bounds = ob.RealVectorBounds(3)
    for k in range(3):
        bounds.setLow(k, float(lo[k]))
        bounds.setHigh(k, float(hi[k]))
    space.setBounds(bounds)
    ss = og.SimpleSetup(space)
    si = ss.getSpaceInformation()
    checks = [0]

    def valid(s):
        checks[0] += 1
        return tree.query((s[0], s[1], s[2]), distance_upper_bound=CLEARANCE)[0] >= CLEARANCE

    def valid_slice(s):
        checks[0] += 1
        return bool(checker.clearance(np.array([[s[0], s[1], s[2]]]), CLEARANCE)[0] >= CLEARANCE)

    ss.setStateValidityChecker(valid if checker is None else valid_slice)
    si.setStateValidityCheckingResolution(CHECK_STEP / space.getMaximumExtent())
    start, goal = space.allocState(), space.allocState()
    for k in range(3):
        start[k], goal[k] = float(section[0, k]), float(section[-1, k])
    ss.setStartAndGoalStates(start, goal)
    objective = None
    if planner != "RRTConnect":
        objective = OffsetObjective(si, band)
        ss.setOptimizationObjective(objective)
    ss.setPlanner(getattr(og, planner)(si))
    t0 = time.perf_counter()
    ss.solve(time_limit)
    t1 = time.perf_counter()
    exact = ss.haveExactSolutionPath()
    n_solve = checks[0]
    if exact and planner == "RRTConnect":
        ss.simplifySolution()
    t2 = time.perf_counter()
    path = ss.getSolutionPath() if ss.haveSolutionPath() else None
    path = (np.array([[path.getState(i)[k] for k in range(3)]
                      for i in range(path.getStateCount())])
            if path is not None else section[[0, -1]])
    return (exact, path, n_solve, checks[0] - n_solve, t1 - t0, t2 - t1,
            objective.calls if objective is not None else 0)


def per_check_us(tree, local, lo, hi, seed: int, n: int = 20000):
    """us per call of the validity callback on OMPL states (and of SliceMap.clearance)."""
    rng = np.random.default_rng(seed)
    pts = rng.uniform(lo, hi, (n, 3))
    space = ob.RealVectorStateSpace(3)
    states = []
    for p in pts:
        s = space.allocState()
        s[0], s[1], s[2] = p
        states.append(s)
    t = time.perf_counter()
    ok = [tree.query((s[0], s[1], s[2]), distance_upper_bound=CLEARANCE)[0] >= CLEARANCE
          for s in states]
    out = {"cKDTree.query": 1e6 * (time.perf_counter() - t) / n, "valid": float(np.mean(ok))}
    t = time.perf_counter()
    tree.query(pts, distance_upper_bound=CLEARANCE)
    out["cKDTree.query, one batch"] = 1e6 * (time.perf_counter() - t) / n
    smap = SliceMap(local, (DEPTH, DEPTH), BAND, CLEARANCE, box=(lo, hi))
    m = n // 4
    t = time.perf_counter()
    for s in states[:m]:
        smap.clearance(np.array([[s[0], s[1], s[2]]]), CLEARANCE)
    out["SliceMap.clearance"] = 1e6 * (time.perf_counter() - t) / m
    t = time.perf_counter()
    smap.clearance(pts, CLEARANCE)
    out["SliceMap.clearance, one batch"] = 1e6 * (time.perf_counter() - t) / n
    return out


def stats(x) -> str:
    x = np.asarray(x, dtype=float)
    return f"median {np.median(x):7.2f}  p95 {np.percentile(x, 95):7.2f}"


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--sections", type=int, default=50)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    ou.setLogLevel(ou.LOG_ERROR)
    ou.RNG.setSeed(args.seed + 1)  # OMPL's seed of seeds (time-limited solves still vary)
    print(machine())
    print(f"ompl {importlib.metadata.version('ompl')}, numpy {np.__version__}; SliceMap from "
          f"{sys.modules[SliceMap.__module__].__file__}")
    occupied = voxels()
    secs = sections(args.sections, args.seed)
    print(f"{len(occupied)} voxels; {len(secs)} sections, "
          f"{np.mean([arclength(s)[-1] for s in secs]):.1f} m long on average")

    s0 = secs[0]
    lo, hi = s0.min(axis=0) - [6.0, 6.0, 4.0], s0.max(axis=0) + [6.0, 6.0, 4.0]
    local, tree, _ = map_query(occupied, lo, hi)
    for name, v in per_check_us(tree, local, lo, hi, args.seed).items():
        print(f"  per state, {name:32s} {v:6.2f}" + (" (fraction)" if name == "valid" else " us"))

    offset = [("RRTConnect", 1.0, None), ("RRTConnect", 1.0, "SliceMap"),
              ("RRTstar", 0.025, None), ("BITstar", 0.025, None), ("BITstar", 0.008, None),
              ("RRTstar", 0.25, None), ("BITstar", 0.25, None), ("STOMP", 0, None)]
    prior = [("RRTConnect", 1.0, None), ("RRTConnect", 1.0, "SliceMap"), ("BITstar", 0.025, None),
             ("STOMP", 0, None)]
    for title, secs, runs in [
            (f"sections on the contour at the offset ({OMEGA:.0f} m)", secs, offset),
            ("sections on a contour 2 m too close (4 m, the prior map 2 m off): the chord of a "
             "corner section passes within 3 m", sections(args.sections, args.seed, 4.0), prior)]:
        print(f"== {title}")
        bench_set(occupied, secs, runs)


def bench_set(occupied, secs, runs):
    reference, chord_ok = [], []
    for sec in secs:
        _, tree, band = map_query(occupied, sec.min(axis=0) - [6, 6, 4],
                                  sec.max(axis=0) + [6, 6, 4])
        reference.append((offset_error(band, sec)[0], offset_error(band, sec[[0, -1]])[0]))
        chord = resample(sec[[0, -1]], CHECK_STEP)
        chord_ok.append(np.all(tree.query(chord, distance_upper_bound=CLEARANCE)[0] >= CLEARANCE))
    ref = np.array(reference)
    print(f"straight chord valid in {np.mean(chord_ok):.0%} of sections; mean |d - {OMEGA:.0f}| "
          f"(m): section polyline {ref[:, 0].mean():.3f}, straight chord {ref[:, 1].mean():.3f}")
    for planner, limit, which in runs:
        rows = []
        for sec in secs:
            lo, hi = sec.min(axis=0) - [6.0, 6.0, 4.0], sec.max(axis=0) + [6.0, 6.0, 4.0]
            if planner == "STOMP":  # the replanner's step, cold (no warm start), same map
                band = map_query(occupied, lo, hi)[2]
                t = time.perf_counter()
                res = replan_section(sec[0], sec[1:], 0, occupied,
                                     ReplanningParameters(radius=12.0, max_waypoints=12), seed=0)
                t_step = time.perf_counter() - t
                err = offset_error(band, res.trajectory)
                rows.append((1, 0, 0, 1e3 * res.query_time, 1e3 * t_step, 0, 1e3 * t_step,
                             err[0], err[1], len(res.trajectory), 0,
                             min_clearance(occupied, res.trajectory)))
                continue
            t = time.perf_counter()
            local, tree, band = map_query(occupied, lo, hi)
            checker = None
            if which == "SliceMap":
                checker = SliceMap(local, (DEPTH, DEPTH), BAND, CLEARANCE, box=(lo, hi))
            t_map = time.perf_counter() - t
            exact, path, n1, n2, t_solve, t_simp, calls = plan(sec, tree, band, planner, limit,
                                                               checker)
            t_step = time.perf_counter() - t
            err = offset_error(band, path)
            rows.append((exact, n1, n2, 1e3 * t_map, 1e3 * t_solve, 1e3 * t_simp, 1e3 * t_step,
                         err[0], err[1], len(path), calls, min_clearance(occupied, path)))
        r = np.array(rows, dtype=float)
        ok = r[:, 0] > 0
        label = (f"{planner} ({which or 'cKDTree'} check, limit {1e3 * limit:.0f} ms)"
                 if planner != "STOMP" else "STOMP (drake_auv replan_section, cold start)")
        print(f"{label}: success {ok.mean():.0%}")
        print(f"  step (map + setup + solve + simplify) ms {stats(r[:, 6])}")
        if planner == "STOMP":
            print(f"  voxel query ms {stats(r[:, 3])};  mean |d - {OMEGA:.0f}| "
                  f"{r[:, 7].mean():.3f} m "
                  f"(max {r[:, 7].max():.3f}), integral {r[:, 8].mean():.2f} m^2;  min clearance "
                  f"{r[:, 11].min():.2f} m (the obstacle term is a cost)")
            continue
        print(f"  map query ms {stats(r[:, 3])};  solve ms {stats(r[:, 4])};  "
              f"simplify ms {stats(r[:, 5])}")
        print(f"  validity checks per solve {stats(r[:, 1])};  per simplify {stats(r[:, 2])}"
              + (f";  objective calls {stats(r[:, 10])}" if planner != "RRTConnect" else ""))
        if ok.any():
            print(f"  solve ms / checks (us, incl. planner) "
                  f"{1e3 * np.median(r[:, 4] / np.maximum(r[:, 1], 1)):.1f};  path points "
                  f"{np.median(r[ok, 9]):.0f};  mean |d - {OMEGA:.0f}| {r[ok, 7].mean():.3f} m "
                  f"(max {r[ok, 7].max():.3f}), integral {r[ok, 8].mean():.2f} m^2 "
                  f"(section polyline {ref[ok, 0].mean():.3f}, chord "
                  f"{ref[ok, 1].mean():.3f} m);  min "
                  f"clearance {r[ok, 11].min():.2f} m")


if __name__ == "__main__":
    main()
    sys.stdout.flush()
    os._exit(0)  # nanobind reports OMPL objects still held at interpreter exit as leaks
