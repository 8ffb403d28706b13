"""Slope map and classification."""

import numpy as np
import pytest

from drake_auv.terrain.bathymetry import Bathymetry
from drake_auv.terrain.slope import classify, slope_map
from drake_auv.terrain.synthetic import caldera_site


def _plane(a, b, shape=(40, 60), spacing=(0.5, 2.0)):
    x = np.arange(shape[1]) * spacing[0]
    y = np.arange(shape[0]) * spacing[1]
    xx, yy = np.meshgrid(x, y)
    return Bathymetry(a * xx + b * yy - 30.0, spacing)


def test_slope_of_a_plane_uses_the_true_non_square_spacing():
    s = slope_map(_plane(0.3, -0.4))
    np.testing.assert_allclose(s, 0.5, atol=1e-12)


def test_slope_next_to_no_data_uses_one_sided_differences():
    z = _plane(0.3, -0.4).z.copy()
    z[10:14, 20:30] = np.nan
    z[0, 0] = np.nan
    s = slope_map(Bathymetry(z, (0.5, 2.0)))
    assert np.isnan(s[10:14, 20:30]).all()
    np.testing.assert_allclose(s[np.isfinite(z)], 0.5, atol=1e-12)


def test_small_planar_specks_inside_a_wall_become_high_slope():
    z = _band(20.0).z.copy()
    z[50:53, 100:103] = z[51, 101]  # a 1.5 m x 1.5 m flat step in the middle of the ramp
    labels = classify(Bathymetry(z, (0.5, 0.5)), closing_radius=0.0, opening_radius=0.0,
                      min_area=10.0)
    assert labels.high[51, 101] and labels.n_regions == 1


def test_flat_terrain_has_no_high_slope_region():
    labels = classify(_plane(0.0, 0.0))
    assert labels.n_regions == 0 and not labels.high.any() and labels.planar.all()


def _band(width_m, gap_m=None, blob=False):
    """Flat ground with a 0.8-slope ramp (optionally split by a gentle gap) and a small blob."""
    x = np.arange(200) * 0.5
    slope = np.where((x > 40) & (x < 40 + width_m), 0.8, 0.0)
    if gap_m is not None:
        slope[(x > 40 + width_m / 2) & (x < 40 + width_m / 2 + gap_m)] = 0.0
    z1 = np.cumsum(slope) * 0.5
    z = np.tile(z1, (120, 1))
    if blob:  # a 2 m x 2 m steep bump, far from the ramp
        yy, xx = np.mgrid[0:120, 0:200]
        z = z + 1.0 * np.exp(-(((xx - 20) / 2.0) ** 2 + ((yy - 60) / 2.0) ** 2))
    return Bathymetry(z, (0.5, 0.5))


def test_classification_threshold_closing_and_small_components():
    labels = classify(_band(20.0, blob=True), slope_threshold=0.5, min_area=20.0)
    assert labels.n_regions == 1  # the blob (about 4 m^2) is removed by min_area
    xs = np.flatnonzero(labels.high.any(axis=0)) * 0.5
    assert 39.0 <= xs.min() <= 41.0 and 59.0 <= xs.max() <= 61.0
    kept = classify(_band(20.0, blob=True), slope_threshold=0.5, min_area=0.0, opening_radius=0.0)
    assert kept.n_regions == 2
    # A 1 m gentle gap splits the ramp in two; a 2 m closing joins the parts again.
    split = classify(_band(20.0, gap_m=1.0), closing_radius=0.0, opening_radius=0.0, min_area=0.0)
    joined = classify(_band(20.0, gap_m=1.0), closing_radius=2.0, opening_radius=0.0, min_area=0.0)
    assert split.n_regions == 2 and joined.n_regions == 1


def test_no_data_is_never_high_slope():
    z = _band(20.0).z.copy()
    z[:, 90:95] = np.nan
    labels = classify(Bathymetry(z, (0.5, 0.5)), min_area=0.0)
    assert not labels.high[:, 90:95].any() and not labels.planar[:, 90:95].any()


@pytest.mark.parametrize("kwargs, match", [
    (dict(slope_threshold=0.0), "slope_threshold"), (dict(slope_threshold=-1.0), "slope_threshold"),
    (dict(slope_threshold=np.nan), "slope_threshold"), (dict(closing_radius=-1.0), "closing_radius"),
    (dict(opening_radius=np.inf), "opening_radius"), (dict(min_area=-5.0), "min_area")])
def test_bad_classification_parameters(kwargs, match):
    with pytest.raises(ValueError, match=match):
        classify(_plane(0.1, 0.0), **kwargs)


def test_caldera_site_matches_the_reference_figures():
    bathy = caldera_site()
    assert bathy.shape == (501, 201) and bathy.spacing == (0.5, 0.5)
    s = slope_map(bathy)
    assert s.min() < 0.01 and 0.6 < s.max() < 0.67  # the reference: 0.001 to 0.622
    labels = classify(bathy, 0.5)
    assert labels.n_regions == 1
    planar = s[labels.planar]
    assert np.mean(planar < 0.3) > 0.8  # planar slopes mostly under 0.3
    assert 0.25 < labels.high.mean() < 0.5
    # Same seed, same site; another seed only changes the centimetre texture.
    np.testing.assert_array_equal(caldera_site(seed=0).z, bathy.z)
    other = caldera_site(seed=1).z
    assert 0 < np.abs(other - bathy.z).max() < 0.2


def _block(shape=(80, 100)):
    """A 30 m x 20 m block 6 m high with vertical sides on a 1 m grid (a steep band 2 cells
    wide, slope 3, seen from above)."""
    yy, xx = np.mgrid[0:shape[0], 0:shape[1]] * 1.0
    cy, cx = shape[0] / 2, shape[1] / 2
    return Bathymetry(-30.0 + 6.0 * ((np.abs(xx - cx) < 15) & (np.abs(yy - cy) < 10)), (1, 1))


def _listing_hull():
    """A 50 m x 12 m hull turned 29 deg, its deck listing 0.3 m per m, on a 1 m grid."""
    yy, xx = np.mgrid[0:80, 0:100] * 1.0
    c, s = np.cos(0.5), np.sin(0.5)
    u, v = (xx - 50) * c + (yy - 40) * s, -(xx - 50) * s + (yy - 40) * c
    inside = (np.abs(u) < 25) & (np.abs(v) < 6)
    return Bathymetry(-30.0 + np.where(inside, 4.0 + 0.3 * v, 0.0), (1, 1))


@pytest.mark.parametrize("make", [_block, _listing_hull], ids=["block", "listing hull"])
def test_thin_near_vertical_walls_survive_and_are_sliced(make):
    from drake_auv.planning.coverage_plan import plan_coverage
    from drake_auv.planning.parameters import CoverageParameters

    bathy = make()
    labels = classify(bathy)
    assert labels.n_regions == 1
    assert labels.high.sum() <= 0.12 * labels.valid.sum()  # the wall band, not the deck
    plan = plan_coverage(bathy, CoverageParameters(omega=2.0), compute_metrics=False)
    assert len(plan.contours) >= 1 and plan.path.length_by_label()["slice"] > 100.0
    # An opening of 2 cells (the former default) erases such a wall: what this guards.
    assert classify(bathy, opening_radius=2.0).n_regions == 0


def test_region_count_does_not_depend_on_the_roi_size():
    from drake_auv.terrain.synthetic import random_seabed

    def mound(n):
        yy, xx = np.mgrid[0:n, 0:n] * 1.0
        r = np.hypot(xx - n / 2, yy - n / 2)
        return -40.0 + 8.0 * np.exp(-(r / 6.0) ** 2)

    small = Bathymetry(mound(60), (1, 1))
    texture = random_seabed(2, shape=(120, 120), relief=0.5, smoothness=6.0).z + 40.0
    large = Bathymetry(mound(120) + texture, (1, 1))  # the same mound, 4x the area
    a, b = classify(small), classify(large)
    assert a.n_regions == b.n_regions == 1
    assert abs(int(a.high.sum()) - int(b.high.sum())) <= 0.1 * a.high.sum()
    # A minimum area in m^2 from the CLI's --min-area: above the mound's, it is dropped.
    assert classify(small, min_area=2.0 * a.high.sum()).n_regions == 0
