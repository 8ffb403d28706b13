"""Region of interest: rectangles and polygons in map coordinates."""


import numpy as np
import pytest

from drake_auv.scenarios import DATA_DIR as DATA
from drake_auv.terrain.bathymetry import Bathymetry
from drake_auv.terrain.readers import read_bathymetry
from drake_auv.terrain.roi import crop_to_roi, parse_roi

MONTEREY = sorted((DATA / "monterey").glob("*.tif"))


def _grid():
    yy, xx = np.mgrid[0:30, 0:40]
    return Bathymetry(-10.0 - 0.1 * xx - 0.01 * yy, (1.0, 1.0), (100.0, 50.0))


def test_rectangle_crop_keeps_world_frame():
    bathy = _grid()
    out = crop_to_roi(bathy, (110.0, 55.0, 120.0, 60.0))
    assert out.shape == (6, 11) and out.origin == (110.0, 55.0)
    np.testing.assert_array_equal(out.z, bathy.z[5:11, 10:21])


def test_polygon_crop_sets_outside_to_no_data():
    out = crop_to_roi(_grid(), [(100.0, 50.0), (139.0, 50.0), (100.0, 79.0)])
    assert np.isnan(out.z[-1, -1]) and np.isfinite(out.z[0, 0])
    # Cells on or below the hypotenuse are kept: about half the square.
    assert 0.45 < np.isfinite(out.z).mean() < 0.6


def test_parse_roi_forms():
    np.testing.assert_array_equal(parse_roi("1,2,3,4")[2], [3.0, 4.0])
    assert parse_roi("0,0;5,0;5,5").shape == (3, 2)
    with pytest.raises(ValueError, match="--roi"):
        parse_roi("1,2,x,4")


@pytest.mark.parametrize("roi, match", [
    ((0.0, 0.0, 10.0, 10.0), "outside the grid"),
    ((120.0, 60.0, 110.0, 70.0), "xmax > xmin"),
    ([(0.0, 0.0), (1.0, 1.0)], "vertices"),
    ((110.0, 55.0, 111.0, 56.0), "at least 3 x 3")])
def test_bad_rois(roi, match):
    with pytest.raises(ValueError, match=match):
        crop_to_roi(_grid(), roi)


def test_roi_all_no_data():
    z = _grid().z.copy()
    z[:10, :10] = np.nan
    with pytest.raises(ValueError, match="only no-data"):
        crop_to_roi(Bathymetry(z, (1.0, 1.0), (100.0, 50.0)), (100.0, 50.0, 105.0, 55.0))


def test_monterey_roi_in_pseudo_mercator():
    bathy = read_bathymetry(MONTEREY[0])
    corner = bathy.world_to_crs([[0.0, 0.0]])[0]
    roi = (corner[0] + 200.0, corner[1] + 300.0, corner[0] + 600.0, corner[1] + 800.0)
    out = crop_to_roi(bathy, roi)
    # 400 x 500 map metres = 320 x 400 ground metres at cos(36.8 deg) = 0.80.
    ext = out.extent
    assert ext[1] - ext[0] == pytest.approx(320.0, abs=2 * bathy.spacing[0])
    assert ext[3] - ext[2] == pytest.approx(400.0, abs=2 * bathy.spacing[1])
    back = out.world_to_crs([[ext[0], ext[2]], [ext[1], ext[3]]])
    assert np.all(back[0] >= roi[:2]) and np.all(back[1] <= roi[2:])
