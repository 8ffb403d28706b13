"""Point clouds and surfaces from the recorded returns, scored against the truth.

`pointcloud` (the cloud of a `ScanLog`, PLY and LAS files), `surface` (Hoppe normals oriented
by the sensor, screened Poisson through the optional Open3D, density trimming), `scoring`
(accuracy and completeness against a true mesh), `figures` (the reference's Figure 89, coloured
by error) and `products` (a flown mission's points.ply, surface and report section). No Drake.
"""
