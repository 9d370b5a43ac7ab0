"""The browser viewer (kinengine.presentation.viewer, `kinengine view`): what it sends equals kinengine's
forward kinematics, bad meshes cost one warning and never a failure, a missing extra names the fix, and
in a real browser (headless Chromium, software WebGL) the robot is drawn where its links project and
moves there when ``update(q)`` is called on the open page."""

from __future__ import annotations

import base64
import contextlib
import importlib.util
import io
import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import urllib.request
import warnings
from pathlib import Path

import numpy as np
import pytest

import kinengine
from kinengine.errors import KinematicsError
from kinengine.presentation import viewer_scene
from kinengine.presentation.viewer import view

pytestmark = pytest.mark.slow  # drives the viewer in a real browser

# Every test but the first needs the [view] extra (viser, pycollada for the DAE meshes).
needs_view = pytest.mark.skipif(
    importlib.util.find_spec("viser") is None or importlib.util.find_spec("collada") is None,
    reason="the viewer extra is not installed: pip install '.[view]'",
)

WIDTH, HEIGHT = 800, 600
PANEL_LEFT = 450  # the control panel covers the page right of this column [px]


# -- without a browser ---------------------------------------------------------------------------
def test_missing_extra_names_the_install_command(abb, monkeypatch):
    monkeypatch.setitem(sys.modules, "viser", None)  # import viser -> ImportError
    with pytest.raises(KinematicsError, match=r"pip install 'kinengine\[view\]'"):
        abb.view(port=0)


@needs_view
def test_the_scene_is_kinengines_forward_kinematics(abb):
    q0 = np.array([0.3, -0.4, 0.5, 0.2, -0.7, 1.1])
    with abb.view(q0, port=0, frames=["tool0"], ellipsoid="tool0") as v:
        assert v.url.startswith("http://127.0.0.1:")
        for q in (q0, np.array([-1.0, 0.6, -0.3, 1.2, 0.4, -2.0])):
            v.update(q)
            np.testing.assert_allclose(v.q, q)
            for link in ("base_link", "link_3", "tool0"):
                np.testing.assert_allclose(v.shown_pose(link), abb.frame_pose(q, link), atol=1e-6)
            chi = abb.pose_parameters(q, "tool0", "cartesian", "euler_zyx")
            np.testing.assert_allclose(v.readout["chi"], chi)
            assert not v.readout["singular"]
        with pytest.raises(kinengine.ConfigurationError):
            v.update([0.0, 1.0])
    with pytest.raises(KinematicsError, match="closed"):
        v.update(q0)


@needs_view
def test_the_readout_turns_red_at_the_representation_singularity(abb):
    """At q = 0 the IRB 120's tool0 z axis points along the root x axis: ZYX pitch = π/2 (gimbal lock);
    the quaternion has no singular set."""
    with view(abb, np.zeros(6), port=0, parameterization="euler_zyx") as v:
        assert v.readout["singular"] and v.readout["distance"] < 1e-9
        np.testing.assert_allclose(v.readout["chi"][4], np.pi / 2)
    with view(abb, np.zeros(6), port=0, parameterization="quaternion") as v:
        assert not v.readout["singular"] and v.readout["distance"] == np.inf


@needs_view
def test_bad_input_is_refused_before_serving(abb):
    with pytest.raises(kinengine.FrameNotFoundError):
        abb.view(port=0, frames=["no_such_frame"])
    with pytest.raises(kinengine.ParameterizationError):
        abb.view(port=0, parameterization="euler_abc")
    with pytest.raises(KinematicsError, match="port"):
        abb.view(port=70000)


@needs_view
def test_panda_meshes_are_found_and_read():
    panda = kinengine.load("panda")
    visuals = viewer_scene.read_visuals(panda.urdf_text, panda.source)
    assert visuals.failures == []
    kinds = {link: [v.kind for v in items] for link, items in visuals.links.items()}
    assert kinds["panda_link0"] == ["mesh"] and kinds["panda_hand"] == ["mesh"]
    assert len(visuals.links["panda_link3"][0].mesh.faces) > 1000


@needs_view
def test_a_missing_or_broken_mesh_costs_one_warning(tmp_path):
    (tmp_path / "broken.stl").write_bytes(b"solid nothing\nthis is not an STL\n")
    (tmp_path / "robot.urdf").write_text("""<robot name="meshy">
  <link name="base"><visual><geometry><mesh filename="package://no_such_package/base.stl"/></geometry></visual></link>
  <link name="arm"><visual><geometry><mesh filename="broken.stl"/></geometry></visual></link>
  <link name="tip"><visual><origin xyz="0 0 0.05"/><geometry><box size="0.1 0.1 0.1"/></geometry></visual>
  </link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="arm"/><axis xyz="0 0 1"/>
    <limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
  <joint name="j2" type="continuous"><parent link="arm"/><child link="tip"/><origin xyz="0.5 0 0"/>
    <axis xyz="0 1 0"/></joint>
</robot>""")
    robot = kinengine.load(str(tmp_path / "robot.urdf"))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        v = robot.view(port=0)
    try:
        messages = [str(w.message) for w in caught if issubclass(w.category, UserWarning)]
        assert len(messages) == 1, messages
        assert "2 meshes of meshy" in messages[0] and "skeleton" in messages[0]
        v.update([0.5, 2.0])
        np.testing.assert_allclose(v.shown_pose("tip"), robot.frame_pose([0.5, 2.0], "tip"), atol=1e-6)
    finally:
        v.close()
    assert viewer_scene.slider_ranges(robot) == [(-1.0, 1.0), (-np.pi, np.pi)]


@needs_view
def test_the_command_serves_the_page_until_ctrl_c():
    proc = subprocess.Popen(
        [sys.executable, "-m", "kinengine", "view", "abb_irb120", "--port", "0"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        line = proc.stdout.readline()
        assert "viewing abb_irb120 at http://127.0.0.1:" in line, line + proc.stderr.read()
        url = line.split(" at ")[1].split()[0]
        with urllib.request.urlopen(url, timeout=30) as response:
            assert response.status == 200 and b"<html" in response.read(2000)
        proc.send_signal(signal.SIGINT)
        assert proc.wait(timeout=30) == 0
    finally:
        if proc.poll() is None:
            proc.kill()
        proc.stdout.close()
        proc.stderr.close()


# -- in a real browser ----------------------------------------------------------------------------
def _chromium() -> str:
    for name in ("chromium", "chromium-browser", "google-chrome"):
        path = shutil.which(name)
        if path:
            return path
    pytest.skip(
        "no Chromium on this machine (Debian: apt-get install chromium; .ci/run installs it where "
        "it may): the browser test cannot run"
    )


_HIDE_NOTICES = """if (document.head && !document.getElementById('kinengine-test')) {
  const style = document.createElement('style'); style.id = 'kinengine-test';
  style.textContent = '.mantine-Notification-root { display: none !important; }';
  document.head.appendChild(style); }"""


class Browser:
    """Headless Chromium driven over the DevTools protocol: software WebGL (SwiftShader), one page,
    800x600 CSS pixels, screenshots once the picture has stopped changing."""

    def __init__(self, executable: str, url: str) -> None:
        from websockets.sync.client import connect

        self.folder = tempfile.mkdtemp(prefix="kinengine-chromium-")
        self.process = subprocess.Popen(
            [
                executable,
                "--headless",
                "--no-sandbox",
                "--disable-gpu",
                "--use-angle=swiftshader",
                "--enable-unsafe-swiftshader",
                "--disable-quic",
                "--no-first-run",
                "--disable-background-networking",
                "--disable-component-update",
                "--disable-sync",
                f"--user-data-dir={self.folder}",
                f"--window-size={WIDTH},{HEIGHT}",
                "--remote-debugging-port=0",
                url,
            ],
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
            start_new_session=True,  # its own process group: close() ends its renderer processes too
        )
        port_file = Path(self.folder) / "DevToolsActivePort"
        deadline = time.monotonic() + 60
        while not (port_file.exists() and port_file.read_text().strip()):
            if time.monotonic() > deadline or self.process.poll() is not None:
                raise RuntimeError(f"chromium did not start (exit code {self.process.poll()})")
            time.sleep(0.1)
        port = int(port_file.read_text().split()[0])
        with urllib.request.urlopen(f"http://127.0.0.1:{port}/json/list", timeout=30) as response:
            page = next(t for t in json.load(response) if t["type"] == "page")
        self.socket = connect(page["webSocketDebuggerUrl"], max_size=None)
        self.count = 0
        self.call(
            "Emulation.setDeviceMetricsOverride",
            width=WIDTH,
            height=HEIGHT,
            deviceScaleFactor=1,
            mobile=False,
        )

    def call(self, method: str, **params: object) -> dict:
        self.count += 1
        self.socket.send(json.dumps({"id": self.count, "method": method, "params": params}))
        while True:
            message = json.loads(self.socket.recv(timeout=120))
            if message.get("id") == self.count:
                if "error" in message:
                    raise RuntimeError(f"{method}: {message['error']}")
                return message["result"]

    def screenshot(self) -> tuple[np.ndarray, bytes]:
        from PIL import Image

        # the "software WebGL" notice would cover the top left of the picture
        self.call("Runtime.evaluate", expression=_HIDE_NOTICES)
        png = base64.b64decode(self.call("Page.captureScreenshot", format="png")["data"])
        return np.asarray(Image.open(io.BytesIO(png)).convert("RGB"), dtype=np.int16), png

    def settled(self, timeout: float = 150.0, quiet: float = 1.5) -> tuple[np.ndarray, bytes]:
        """The page once two screenshots ``quiet`` s apart are equal (models loaded, animations done)."""
        deadline, last = time.monotonic() + timeout, None
        while True:
            image, png = self.screenshot()
            if (
                last is not None
                and image.shape == last.shape
                and not np.any(image != last)
                and image.std() > 0
            ):
                return image, png
            if time.monotonic() > deadline:
                raise AssertionError(f"the page kept changing for {timeout} s")
            last = image
            time.sleep(quiet)

    def close(self) -> None:
        """End chromium and every process it started (a renderer left running takes a core from the next
        test), then reap it."""
        self.socket.close()
        self._signal_group(signal.SIGTERM)
        try:
            self.process.wait(timeout=20)
        except subprocess.TimeoutExpired:
            self._signal_group(signal.SIGKILL)
            self.process.wait()
        self._signal_group(signal.SIGKILL)  # what outlived the main process
        shutil.rmtree(self.folder, ignore_errors=True)

    def _signal_group(self, number: int) -> None:
        with contextlib.suppress(ProcessLookupError, PermissionError):  # the group has ended
            os.killpg(self.process.pid, number)


def _changed(
    a: np.ndarray, b: np.ndarray, points: np.ndarray, radius: int = 10, level: float = 12.0
) -> np.ndarray:
    """Per pixel point (column, row): does the mean |a - b| in a (2 radius + 1)² window exceed ``level``?"""
    out = []
    for c, r in np.round(points).astype(int):
        window = (slice(max(r - radius, 0), r + radius + 1), slice(max(c - radius, 0), c + radius + 1))
        out.append(float(np.abs(a[window] - b[window]).mean()) > level)
    return np.array(out)


def _in_view(points: np.ndarray) -> np.ndarray:
    return (points[:, 0] > 5) & (points[:, 0] < PANEL_LEFT) & (points[:, 1] > 5) & (points[:, 1] < HEIGHT - 5)


@needs_view
def test_the_robot_is_drawn_and_moves_in_a_real_browser(abb, tmp_path):
    executable = _chromium()
    links = [link.name for link in abb.description.links]
    q0, q1 = np.zeros(6), np.array([0.9, 0.7, -0.6, 0.0, 0.8, 0.0])
    with abb.view(q0, port=0, frames=["tool0"]) as v:
        browser = Browser(executable, v.url)
        try:

            def pixels(q):
                points = np.array([abb.frame_pose(q, link)[:3, 3] for link in links])
                return viewer_scene.project(points, v.camera_position, v.camera_look_at, v.fov, WIDTH, HEIGHT)

            drawn, png = browser.settled()
            (tmp_path / "drawn.png").write_bytes(png)
            assert drawn.shape == (HEIGHT, WIDTH, 3)
            v.show_robot(False)
            empty, png = browser.settled()
            (tmp_path / "empty.png").write_bytes(png)
            v.show_robot(True)
            v.update(q1)
            moved, png = browser.settled()
            (tmp_path / "moved.png").write_bytes(png)
        finally:
            browser.close()

    p0, p1 = pixels(q0), pixels(q1)
    seen0 = _in_view(p0)
    assert seen0.sum() >= 4, f"the camera should frame the robot: links at pixels {p0.round()}"
    hit0 = _changed(drawn, empty, p0[seen0])
    assert hit0.mean() >= 0.75, (
        f"robot not drawn where its links project at q0: {hit0} at "
        f"{p0[seen0].round()}; screenshots in {tmp_path}"
    )
    # far from every link the robot leaves the picture alone (the grid and sky are the same)
    corner = np.array([[30.0, HEIGHT - 100.0]])
    if np.min(np.linalg.norm(np.vstack([p0, p1]) - corner, axis=1)) > 150:
        assert not _changed(drawn, empty, corner, radius=20, level=3.0)[0]

    travelled = np.linalg.norm(p1 - p0, axis=1) > 30
    seen1 = _in_view(p1) & travelled
    assert seen1.sum() >= 3, f"q1 should move the links visibly: {p0.round()} -> {p1.round()}"
    hit1 = _changed(moved, drawn, p1[seen1])
    drawn1 = _changed(moved, empty, p1[seen1])
    assert hit1.mean() >= 0.75 and drawn1.mean() >= 0.75, (
        f"after update(q1) the links are not drawn at {p1[seen1].round()}: {hit1}, {drawn1}; see {tmp_path}"
    )
    assert _changed(moved, drawn, p0[_in_view(p0) & travelled]).mean() >= 0.5, "the old place is not cleared"


@needs_view
def test_panda_meshes_are_drawn_in_a_real_browser(tmp_path):
    """example-robot-data's textured DAE meshes, found through package:// and drawn where the links are."""
    executable = _chromium()
    panda = kinengine.load("panda")
    q = panda.neutral()
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # every mesh must be read: no "drawn as skeleton only" warning
        v = panda.view(q, port=0, frames=[])
    try:
        browser = Browser(executable, v.url)
        try:
            drawn, png = browser.settled()
            (tmp_path / "drawn.png").write_bytes(png)
            v.show_robot(False)
            empty, png = browser.settled()
            (tmp_path / "empty.png").write_bytes(png)
        finally:
            browser.close()
        links = [f"panda_link{i}" for i in range(8)] + ["panda_hand"]
        points = np.array([panda.frame_pose(q, link)[:3, 3] for link in links])
        pixels = viewer_scene.project(points, v.camera_position, v.camera_look_at, v.fov, WIDTH, HEIGHT)
    finally:
        v.close()
    seen = _in_view(pixels)
    assert seen.sum() >= 5, f"the camera should frame the robot: links at pixels {pixels.round()}"
    hit = _changed(drawn, empty, pixels[seen])
    assert hit.mean() >= 0.75, f"meshes not drawn at {pixels[seen].round()}: {hit}; screenshots in {tmp_path}"


if os.environ.get("KINENGINE_VIEWER_SCREENSHOT"):  # writes docs/images/viewer_abb.png; not a test

    @needs_view
    def test_write_documentation_screenshot(abb):
        with abb.view([0.4, 0.3, -0.2, 0.0, 0.6, 0.0], port=0, frames=["tool0"], ellipsoid="tool0") as v:
            browser = Browser(_chromium(), v.url)
            try:
                _, png = browser.settled()
            finally:
                browser.close()
        (Path(__file__).resolve().parent.parent / "docs" / "images" / "viewer_abb.png").write_bytes(png)
