"""The `ocean:` section of a mission file: what it accepts, what it refuses (one line naming
the key and the allowed range), and the model it builds."""

import math
import re

import numpy as np
import pytest

from drake_auv.ocean.clock import parse_utc
from drake_auv.ocean.spec import OceanSpec, OceanSpecError, ocean_from_raw, ocean_to_raw

SEA = {"current": {"speed_mps": 0.3, "towards_deg": 90},
       "profile": {"seabed_depth_m": 40, "boundary_layer_m": 10},
       "tides": [{"name": "M2", "amplitude_mps": 0.2, "phase_deg": 30,
                  "flood_towards_deg": 0, "ebb_towards_deg": 170}],
       "turbulence": {"speed_sd_mps": 0.04, "direction_sd_deg": 10, "time_constant_s": 300},
       "waves": {"hs_m": 1.0, "tp_s": 8, "towards_deg": 45, "depth_m": 40},
       "start_utc": "2024-03-01T06:00:00Z"}


def test_still_water():
    assert ocean_from_raw(None) is None
    assert ocean_from_raw("none") is None
    assert ocean_to_raw(None) == "none"


def test_a_full_sea_is_read_and_round_trips():
    spec = ocean_from_raw(SEA)
    assert spec.current.speed_mps == 0.3 and spec.tides[0].ebb_towards_deg == 170
    assert spec.turbulence.time_constant_s == 300.0 and spec.waves.hs_m == 1.0
    assert ocean_from_raw(ocean_to_raw(spec)) == spec
    assert OceanSpec() == ocean_from_raw({})


def test_the_model_places_the_dive_on_the_tide():
    spec = ocean_from_raw({"current": {"speed_mps": 0.1, "towards_deg": 0},
                           "tides": [{"name": "S2", "amplitude_mps": 0.2,
                                      "flood_towards_deg": 90}],
                           "start_utc": "2000-01-01T03:00:00Z"})
    model = spec.model(np.random.default_rng(0))
    assert model.start_s == parse_utc("2000-01-01T03:00:00Z")
    velocity, _ = model.water(0.0, [[0.0, 0.0, -10.0]])
    # S2 (30 deg/h) three hours after the tides' epoch: cos(90 deg) = 0, slack water
    np.testing.assert_allclose(velocity[0], [0.0, 0.1, 0.0], atol=1e-12)
    velocity, _ = model.water(3 * 3600.0, [[0.0, 0.0, -10.0]])  # cos(180 deg): full ebb
    np.testing.assert_allclose(velocity[0], [-0.2, 0.1, 0.0], atol=1e-12)


def test_the_seed_draws_the_waves():
    spec = ocean_from_raw({"waves": {"hs_m": 1.0, "tp_s": 8}})
    a = spec.model(np.random.default_rng(1)).water(5.0, [[0, 0, -2]])[0]
    b = spec.model(np.random.default_rng(1)).water(5.0, [[0, 0, -2]])[0]
    c = spec.model(np.random.default_rng(2)).water(5.0, [[0, 0, -2]])[0]
    np.testing.assert_array_equal(a, b)
    assert not np.allclose(a, c)
    assert ocean_from_raw({"waves": {"hs_m": 0.0}}).model(np.random.default_rng(0)).waves \
        is None


@pytest.mark.parametrize("raw, key, allowed", [
    ({"current": {"speed_mps": 5.5}}, "ocean.current.speed_mps", r"\[0, 5\] m/s"),
    ({"current": {"speed_mps": -0.1}}, "ocean.current.speed_mps", r"\[0, 5\] m/s"),
    ({"waves": {"hs_m": -1}}, "ocean.waves.hs_m", r"\[0, 20\] m"),
    ({"waves": {"tp_s": -8}}, "ocean.waves.tp_s", r"\[1, 30\] s"),
    ({"turbulence": {"time_constant_s": 0}}, "ocean.turbulence.time_constant_s", r"\(0, "),
    ({"tides": [{"name": "M2", "amplitude_mps": 0.1, "phase": 3}]}, "ocean.tides[0].phase",
     "name, amplitude_mps, phase_deg"),
    ({"tides": [{"amplitude_mps": 0.1}]}, "ocean.tides[0].name", "name"),
    ({"current": {"speed_mps": 3.0}, "tides": [{"name": "M2", "amplitude_mps": 2.5}]},
     "ocean.tides", "at most 5 m/s"),
    ({"curent": {}}, "ocean.curent", "current, profile, tides"),
    ({"start_utc": "2024-03-01 06:00"}, "ocean.start_utc", "YYYY-MM-DDTHH:MM:SSZ"),
    ({"profile": {"depth_m": [0, 10], "factor": [1.0]}}, "ocean.profile", "equal length"),
    ({"file": "missing.nc"}, "ocean.file", "a CF netCDF file"),
    (42, "ocean", "none or a mapping"),
])
def test_bad_values_are_refused_in_one_line_naming_the_key(raw, key, allowed):
    with pytest.raises(OceanSpecError) as err:
        ocean_from_raw(raw)
    text = str(err.value)
    assert text.startswith(f"{key}: ") and "\n" not in text
    assert err.value.where == key
    assert re.search(allowed, err.value.allowed), text


def test_the_turbulent_mean_speed_is_the_current_speed():
    spec = ocean_from_raw({"current": {"speed_mps": 0.3, "towards_deg": 0},
                           "turbulence": {"speed_sd_mps": 0.03, "direction_sd_deg": 8}})
    model = spec.model(np.random.default_rng(0))
    rng = np.random.default_rng(1)
    deviations = model.turbulence.sd() * rng.standard_normal((5000, 2))
    speeds = np.array([np.hypot(*model.water(0.0, [[0, 0, -5]], d)[0][0, :2])
                       for d in deviations])
    assert speeds.mean() == pytest.approx(0.3, abs=0.002)
    assert speeds.std() == pytest.approx(0.03, rel=0.05)
    headings = np.array([math.atan2(*model.water(0.0, [[0, 0, -5]], d)[0][0, :2])
                         for d in deviations[:500]])
    assert math.degrees(headings.std()) == pytest.approx(8.0, rel=0.1)


def test_a_gridded_file_is_checked_when_the_mission_is_read(tmp_path):
    from test_ocean_gridded import write_cf

    good, bad = tmp_path / "good.nc", tmp_path / "bad.nc"
    write_cf(good)
    write_cf(bad, units="cm/s")
    spec = ocean_from_raw({"file": "good.nc"}, tmp_path)
    assert spec.file == good.resolve()
    with pytest.raises(OceanSpecError, match=r"^ocean.file: bad.nc: u has units 'cm/s'; "
                                             r"allowed: m s-1$"):
        ocean_from_raw({"file": "bad.nc"}, tmp_path)


def test_missions_take_an_ocean_section_and_set_its_keys():
    from drake_auv.mission.config import (MissionFileError, load_mission, mission_from_dict,
                                          mission_to_dict)

    still = load_mission("pool")  # an indoor pool: still water, left out of the written file
    assert still.ocean is None and "ocean" not in mission_to_dict(still)
    assert load_mission("boulder").ocean.waves.hs_m == 1.0  # the demo's default sea
    spec = load_mission("boulder", overrides=[
        "ocean.current.speed_mps=0.4", "ocean.current.towards_deg=270",
        "ocean.tides=[{name: M2, amplitude_mps: 0.2}]", "ocean.tides.0.phase_deg=45",
        "ocean.turbulence.speed_sd_mps=0.05", "ocean.waves.hs_m=1.0"])
    assert spec.ocean.current == spec.ocean.current.__class__(0.4, 270.0)
    assert spec.ocean.tides[0].phase_deg == 45.0 and spec.ocean.waves.hs_m == 1.0
    assert mission_from_dict(mission_to_dict(spec), "/", "x") == spec
    assert load_mission("boulder", overrides=["ocean=none"]).ocean is None
    # YAML reads an unquoted UTC time as a datetime: taken back as the text; a zoneless one is
    # refused.
    timed = load_mission("boulder", overrides=["ocean.start_utc=2024-03-01T06:00:00Z"])
    assert timed.ocean.start_utc == "2024-03-01T06:00:00Z"
    with pytest.raises(MissionFileError, match="ocean.start_utc: .* is not a UTC time"):
        load_mission("boulder", overrides=["ocean.start_utc=2024-03-01T06:00:00"])
    for sets, text in [
            (["ocean.current.speed_mps=6"], "boulder.yaml: ocean.current.speed_mps: 6.0 is out "
                                            "of range; allowed: [0, 5] m/s"),
            (["ocean.waves.tp_s=-2"], "boulder.yaml: ocean.waves.tp_s: -2.0 is out of range; "
                                      "allowed: [1, 30] s"),
            (["ocean.turbulence.sd=1"], "boulder.yaml (--set): ocean.turbulence.sd: unknown "
                                        "key; allowed: speed_sd_mps, direction_sd_deg, "
                                        "time_constant_s")]:
        with pytest.raises(MissionFileError) as err:
            load_mission("boulder", overrides=sets)
        assert str(err.value) == text


def test_a_campaign_varies_the_sea():
    from drake_auv.campaign.grid import expand_runs, parse_vary

    runs = expand_runs("boulder", [0, 1], parse_vary(["ocean.current.speed_mps=0,0.2,0.4"]),
                       overrides=["ocean.current.towards_deg=90"])
    assert len(runs) == 6
    speeds = sorted({run.mission["ocean"]["current"]["speed_mps"] for run in runs})
    assert speeds == [0.0, 0.2, 0.4]
    assert all(run.mission["ocean"]["current"]["towards_deg"] == 90.0 for run in runs)


def test_a_tidal_csv_drives_the_tide_and_its_span_is_checked(tmp_path):
    (tmp_path / "tide.csv").write_text(
        "time_utc,east_mps,north_mps\n2024-03-01T00:00:00Z,0.0,0.2\n"
        "2024-03-01T02:00:00Z,0.2,-0.2\n")
    spec = ocean_from_raw({"tides": "tide.csv", "start_utc": "2024-03-01T00:30:00Z"},
                          tmp_path)
    assert spec.tides_file == (tmp_path / "tide.csv").resolve()
    assert ocean_from_raw(ocean_to_raw(spec), tmp_path) == spec
    model = spec.model(np.random.default_rng(0))
    velocity, acceleration = model.water(1800.0, [[0.0, 0.0, -5.0]])  # one hour in
    np.testing.assert_allclose(velocity[0], [0.1, 0.0, 0.0], atol=1e-12)
    np.testing.assert_allclose(acceleration[0], [0.1 / 3600, -0.2 / 3600, 0.0], atol=1e-15)
    model.check((0, 0, 1, 1), 10.0, 3600.0)
    with pytest.raises(ValueError, match="not the dive's"):
        model.check((0, 0, 1, 1), 10.0, 2 * 3600.0)
