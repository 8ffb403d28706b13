"""`drake-auv run MISSION --meshcat`: the scene served on localhost while the mission flies, the
leg and the replanner's section drawn as they change, and the same report as without it."""

import json
import os
import shutil
import subprocess
import tempfile
import threading
import time
import urllib.request

import numpy as np
import pytest
from matplotlib.image import imread
from pydrake.geometry import Meshcat, MeshcatParams

import drake_auv.visualization as visualization
from drake_auv.cli import main
from drake_auv.mission.legs import Leg
from drake_auv.mission.live_view import CLOCK, LABEL_PREFIX, MissionView

CHROMIUM = shutil.which("chromium")
SHORT = ["--set", "limits.max_time_s=30", "--quiet"]


def _held_page(url: str, hold_s: float):
    """A 127.0.0.1 HTTP server of a page framing `url` that also loads an image the server
    answers only after `hold_s` real seconds: Chromium's virtual time stands still while a
    fetch is pending, so its screenshot waits that long for the scene's websocket (a
    virtual-time budget alone races ahead of it on a loaded machine: Meshcat's empty grid)."""
    import http.server

    class Handler(http.server.BaseHTTPRequestHandler):
        def do_GET(self):
            if self.path == "/hold.gif":
                time.sleep(hold_s)
                body, kind = (b"GIF89a\x01\x00\x01\x00\x00\x00\x00;", "image/gif")
            else:
                body, kind = (f'<html><body style="margin:0"><iframe src="{url}" style="border:0;'
                              'width:100%;height:100%"></iframe><img src="/hold.gif" '
                              'style="display:none"></body></html>').encode(), "text/html"
            self.send_response(200)
            self.send_header("Content-Type", kind)
            self.send_header("Content-Length", str(len(body)))
            self.end_headers()
            self.wfile.write(body)

        def log_message(self, *args):
            pass

    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), Handler)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    return server


def screenshot(url: str, png) -> np.ndarray:
    """(h, w, 3) floats in [0, 1]: the live page at `url` in headless Chromium, once the scene
    has arrived over its websocket (`_held_page`); an attempt that still shows the empty page
    (no seabed) is held longer."""
    for hold_s in (4.0, 10.0, 25.0):
        server = _held_page(url, hold_s)
        try:
            with tempfile.TemporaryDirectory() as profile:
                subprocess.run(
                    [CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu", "--no-first-run",
                     "--disable-background-networking", "--disable-component-update",
                     "--disable-sync", f"--user-data-dir={profile}", "--use-angle=swiftshader",
                     "--enable-unsafe-swiftshader", "--hide-scrollbars", "--window-size=640,480",
                     "--virtual-time-budget=5000", f"--screenshot={png}",
                     f"http://127.0.0.1:{server.server_address[1]}/"],
                    check=True, capture_output=True, timeout=180)
        finally:
            server.shutdown()
        view = imread(png)[..., :3]
        if seabed_fraction(view) > 0.3:
            break
    return view


def seabed_fraction(view: np.ndarray) -> float:
    """Share of the central pixels that are dark (the lit seabed and the boulder are; Meshcat's
    empty page, a light background and a grid, is not)."""
    h, w = view.shape[:2]
    return float((view[h // 5: 4 * h // 5, w // 5: 4 * w // 5].mean(axis=-1) < 0.5).mean())


LEGS = (Leg("transit", 0, "path", "arrive", 100.0, target=(10.0, 0.0, -20.0), tolerance=1.5),
        Leg("follow", 0, "follow", "loops", 300.0, centre=(0.0, 5.0)))


def view_context(meshcat, leg, section=None):
    view = MissionView(meshcat, "/test", LEGS)
    context = view.CreateDefaultContext()
    view.leg_input.FixValue(context, leg)
    view.state_input.FixValue(context, np.r_[1.0, 2.0, -20.0, np.zeros(9)])
    view.reference_input.FixValue(context, np.r_[3.0, 2.0, -20.0, np.zeros(5)])
    if section is not None:
        view.section_input.FixValue(context, section)
    return view, context


def test_mission_view_draws_the_leg_and_the_section():
    meshcat = Meshcat(MeshcatParams(host="localhost"))
    section = np.column_stack([np.linspace(0, 5, 6), np.zeros(6), np.full(6, -20.0)])
    view, context = view_context(meshcat, [0.0, 0.0], section)
    context.SetTime(12.5)
    view.ForcedPublish(context)
    assert meshcat.GetButtonNames() == ["leg 1 of 2: transit, path until arrive (since 0 s)"]
    assert meshcat.GetSliderValue(CLOCK) == pytest.approx(12.5, abs=0.5)  # 1 s steps
    assert meshcat.HasPath("/test/leg/target") and meshcat.HasPath("/test/leg/line")
    assert meshcat.HasPath("/test/section") and meshcat.HasPath("/test/reference")
    # the next leg replaces the label and the goal geometry
    view.leg_input.FixValue(context, [1.0, 42.0])
    view.ForcedPublish(context)
    assert meshcat.GetButtonNames() == ["leg 2 of 2: follow, follow until loops (since 42 s)"]
    assert meshcat.HasPath("/test/leg/centre") and not meshcat.HasPath("/test/leg/target")


def test_mission_view_without_a_replanner_draws_no_section():
    meshcat = Meshcat(MeshcatParams(host="localhost"))
    view, context = view_context(meshcat, [0.0, 0.0])
    view.ForcedPublish(context)
    assert not meshcat.HasPath("/test/section")
    with pytest.raises(ValueError, match="period"):
        MissionView(meshcat, "/test", LEGS, period=0.0)


@pytest.fixture(scope="module")
def live_run(tmp_path_factory):
    """`run boulder --meshcat --realtime 0` on a short cap, with a thread that fetches the
    served page over HTTP on 127.0.0.1 as soon as the scene exists; after the run, a headless
    Chromium screenshot of that live server (a browser connected during a 2 s dive at full
    speed would race it)."""
    out = tmp_path_factory.mktemp("live")
    scenes, seen = [], {}

    class WatchedScene(visualization.Scene):
        def __init__(self, *args, **kwargs):
            super().__init__(*args, **kwargs)
            # Meshcat answers only on its own thread: its URL is read here. Holding the scene
            # also keeps the server up after the run, for the screenshot.
            scenes.append((self, self.meshcat.web_url()))

    def watch():
        while not scenes:
            time.sleep(0.05)
        url = scenes[0][1].replace("localhost", "127.0.0.1")
        with urllib.request.urlopen(url, timeout=30) as page:
            seen.update(url=url, status=page.status, html=page.read().decode(),
                        fetched=time.monotonic())

    original = visualization.Scene
    visualization.Scene = WatchedScene
    try:
        watcher = threading.Thread(target=watch, daemon=True)
        watcher.start()
        assert main(["run", "boulder", "--meshcat", "--realtime", "0", "-o", str(out / "run"),
                     *SHORT]) == 0
        ended = time.monotonic()
        watcher.join(timeout=60)
    finally:
        visualization.Scene = original
    if CHROMIUM is not None:  # the server the run drew in, still up: what a browser shows
        seen["view"] = screenshot(seen["url"], out / "live.png")
    return out, seen, ended, scenes


def test_the_page_is_served_during_the_run(live_run):
    out, seen, ended, scenes = live_run
    assert seen["status"] == 200 and "meshcat" in seen["html"].lower()
    assert seen["fetched"] < ended  # while the mission was still being planned or flown
    scene = scenes[0][0]
    assert scene.live and seen["url"].startswith("http://127.0.0.1:")
    for layer in ("live/reference", "live/leg/centre", "vehicle", "world"):
        assert scene.meshcat.HasPath(scene.path_of(layer)), layer
    # the transit arrived after 26 s: the follow leg's label replaced it
    names = scene.meshcat.GetButtonNames()
    assert [name.split(" (")[0] for name in names if name.startswith(LABEL_PREFIX)] == [
        "leg 2 of 4: follow, follow until loops"]
    # the legend names each layer and marker; the clock stopped at the cap
    legend = {entry.label for entry in scene.legend.values()}
    assert legend <= set(names)
    assert {"magenta sphere: leg's target", "magenta bar: loops' centre", "yellow sphere: "
            "reference", "cyan arrow: current", "viridis dots: octree"} <= legend
    assert scene.meshcat.GetSliderNames() == [CLOCK]
    assert scene.meshcat.GetSliderValue(CLOCK) == 30.0
    assert (out / "run" / "mission.html").is_file()  # the recording is still written


@pytest.mark.skipif(CHROMIUM is None and not os.environ.get("CI"),
                    reason="no chromium (Debian package `chromium`)")
def test_chromium_renders_the_live_scene(live_run):
    fraction = seabed_fraction(live_run[1]["view"])
    assert fraction > 0.3, f"the live view shows no seabed ({fraction:.1%} of the centre)"


def test_the_report_is_the_same_without_meshcat(live_run):
    out, _, _, _ = live_run
    assert main(["run", "boulder", "-o", str(out / "plain"), *SHORT]) == 0
    live, plain = (json.loads((out / name / "report.json").read_text())
                   for name in ("run", "plain"))
    for report in (live, plain):
        assert report.pop("timing")["sim_s"] == 30.0
    assert live == plain


def test_a_negative_realtime_rate_is_one_line(tmp_path, capsys):
    assert main(["run", "boulder", "--meshcat", "--realtime", "-1", "-o", str(tmp_path)]) != 0
    assert "--realtime must be >= 0" in capsys.readouterr().err
