"""All together at the boulder site (reference Section 5.5.4): the same run as `make demo`.

Off-line plan on the boulder's prior map (Omega = 10 m, two slicing contours 2 m apart,
boustrophedon lanes elsewhere), horizontal profile following around the boulder, then the plan
flown with realtime replanning against the on-line octree map under prior-map and navigation
error: the built-in `boulder` mission (drake_auv/mission/missions/boulder.yaml). Writes
out/demo/: report.md, report.json, plan.png, coverage.png, distance.png, mission.html,
trajectory.csv and diagram.dot. Run:
    MPLBACKEND=Agg .venv/bin/python examples/boulder_all_together.py [--seed 0] [--out DIR]
Every option of `drake-auv demo` is accepted (see `drake-auv demo --help`), e.g.
`--set limits.max_time_s=300` for a short dive.
"""

import sys

from drake_auv.cli import main

if __name__ == "__main__":
    sys.exit(main(["demo", *sys.argv[1:]]))
