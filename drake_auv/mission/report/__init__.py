"""The report of a flown mission: `report.json`, `report.md`, figures, the trajectory and the
Diagram, written by `outputs.write_outputs`. `summary` computes the numbers (`summarise`),
`markdown` writes them as `report.md`, `figures` draws the dive.

`report.json` keys (a contract; more may be added): `coverage.multibeam`, `coverage.camera`
(fractions of the target's area, union over the dive), `min_clearance_m` (the true signed
clearance to anything, `geometry.clearance`: negative inside the world or above the sea
surface), `contact` (that clearance at or below the vehicle's radius), `distance_to_target`
(`mean_m`, `sd_m`, `min_m` over the survey samples within 2 Omega of the target, and `map_mean_m`, the same against the on-line map's voxels on the
target, as the reference reports it), `phases` (`name`, `start_s`, `end_s`, one time axis),
`faults` (the injected ones, as in the mission file), `responses` (the supervisor's answers:
`response`, `cause`, `start_s`, `end_s`), `mission.aborted` and `coverage_vs_time` (`t_s`,
`multibeam`, `camera`: the covered shares every `period_s` from 0 to the end of the dive, and
`time_to_s`, the exact mission time each sensor first covered 80 % and 90 %, null if never).
Everything but `timing` depends only on the mission file and its seed. `timing` (wall clock,
s): `sim_s` simulated; `wall_s` = `simulation_s`, the simulation's wall time, and
`real_time_factor` = `sim_s / simulation_s`; from `write_outputs`, the end-to-end figures:
`setup_s` (when the caller measured it: loading, planning, building the Diagram, reading the
logs back), `outputs_s` (every file, the Meshcat recording included), `reconstruction_s` (of
which the point cloud and the surface), `total_s` and `peak_rss_mb` (the process's peak
resident memory, MiB).
"""
