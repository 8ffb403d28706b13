"""A small user site in UTM coordinates, written as files, for the mission tests.

`write_utm_site(tmp_path)` writes, in EPSG:32631 coordinates (eastings near 500 km, northings
near 4600 km, z up, sea surface z = 0):
- world.ply: a 60 m x 60 m flat seabed at -20 m with a 6 m cube on it (sunk 0.5 m into it,
  top at -14.5 m), centred at (BOX_CENTRE);
- target.ply: the cube alone;
- prior.tif: a 1 m GeoTIFF of the same site seen from above;
- mission.yaml: a plan, follow and survey mission on those files, capped at 90 s simulated;
and returns the mission file's path.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import trimesh
import yaml

from drake_auv.terrain.bathymetry import Bathymetry
from drake_auv.terrain.mesh import bathymetry_to_mesh
from drake_auv.terrain.readers import write_geotiff

CRS = "EPSG:32631"
SW_CORNER = np.array([499970.0, 4599970.0])  # m, the seabed's south-west corner
SIZE = 60.0  # m, the seabed's side
SEABED_Z = -20.0  # m
BOX_SIZE = 6.0  # m
BOX_CENTRE = np.array([500005.0, 4600000.0, SEABED_Z - 0.5 + BOX_SIZE / 2])  # m
LOCAL_ORIGIN = SW_CORNER + SIZE / 2  # the world's bounds centre, rounded


def utm_box() -> trimesh.Trimesh:
    """The cube, site coordinates."""
    box = trimesh.creation.box(extents=(BOX_SIZE,) * 3)
    box.apply_translation(BOX_CENTRE)
    return box


def utm_prior(spacing: float = 1.0) -> Bathymetry:
    """The site seen from above on a grid of `spacing` m, site coordinates, in CRS."""
    n = int(round(SIZE / spacing)) + 1
    x = SW_CORNER[0] + spacing * np.arange(n)
    y = SW_CORNER[1] + spacing * np.arange(n)
    gx, gy = np.meshgrid(x, y)
    on_box = ((np.abs(gx - BOX_CENTRE[0]) <= BOX_SIZE / 2)
              & (np.abs(gy - BOX_CENTRE[1]) <= BOX_SIZE / 2))
    z = np.where(on_box, BOX_CENTRE[2] + BOX_SIZE / 2, SEABED_Z)
    return Bathymetry(z, (spacing, spacing), tuple(SW_CORNER), CRS)


def write_utm_site(tmp_path) -> Path:
    """Writes the site's files and mission.yaml into `tmp_path`; returns mission.yaml."""
    folder = Path(tmp_path)
    seabed = bathymetry_to_mesh(utm_prior().with_z(np.full((61, 61), SEABED_Z)))
    box = utm_box()
    trimesh.util.concatenate([seabed, box]).export(folder / "world.ply")
    box.export(folder / "target.ply")
    write_geotiff(utm_prior(), folder / "prior.tif")
    mission = dict(
        name="utm_box", seed=0,
        site=dict(world="world.ply", target="target.ply", prior="prior.tif",
                  prior_error_m=2.0),
        navigation=dict(heading_bias_deg=1.0, dvl_scale_error=0.01, random_walk=0.02),
        sonar_noise="clean", replanner=dict(optimizer="stomp", R=5.0, K=10),
        payload=dict(multibeam_mount="port", camera_range_m=12),
        limits=dict(max_time_s=90.0),
        steps=[dict(plan=dict(omega=3.0, slice_count=1)),
               dict(follow=dict(mode="horizontal", depth=17.0, offset=3.0, loops=0.5)),
               dict(survey=dict(replanning=True))])
    path = folder / "mission.yaml"
    path.write_text(yaml.safe_dump(mission, sort_keys=False))
    return path
