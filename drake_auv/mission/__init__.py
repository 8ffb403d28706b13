"""Missions: mission files (`config`), the sites they fly on (`site`), the supervisor, the
one-dive Diagram, the runner and the report."""
