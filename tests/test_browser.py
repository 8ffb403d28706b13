"""What a user sees: every standalone HTML recording the project writes, opened in headless
Chromium (WebGL in software), screenshotted. The view must show the scene, not Meshcat's empty
default view, and the animation must advance. Recordings are kept short (tens of seconds)."""

import os
import re
import shutil
import subprocess
import tempfile
from pathlib import Path

import numpy as np
import pytest
from matplotlib.image import imread

from drake_auv.cli import main
from drake_auv.visualization.legend import CLOCK_ID, LEGEND_ID
from drake_auv.visualization.scene import Scene

CHROMIUM = shutil.which("chromium")
pytestmark = pytest.mark.skipif(CHROMIUM is None and not os.environ.get("CI"),
                                reason="no chromium (Debian package `chromium`)")
EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
WINDOW = (640, 480)


def chromium(html: Path, at_ms: int, output: list[str], attempts: int = 4) -> str:
    """Headless Chromium's stdout on `html` after `at_ms` ms of (virtual) page time, with the
    `output` options (a screenshot, a DOM dump).

    Headless Chromium 156 sometimes never ends a virtual-time budget (it then idles at a few
    seconds of CPU in minutes: measured on this file's recordings, about one run in two while
    other suites ran beside it; a finished run takes 8-20 s), so a run that has not ended in
    60 s is started again with a fresh profile."""
    for attempt in range(attempts):
        with tempfile.TemporaryDirectory() as profile:
            try:
                return subprocess.run(
                    [CHROMIUM or "chromium", "--headless", "--no-sandbox", "--disable-gpu",
                     "--disable-quic", "--no-first-run", "--disable-background-networking",
                     "--disable-component-update", "--disable-sync", f"--user-data-dir={profile}",
                     "--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--hide-scrollbars",
                     f"--window-size={WINDOW[0]},{WINDOW[1]}", f"--virtual-time-budget={at_ms}",
                     *output, html.resolve().as_uri()],
                    check=True, capture_output=True, timeout=60, text=True).stdout
            except subprocess.TimeoutExpired:
                if attempt == attempts - 1:
                    raise


def screenshot(html: Path, at_ms: int) -> np.ndarray:
    """(h, w, 3) floats in [0, 1]: `html` after `at_ms` ms of (virtual) page time."""
    png = html.with_name(f"{html.stem}_{at_ms}.png")
    chromium(html, at_ms, [f"--screenshot={png}"])
    return imread(png)[..., :3]


def changed(a: np.ndarray, b: np.ndarray, threshold: float = 0.08) -> np.ndarray:
    """Mask of the pixels that differ by more than `threshold` in some channel."""
    return np.abs(a - b).max(axis=-1) > threshold


def central(mask: np.ndarray) -> np.ndarray:
    h, w = mask.shape
    return mask[h // 5: 4 * h // 5, w // 5: 4 * w // 5]


@pytest.fixture(scope="module")
def empty_view(tmp_path_factory) -> np.ndarray:
    """Meshcat's default view of an empty scene: the grid and the background."""
    html = Scene().write_html(tmp_path_factory.mktemp("empty") / "empty.html")
    return screenshot(html, 2000)


def assert_shows_scene_and_plays(html: Path, empty_view, early_ms: int, late_ms: int):
    early, late = screenshot(html, early_ms), screenshot(html, late_ms)
    scene_fraction = central(changed(late, empty_view)).mean()
    assert scene_fraction > 0.15, f"{html.name}: the view looks like Meshcat's empty default " \
                                  f"({scene_fraction:.1%} of the centre differs from it)"
    moved = changed(early, late).sum()
    assert moved > 50, f"{html.name}: the animation did not advance ({moved} pixels changed)"


def test_lawnmower_recording(tmp_path, empty_view):
    assert main(["lawnmower", "--extent", "12", "6", "--quiet", "--out", str(tmp_path)]) == 0
    assert_shows_scene_and_plays(tmp_path / "mission.html", empty_view, 1000, 5000)


def test_the_check_fails_on_the_default_camera(tmp_path, empty_view, monkeypatch):
    monkeypatch.setattr(Scene, "frame_camera", lambda self, *args, **kwargs: None)
    assert main(["lawnmower", "--extent", "12", "6", "--quiet", "--out", str(tmp_path)]) == 0
    with pytest.raises(AssertionError, match="empty default"):
        assert_shows_scene_and_plays(tmp_path / "mission.html", empty_view, 1000, 5000)


def test_profile_following_recording(tmp_path, empty_view):
    # the pool mission is profile following alone: its first 40 s, recorded
    assert main(["run", "pool", "-o", str(tmp_path), "--set", "limits.max_time_s=40",
                 "--quiet"]) == 0
    assert_shows_scene_and_plays(tmp_path / "mission.html", empty_view, 500, 3500)


@pytest.fixture(scope="module")
def demo_recording(tmp_path_factory) -> Path:
    """The demo's folder (the boulder, in a sea) flown for its first 60 s."""
    out = tmp_path_factory.mktemp("demo")
    assert main(["demo", "--out", str(out), "--set", "steps.1.follow.loops=0.1",
                 "--set", "limits.max_time_s=60",
                 "--quiet"]) == 0
    return out


def test_mission_recording(demo_recording, empty_view):
    assert_shows_scene_and_plays(demo_recording / "mission.html", empty_view, 300, 1800)


def overlay(html: Path, at_ms: int) -> tuple[dict, dict]:
    """The page's legend ({name: its layer's visibility in the viewer}) and clock (its
    attributes and text) after `at_ms` ms, read from the DOM Chromium dumps."""
    dom = chromium(html, at_ms, ["--dump-dom"])
    legend = dom[dom.index(f'id="{LEGEND_ID}"'):]
    rows = dict((name, visible) for visible, name in re.findall(
        r'<label data-layer="[^"]+" data-visible="(\w+)">.*?<b>([^<]+)</b>', legend))
    clock = re.search(rf'<div id="{CLOCK_ID}"[^>]*data-time="([\d.]+)"[^>]*>.*?'
                      r'<span class="leg">([^<]*)</span>', dom, re.S)
    return rows, {"time": float(clock.group(1)), "leg": clock.group(2)}


def test_the_recording_has_its_legend_and_clock(demo_recording):
    html = demo_recording / "mission.html"
    (early, clock_early), (late, clock_late) = overlay(html, 300), overlay(html, 1800)
    # every layer drawn is named, on by default but the voxels and the reconstruction
    for name in ("world", "nominal path", "vehicle", "vehicle trail", "current", "coverage"):
        assert late[name] == "true", name
    assert late["octree"] == "false"
    assert late.get("reconstruction") == ("false" if (demo_recording / "reconstruction.ply")
                                          .is_file() else None)
    assert early == late  # nothing toggles itself as the animation plays
    # the clock runs with the animation (20x) and names the leg flying: the transit first
    assert 0 < clock_early["time"] < clock_late["time"] <= 60.0
    assert clock_early["leg"].startswith("leg 1 of 4: transit")
