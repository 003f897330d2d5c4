"""The operator's dashboard (issue 21) in a real browser against the real shiftd on loopback.

Headless Chromium (Debian's ``chromium``, driven by Playwright's Python client with ``executable_path``; its own
browser download is never used) loads ``/`` from the daemon, and the tests check outcomes, not the absence of
errors: what the page's debug hook ``window.__shift`` counts as drawn, and the canvas pixels where the path, a
robot and a correction must be.

- The operator's loop: upload a map through the page's form, create a plan by clicking its start on the map,
  see the path drawn coloured by speed, assign it to a scripted robot (a Zenoh participant) from the page, see
  the robot's marker follow its odometry, and see a correction drawn after an obstacle appears on its path.
- With a token on the daemon: an action without it shows the API's own message, and works once the token is
  typed; the token never appears in a requested URL.
- A 30-robot fleet at 10 Hz: the page's main-thread busy fraction (CDP ``Performance.getMetrics``
  ``TaskDuration`` over wall time) stays under one core, and first paint is under a second.

Screenshots go to ``$SHIFT_ARTEFACTS`` (or a pytest temporary folder); their paths and the measured figures
are printed. ``SHIFT_CHROMIUM`` overrides ``/usr/bin/chromium``. ``SHIFT_DASHBOARD_DIR=server/daemon/dashboard``
serves the page's files from that folder instead of the binary's embedded copy (for editing the page without
rebuilding shiftd; by default the test checks that the binary serves exactly the files of the repository).
"""

from __future__ import annotations

import json
import math
import mimetypes
import os
import re
import time
from pathlib import Path
from typing import Any, Callable, Dict, Iterator, List, Optional, Sequence, Tuple, TypeVar

import httpx
import pytest
import zenoh
from playwright.sync_api import Browser, BrowserContext, Page, Playwright, sync_playwright

from shift_client import Robot
from shift_client.keys import KeySpace
from shift_client.robot import peer_config

from conftest import REPO_ROOT, Daemon
from conftest import poll as conftest_poll

CHROMIUM = os.environ.get("SHIFT_CHROMIUM", "/usr/bin/chromium")
CHROMIUM_ARGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
]
DASHBOARD_DIR = REPO_ROOT / "server/daemon/dashboard"
VIEWPORT = {"width": 1600, "height": 960}
LONG = 180.0
T = TypeVar("T")


# --- fixtures -------------------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def playwright() -> Iterator[Playwright]:
    with sync_playwright() as p:
        yield p


@pytest.fixture(scope="module")
def browser(playwright: Playwright) -> Iterator[Browser]:
    if not os.access(CHROMIUM, os.X_OK):
        pytest.fail(f"no Chromium at {CHROMIUM} (Debian: apt-get install chromium; or set SHIFT_CHROMIUM)")
    b = playwright.chromium.launch(executable_path=CHROMIUM, headless=True, args=CHROMIUM_ARGS)
    yield b
    b.close()


@pytest.fixture(scope="module")
def artefacts(tmp_path_factory: pytest.TempPathFactory) -> Path:
    env = os.environ.get("SHIFT_ARTEFACTS")
    path = Path(env) if env else tmp_path_factory.mktemp("dashboard-artefacts")
    path.mkdir(parents=True, exist_ok=True)
    return path


class Tab:
    """A page on the dashboard with what it requested and what it logged."""

    def __init__(self, context: BrowserContext, page: Page, daemon: Daemon) -> None:
        self.context = context
        self.page = page
        self.daemon = daemon
        self.requests: List[Dict[str, Any]] = []
        self.console_errors: List[str] = []
        self.page_errors: List[str] = []
        page.on("request", lambda r: self.requests.append({"url": r.url, "method": r.method, "headers": r.headers}))
        page.on("console", lambda m: self.console_errors.append(m.text) if m.type == "error" else None)
        page.on("pageerror", lambda e: self.page_errors.append(str(e)))

    def shift(self) -> Dict[str, Any]:
        """The page's debug hook (a fresh snapshot)."""
        return self.page.evaluate("() => JSON.parse(JSON.stringify(window.__shift))")

    def wait(self, f: Callable[[Dict[str, Any]], Optional[T]], what: str, timeout: float = LONG) -> T:
        """Polls the debug hook until ``f`` gives a value other than None/False."""
        deadline = time.monotonic() + timeout
        last: Dict[str, Any] = {}
        while True:
            self.check_no_script_errors()
            last = self.shift()
            v = f(last)
            if v is not None and v is not False:
                return v
            if time.monotonic() > deadline:
                raise AssertionError(
                    f"timed out waiting for {what}; page state: {json.dumps(last)[:2000]}\n"
                    f"page errors: {self.console_errors[-5:]}\nshiftd log:\n{self.daemon.log_tail(20)}"
                )
            time.sleep(0.1)

    def check_no_script_errors(self) -> None:
        assert not self.page_errors, f"uncaught errors in the page: {self.page_errors}"

    def canvas_box(self) -> Dict[str, float]:
        box = self.page.get_by_test_id("map-canvas").bounding_box()
        assert box is not None
        return box

    def to_screen(self, x: float, y: float) -> Tuple[float, float]:
        """CSS pixel (relative to the canvas) of a map point."""
        sx, sy = self.page.evaluate("([x, y]) => window.__shift.toScreen(x, y)", [x, y])
        return float(sx), float(sy)

    def click_map(self, x: float, y: float) -> None:
        box = self.canvas_box()
        sx, sy = self.to_screen(x, y)
        self.page.mouse.click(box["x"] + sx, box["y"] + sy)

    def pixels(self, points: Sequence[Tuple[float, float]], radius: int = 0) -> List[List[List[int]]]:
        """RGBA pixels of the map canvas around CSS points: for each point the (2r+1)² pixels of its block."""
        return self.page.evaluate(
            """([pts, r]) => {
                const c = document.querySelector('[data-testid=map-canvas]');
                const ctx = c.getContext('2d');
                const k = c.width / c.clientWidth;
                return pts.map(([x, y]) => {
                    const px = Math.round(x * k) - r, py = Math.round(y * k) - r, n = 2 * r + 1;
                    const d = ctx.getImageData(px, py, n, n).data;
                    const out = [];
                    for (let i = 0; i < d.length; i += 4) out.push([d[i], d[i + 1], d[i + 2], d[i + 3]]);
                    return out;
                });
            }""",
            [list(points), radius],
        )

    def screenshot(self, artefacts: Path, name: str) -> Path:
        path = artefacts / name
        self.page.screenshot(path=str(path))
        return path


def open_tab(browser: Browser, daemon: Daemon) -> Tab:
    context = browser.new_context(viewport=VIEWPORT, device_scale_factor=1)
    page = context.new_page()
    page.set_default_timeout(30_000)
    if os.environ.get("SHIFT_DASHBOARD_DIR"):
        serve_from_disk(page, Path(os.environ["SHIFT_DASHBOARD_DIR"]))
    return Tab(context, page, daemon)


def serve_from_disk(page: Page, folder: Path) -> None:
    """Answers ``/`` and ``/dashboard/*`` from ``folder`` (developing the page without rebuilding shiftd)."""

    def handle(route: Any) -> None:
        path = route.request.url.split("://", 1)[1].split("/", 1)[1].split("?", 1)[0]
        name = "index.html" if path == "" else path.split("/", 1)[1]
        file = folder / name
        ctype = mimetypes.guess_type(name)[0] or "application/octet-stream"
        if name.endswith(".js"):
            ctype = "text/javascript"
        route.fulfill(status=200, body=file.read_bytes(), headers={"content-type": ctype, "cache-control": "no-cache"})

    page.route(lambda url: url.split("://", 1)[1].split("/", 1)[1].split("?")[0] == "", handle)
    page.route("**/dashboard/*", handle)


def say(capsys: pytest.CaptureFixture[str], text: str) -> None:
    """Prints past pytest's capture (figures and artefact paths belong in CI's log)."""
    with capsys.disabled():
        print(f"\n[dashboard] {text}", flush=True)


# --- maps and paths -------------------------------------------------------------------------------------------

RES = 0.1


def write_room(folder: Path) -> Tuple[Path, Path]:
    """A 20 m × 12 m room at 0.1 m (a PGM and its map_server YAML): outer walls, an inner wall from the bottom
    wall up to y = 7.5 m at x = 10 m (a door above it) and a 1 m pillar at (15, 3)."""
    w, h = int(20 / RES), int(12 / RES)
    rows = []
    for r in range(h):  # image row 0 is the top (largest y)
        y = (h - 1 - r + 0.5) * RES
        row = bytearray()
        for c in range(w):
            x = (c + 0.5) * RES
            wall = c < 2 or c >= w - 2 or r < 2 or r >= h - 2
            inner = abs(x - 10.0) < 0.15 and y < 7.5
            pillar = abs(x - 15.0) < 0.5 and abs(y - 3.0) < 0.5
            row.append(0 if (wall or inner or pillar) else 254)
        rows.append(bytes(row))
    pgm = folder / "room.pgm"
    pgm.write_bytes(f"P5\n{w} {h}\n255\n".encode() + b"".join(rows))
    yaml = folder / "room.yaml"
    yaml.write_text(
        "image: room.pgm\nresolution: 0.1\norigin: [0.0, 0.0, 0.0]\nnegate: 0\n"
        "occupied_thresh: 0.65\nfree_thresh: 0.196\n",
        encoding="utf-8",
    )
    return yaml, pgm


def hold_the_worker(d: Daemon, auth: Dict[str, str]) -> List[str]:
    """Uploads a 60 m × 60 m hall at 0.05 m with a lattice of pillars (1.44 M cells: seconds to plan even in a
    release build) as site ``dash-hall`` and queues two plans on it; returns their ids. The first is planning
    when this returns, so a plan posted next waits behind both on a one-worker daemon."""
    n = 1200
    pillar = lambda c: (c // 20) % 6 == 3  # noqa: E731 (1 m pillars every 6 m)
    rows = []
    for r in range(n):
        row = bytearray(254 for _ in range(n))
        if r < 4 or r >= n - 4:
            row = bytearray(n)
        else:
            row[0:4] = bytes(4)
            row[n - 4 : n] = bytes(4)
            if pillar(r):
                for c in range(4, n - 4):
                    if pillar(c):
                        row[c] = 0
        rows.append(bytes(row))
    files = {
        "yaml": ("hall.yaml", b"image: hall.pgm\nresolution: 0.05\norigin: [0.0, 0.0, 0.0]\nnegate: 0\n"
                 b"occupied_thresh: 0.65\nfree_thresh: 0.196\n", "application/yaml"),
        "image": ("hall.pgm", f"P5\n{n} {n}\n255\n".encode() + b"".join(rows), "application/octet-stream"),
    }
    r = httpx.post(f"{d.url}/v1/sites/dash-hall/map", files=files, headers=auth, timeout=60.0)
    assert r.status_code in (200, 201), r.text
    ids = []
    for _ in range(2):
        body = {"site": "dash-hall", "start": [1.0, 1.0], "robot": {"radius": 0.15, "tool_width": 0.3}}
        r = httpx.post(f"{d.url}/v1/plans", json=body, headers=auth, timeout=10.0)
        assert r.status_code == 202, r.text
        ids.append(r.json()["plan_id"])
    poll(lambda: api_get(d, f"/v1/plans/{ids[0]}")["status"] == "planning" or None, "the hall being planned", 30)
    return ids


Pt = Tuple[float, float]


def seg_dist(p: Pt, a: Pt, b: Pt) -> float:
    dx, dy = b[0] - a[0], b[1] - a[1]
    l2 = dx * dx + dy * dy
    t = 0.0 if l2 == 0 else max(0.0, min(1.0, ((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / l2))
    return math.hypot(p[0] - a[0] - t * dx, p[1] - a[1] - t * dy)


def longest_lane(w: Sequence[Pt], cover: Sequence[bool], lo: int = 1) -> Tuple[int, int]:
    """Indices (i, j) of the longest straight stretch of cover waypoints from index ``lo`` on."""
    best, i = (lo, lo), lo
    while i + 1 < len(w):
        j = i
        while (
            j + 1 < len(w)
            and cover[i]
            and cover[j + 1]
            and all(seg_dist(w[k], w[i], w[j + 1]) < 1e-6 for k in range(i + 1, j + 1))
        ):
            j += 1
        if math.dist(w[i], w[j]) > math.dist(w[best[0]], w[best[1]]):
            best = (i, j)
        i = max(j, i + 1)
    return best


def walk(points: Sequence[Pt], step: float = 0.2) -> Iterator[Tuple[float, float, float]]:
    """Poses every ``step`` metres along a polyline, heading along it."""
    for a, b in zip(points, points[1:]):
        d = math.dist(a, b)
        if d < 1e-9:
            continue
        yaw = math.atan2(b[1] - a[1], b[0] - a[0])
        n = max(1, int(d / step))
        for k in range(n):
            f = k / n
            yield a[0] + (b[0] - a[0]) * f, a[1] + (b[1] - a[1]) * f, yaw


def close(c: Sequence[int], ref: Sequence[int], tol: float) -> bool:
    return math.dist(c[:3], ref[:3]) <= tol


def api_get(daemon: Daemon, path: str) -> Any:
    r = httpx.get(f"{daemon.url}{path}", timeout=10.0)
    r.raise_for_status()
    return r.json()


def poll(f: Callable[[], Optional[T]], what: str, timeout: float = LONG) -> T:
    """:func:`conftest.poll` with this module's default timeout."""
    return conftest_poll(f, what, timeout)


def check_served_files(daemon: Daemon) -> None:
    """The binary serves exactly the repository's page (a stale binary would test an old page)."""
    if os.environ.get("SHIFT_DASHBOARD_DIR"):
        return
    index = httpx.get(f"{daemon.url}/", timeout=10.0)
    assert index.status_code == 200 and index.headers["content-type"].startswith("text/html")
    assert index.content == (DASHBOARD_DIR / "index.html").read_bytes(), "shiftd serves another index.html: rebuild it"
    for f in sorted(DASHBOARD_DIR.iterdir()):
        if f.name == "index.html":
            continue
        r = httpx.get(f"{daemon.url}/dashboard/{f.name}", timeout=10.0)
        assert r.status_code == 200, f"/dashboard/{f.name}: {r.status_code}"
        assert r.content == f.read_bytes(), f"shiftd serves another {f.name}: rebuild it (cargo build -p shiftd)"
        if f.suffix == ".js":
            assert r.headers["content-type"].startswith("text/javascript"), r.headers["content-type"]


def first_paint(tab: Tab) -> float:
    """The page's first paint, ms after navigation (the browser records the entry after that frame: polled)."""

    def paint() -> Optional[float]:
        entries = tab.page.evaluate(
            "() => performance.getEntriesByType('paint').map(e => ({name: e.name, t: e.startTime}))"
        )
        byname = {e["name"]: e["t"] for e in entries}
        t = byname.get("first-paint", byname.get("first-contentful-paint"))
        return None if t is None else float(t)

    return poll(paint, "a first-paint entry in the page's performance timeline", 10)


# --- the operator's loop --------------------------------------------------------------------------------------


def test_operator_uploads_plans_assigns_and_watches_a_robot_corrected(
    daemon: Daemon, browser: Browser, artefacts: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    check_served_files(daemon)
    tab = open_tab(browser, daemon)
    page = tab.page
    shots: List[Path] = []
    try:
        page.goto(f"{daemon.url}/")
        tab.wait(lambda s: s["site"] is not None and s["sse"] == "live", "a site shown and its stream live", 30)
        fp = first_paint(tab)
        say(capsys, f"first paint {fp:.0f} ms")
        assert fp < 1000.0

        # Upload the room through the page's form.
        yaml, pgm = write_room(tmp_path)
        page.get_by_test_id("upload-open").click()
        page.get_by_test_id("upload-site").fill("dash-room")
        page.get_by_test_id("upload-yaml").set_input_files(str(yaml))
        page.get_by_test_id("upload-image").set_input_files(str(pgm))
        page.get_by_test_id("upload-submit").click()
        tab.wait(lambda s: s["site"] == "dash-room" and s["view"]["scale"] > 0 and s["sse"] == "live", "the room shown")
        assert page.get_by_test_id("site-select").input_value() == "dash-room"
        # The site selector switches sites (map, stream and all) and back.
        page.get_by_test_id("site-select").select_option("demo")
        tab.wait(lambda s: s["site"] == "demo" and s["sse"] == "live", "the demo site shown", 30)
        page.get_by_test_id("site-select").select_option("dash-room")
        tab.wait(lambda s: s["site"] == "dash-room" and s["sse"] == "live", "the room shown again", 30)
        summary = api_get(daemon, "/v1/sites/dash-room")
        assert (summary["width"], summary["height"], summary["resolution"]) == (200, 120, 0.1)
        # Drawn to scale: 20 m of map take 20 × scale pixels; the scale bar says metres.
        scale = tab.shift()["view"]["scale"]
        ax, _ = tab.to_screen(0.0, 0.0)
        bx, _ = tab.to_screen(20.0, 0.0)
        assert abs((bx - ax) - 20.0 * scale) < 0.5
        # The scale bar is as long as the length it names.
        label = page.get_by_test_id("scale-bar").inner_text().strip()
        value, unit = label.split()
        metres = float(value) * {"m": 1.0, "cm": 0.01, "mm": 0.001}[unit]
        bar_px = page.locator("#scale-bar").bounding_box()["width"]  # type: ignore[index]
        assert abs(bar_px - metres * scale) < 3.0, (label, bar_px, scale)
        # The cursor's position in metres.
        box = tab.canvas_box()
        sx, sy = tab.to_screen(5.0, 6.0)
        page.mouse.move(box["x"] + sx, box["y"] + sy)
        readout = page.get_by_test_id("cursor-readout").inner_text()
        m = re.search(r"x (-?[\d.]+) m\s+y (-?[\d.]+) m\s+(\w+)", readout)
        assert m and abs(float(m[1]) - 5.0) < 2 / scale and abs(float(m[2]) - 6.0) < 2 / scale, readout
        assert m[3] == "free", readout
        # Pan by drag: the map moves with the pointer.
        before = tab.shift()["view"]
        page.mouse.down()
        page.mouse.move(box["x"] + sx + 120, box["y"] + sy + 60, steps=6)
        page.mouse.up()
        after = tab.shift()["view"]
        assert after["cx"] == pytest.approx(before["cx"] - 120 / scale, abs=0.02)
        assert after["cy"] == pytest.approx(before["cy"] + 60 / scale, abs=0.02)
        page.get_by_test_id("fit").click()
        assert tab.shift()["view"]["cx"] == pytest.approx(before["cx"])
        # A wall cell is dark, a free cell light (once the view the click asked for is drawn: the map draws on
        # the next animation frame).
        def wall_and_free() -> Optional[bool]:
            (wall,), (free,) = tab.pixels([tab.to_screen(10.0, 3.0)]), tab.pixels([tab.to_screen(5.0, 6.0)])
            return (sum(wall[0][:3]) < 200 and sum(free[0][:3]) > 600) or None

        poll(wall_and_free, "a dark wall cell and a light free cell on the canvas", 10)

        # A plan: "New plan", then a click on its start.
        page.get_by_test_id("np-radius").fill("0.25")
        page.get_by_test_id("np-tool").fill("0.5")
        page.get_by_test_id("new-plan").click()
        assert page.get_by_test_id("pick-hint").is_visible()
        start = (1.5, 1.5)
        tab.click_map(*start)
        plan_id = tab.wait(lambda s: s["selectedPlan"], "the new plan selected", 30)
        state = tab.wait(
            lambda s: s if s["pathPlan"] == plan_id and s["pathPoints"] > 0 else None, "the path drawn", LONG
        )
        doc = api_get(daemon, f"/v1/plans/{plan_id}/path")
        req_start = doc["waypoints"][0]
        assert math.dist((req_start["x"], req_start["y"]), start) < 0.6, "the plan starts where the map was clicked"
        assert state["pathPoints"] == len(doc["waypoints"])
        vs = [w["v"] for w in doc["waypoints"]]
        assert state["speedRange"] == pytest.approx([min(vs), max(vs)])
        assert state["planStatus"] == "ready"
        legend = page.get_by_test_id("speed-legend")
        assert legend.is_visible() and "m/s" in legend.inner_text()
        metrics = page.get_by_test_id("plan-metrics").inner_text()
        assert "Coverage" in metrics and "Length" in metrics and "%" in metrics

        # The path is in the canvas: cover segments' midpoints carry the speed palette's colours, and stop
        # carrying them when the path layer is switched off.
        palette = page.evaluate(
            "async () => { const m = await import('/dashboard/map.js');"
            " return Array.from({length: 24}, (_, k) => m.paletteAt((k + 0.5) / 24)); }"
        )
        wps = doc["waypoints"]
        cover = [(a, b) for a, b in zip(wps, wps[1:]) if a["kind"] == "cover" and b["kind"] == "cover"]
        step = max(1, len(cover) // 300)
        mids = [tab.to_screen((a["x"] + b["x"]) / 2, (a["y"] + b["y"]) / 2) for a, b in cover[::step]]
        assert len(mids) > 20

        def path_hits() -> float:
            blocks = tab.pixels(mids, radius=1)
            hits = sum(1 for b in blocks if any(any(close(px, c, 40) for c in palette) for px in b))
            return hits / len(blocks)

        on = path_hits()
        page.get_by_text("Layers").click()
        page.locator("[data-layer=path]").uncheck()
        tab.wait(lambda s: s["pathPoints"] == 0, "the path layer off", 10)
        page.wait_for_timeout(100)
        off = path_hits()
        page.locator("[data-layer=path]").check()
        page.get_by_text("Layers").click()
        tab.wait(lambda s: s["pathPoints"] > 0, "the path layer on", 10)
        say(capsys, f"path pixels: {on:.0%} of {len(mids)} cover midpoints in the palette, {off:.0%} with it off")
        assert on > 0.8 and off < 0.2
        shots.append(tab.screenshot(artefacts, "01-plan-ready.png"))

        with Robot("dash-r1", daemon.zenoh_endpoint) as robot:
            robot.publish_odom(start[0], start[1], 0.0)
            # Assign it from the page: the robot list offers it once the daemon has seen it.
            option = "[data-testid=assign-robot] option[value='dash-r1']"
            page.wait_for_selector(option, state="attached", timeout=60_000)
            page.get_by_test_id("assign-robot").select_option("dash-r1")
            page.get_by_test_id("assign").click()
            got = robot.wait_for_plan(plan_id, timeout=LONG)
            assert got.version == 1
            tab.wait(lambda s: s["planStatus"] == "active", "the plan active on the page", 30)

            # Drive along the plan up to its longest lane and onto it; the marker follows.
            path = [(w.x, w.y) for w in got.waypoints]
            lane = longest_lane(path, [w.kind == "cover" for w in got.waypoints])
            assert math.dist(path[lane[0]], path[lane[1]]) > 4.0, "a lane long enough to drive along"
            poses = list(walk(path[: lane[0] + 1], 0.2))
            ux = (path[lane[1]][0] - path[lane[0]][0]) / math.dist(path[lane[0]], path[lane[1]])
            uy = (path[lane[1]][1] - path[lane[0]][1]) / math.dist(path[lane[0]], path[lane[1]])
            lane_yaw = math.atan2(uy, ux)
            poses += [(path[lane[0]][0] + ux * 0.2 * k, path[lane[0]][1] + uy * 0.2 * k, lane_yaw) for k in range(5)]
            seen: List[Tuple[float, float]] = []
            for i, (x, y, yaw) in enumerate(poses):
                robot.publish_odom(x, y, yaw, vx=0.5)
                time.sleep(0.01)
                if i % max(1, len(poses) // 4) == 0:
                    r = tab.shift()["robots"].get("dash-r1")
                    if r and r["x"] is not None:
                        seen.append((r["x"], r["y"]))
            x, y, yaw = poses[-1]
            robot_state = tab.wait(
                lambda s: (lambda r: r if r and r["x"] == pytest.approx(x) and r["y"] == pytest.approx(y) else None)(
                    s["robots"].get("dash-r1")
                ),
                "the marker at the last pose",
                30,
            )
            assert robot_state["alive"] and robot_state["plan"] == plan_id and robot_state["drawn"]
            assert robot_state["trail"] >= 2
            assert len({(round(a, 2), round(b, 2)) for a, b in seen + [(x, y)]}) >= 2, f"the marker moved: {seen}"
            # The marker is in the canvas where the pose is (the robot's dark body).
            body = tab.pixels([tab.to_screen(x, y)], radius=3)[0]
            assert any(close(px, (15, 23, 42), 30) for px in body), body
            # The robots table (rendered a few times a second) names the plan it follows.
            page.wait_for_function(
                "id => (document.querySelector(\"[data-testid=robot-row][data-robot='dash-r1']\")?.innerText || '')"
                ".includes(id)",
                arg=plan_id,
            )
            tab.wait(lambda s: (s["robots"]["dash-r1"]["driven"] or 0) > 0, "driven > 0", 30)
            shots.append(tab.screenshot(artefacts, "02-robot-driving.png"))

            # A 0.2 m post on the lane 2 m ahead of the robot: a correction, drawn.
            ox, oy = x + ux * 2.0, y + uy * 2.0
            post = [
                (ox - 0.1 + 0.05 * i, oy - 0.1 + 0.05 * j, 0.1 + 0.2 * k)
                for i in range(5)
                for j in range(5)
                for k in range(3)
            ]
            # The robot stands and sees the post until the daemon corrects its plan (a loaded machine may take
            # a while to place the first clouds).
            deadline = time.monotonic() + LONG
            while (robot.plan is None or robot.plan.version < 2) and time.monotonic() < deadline:
                robot.publish_odom(x, y, yaw)
                robot.publish_cloud(post)
                time.sleep(0.25)
            if robot.plan is None or robot.plan.version < 2:
                view = api_get(daemon, "/v1/robots/dash-r1")
                raise AssertionError(f"no correction: robot {view}; plan {api_get(daemon, f'/v1/plans/{plan_id}')}")
            new = robot.wait_for_plan(plan_id, min_version=2, timeout=10)
            drawn = tab.wait(
                lambda s: s if s["correctionMarkers"] > 0 and s["corrections"] > 0 else None, "a correction drawn", 60
            )
            assert drawn["pathVersion"] >= 2, "the drawn path is the corrected version"
            tab.wait(lambda s: s["liveCount"] > 0, "the post's live points drawn", 30)
            corrections = api_get(daemon, f"/v1/plans/{plan_id}/corrections")
            assert corrections and corrections[0]["version"] == 2 and new.version >= 2
            page.get_by_test_id("correction-row").first.wait_for(state="visible")
            # The replacing waypoints are highlighted in the canvas (magenta), near where they are.
            patch = [(w["x"], w["y"]) for w in corrections[0]["waypoints"]]
            blocks = tab.pixels([tab.to_screen(px, py) for px, py in patch], radius=2)
            magenta = sum(1 for b in blocks if any(close(px, (192, 38, 211), 45) for px in b))
            assert magenta >= max(1, len(patch) // 2), f"{magenta} of {len(patch)} patch points highlighted"
            shots.append(tab.screenshot(artefacts, "03-correction.png"))

            # Zoom in around the correction: the point under the cursor stays under it.
            box = tab.canvas_box()
            cx, cy = tab.to_screen(ox, oy)
            page.mouse.move(box["x"] + cx, box["y"] + cy)
            before = page.evaluate("([x, y]) => window.__shift.toWorld(x, y)", [cx, cy])
            page.mouse.wheel(0, -700)
            tab.wait(lambda s: s["view"]["scale"] > scale * 2, "zoomed in", 10)
            after = page.evaluate("([x, y]) => window.__shift.toWorld(x, y)", [cx, cy])
            assert math.dist(before, after) < 0.05, (before, after)
            page.wait_for_timeout(300)
            shots.append(tab.screenshot(artefacts, "04-correction-zoomed.png"))
            page.get_by_test_id("fit").click()

            # Measured coverage arrives as a heat layer (the robot's tool swept what it drove).
            tab.wait(lambda s: s["coverageCells"] > 0, "measured coverage drawn", 30)
        tab.wait(lambda s: s["robots"]["dash-r1"]["alive"] is False, "the robot lost once it left", 60)
        page.wait_for_selector("[data-testid=robot-row][data-robot='dash-r1'][data-alive='false']")
        shots.append(tab.screenshot(artefacts, "05-robot-lost.png"))
        tab.check_no_script_errors()
        assert not [e for e in tab.console_errors if "favicon" not in e], tab.console_errors
    finally:
        try:
            shots.append(tab.screenshot(artefacts, "99-last.png"))
        finally:
            tab.context.close()
            say(capsys, "screenshots: " + ", ".join(str(p) for p in shots))


# --- the token ------------------------------------------------------------------------------------------------


def test_actions_ask_for_the_token_show_the_api_message_and_never_put_it_in_a_url(
    token_daemon: Daemon, browser: Browser, artefacts: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    d = token_daemon
    token = d.token
    # What the API says without a token and with a wrong one.
    req = {"site": "demo", "start": [0.5, 0.5], "robot": {"radius": 0.15, "tool_width": 0.3}}
    no_token = httpx.post(f"{d.url}/v1/plans", json=req, timeout=10.0)
    wrong = httpx.post(f"{d.url}/v1/plans", json=req, headers={"authorization": "Bearer nope-nope"}, timeout=10.0)
    assert (no_token.status_code, wrong.status_code) == (401, 403)
    msg_401, msg_403 = no_token.json()["error"]["message"], wrong.json()["error"]["message"]

    tab = open_tab(browser, d)
    page = tab.page
    try:
        page.goto(f"{d.url}/")
        tab.wait(lambda s: s["site"] == "demo" and s["view"]["scale"] > 0, "the demo site shown", 30)
        banner = page.get_by_test_id("error-banner")

        def new_plan_click() -> None:
            page.get_by_test_id("new-plan").click()
            tab.click_map(0.5, 0.5)

        # No token: the API's 401 message in the banner, and the page asks for the token.
        new_plan_click()
        page.get_by_test_id("token-dialog").wait_for(state="visible")
        assert banner.is_visible()
        assert page.get_by_test_id("error-message").inner_text() == msg_401
        assert page.get_by_test_id("token-dialog-message").inner_text() == msg_401
        page.locator("#token-dialog-cancel").click()
        assert api_get(d, "/v1/plans?site=demo")["items"] == [], "nothing was created"

        # A wrong token typed in the bar: the 403 message.
        page.get_by_test_id("token-input").fill("nope-nope")
        page.get_by_test_id("token-save").click()
        assert page.get_by_test_id("token-state").inner_text() == "token set"
        new_plan_click()
        page.get_by_test_id("token-dialog").wait_for(state="visible")
        assert page.get_by_test_id("error-message").inner_text() == msg_403
        shots = [tab.screenshot(artefacts, "10-token-refused.png")]

        # The right one in the dialog: the same action is retried and goes through.
        page.get_by_test_id("token-dialog-input").fill(token)
        page.get_by_test_id("token-dialog-submit").click()
        plan_id = tab.wait(lambda s: s["selectedPlan"], "the plan created after the token", 30)
        assert banner.is_hidden()
        items = api_get(d, "/v1/plans?site=demo")["items"]
        assert [p["plan_id"] for p in items] == [plan_id]
        tab.wait(lambda s: s["pathPoints"] > 0, "its path drawn", LONG)
        shots.append(tab.screenshot(artefacts, "11-token-accepted.png"))

        # Cancel from the page: a plan queued behind two others (one worker), two clicks (no native dialog). The
        # two ahead plan a large pillared hall on another site, so the queued one stays queued however fast the
        # machine is (a demo plan ahead of it drains in well under a second); they are cancelled afterwards.
        auth = {"authorization": f"Bearer {token}"}
        blockers = hold_the_worker(d, auth)
        r = httpx.post(f"{d.url}/v1/plans", json=req, headers=auth, timeout=10.0)
        assert r.status_code == 202, r.text
        queued = r.json()["plan_id"]
        assert api_get(d, f"/v1/plans/{queued}")["status"] == "queued"
        page.locator(f"[data-testid=plan-row][data-plan='{queued}']").click()
        tab.wait(lambda s: s["selectedPlan"] == queued and s["planStatus"] == "queued", "the queued plan selected", 30)
        page.get_by_test_id("cancel-plan").click()
        page.get_by_test_id("cancel-plan").click()
        tab.wait(lambda s: s["planStatus"] == "cancelled", "the plan cancelled", 30)
        assert api_get(d, f"/v1/plans/{queued}")["status"] == "cancelled"
        # The plan panel re-renders at most every 250 ms: the button goes grey on its next render.
        page.wait_for_function("() => document.querySelector('[data-testid=cancel-plan]').disabled", timeout=10_000)
        assert [api_get(d, f"/v1/plans/{b}")["status"] for b in blockers] != ["ready", "ready"], "the worker was held"
        for b in blockers:
            httpx.delete(f"{d.url}/v1/plans/{b}", headers=auth, timeout=10.0)
        for b in blockers:
            poll(lambda b=b: api_get(d, f"/v1/plans/{b}")["status"] in ("cancelled", "ready") or None, f"{b} ended", 60)

        # A mission on the site shows up with its status, its robots' plans and coverage figures.
        mission = {
            "site": "demo",
            "robots": [
                {"id": "tok-a", "start": [0.5, 0.5], "radius": 0.15, "tool_width": 0.3},
                {"id": "tok-b", "start": [7.5, 7.5], "radius": 0.15, "tool_width": 0.3},
            ],
        }
        r = httpx.post(f"{d.url}/v1/missions", json=mission, headers=auth, timeout=10.0)
        assert r.status_code == 202, r.text
        mission_id = r.json()["mission_id"]
        row = page.locator(f"[data-testid=mission-row][data-mission='{mission_id}']")
        row.wait_for(state="attached", timeout=30_000)
        page.wait_for_function(
            "id => document.querySelector(`[data-testid=mission-row][data-mission='${id}']`)"
            "?.dataset.status === 'ready'",
            arg=mission_id,
            timeout=LONG * 1000,
        )
        text = row.inner_text()
        assert "tok-a" in text and "tok-b" in text and "planned" in text and "measured" in text, text
        row.scroll_into_view_if_needed()
        shots.append(tab.screenshot(artefacts, "12-mission.png"))

        # Only headers carry it: no requested URL holds either token, and the accepted POST had the header.
        urls = [r["url"] for r in tab.requests]
        assert not [u for u in urls if token in u or "nope-nope" in u], urls
        assert token not in page.url
        deletes = [r for r in tab.requests if r["method"] == "DELETE"]
        assert [r["headers"].get("authorization") for r in deletes] == [f"Bearer {token}"]
        posts = [r for r in tab.requests if r["method"] == "POST" and r["url"].endswith("/v1/plans")]
        assert len(posts) == 3
        assert "authorization" not in posts[0]["headers"]
        assert posts[1]["headers"].get("authorization") == "Bearer nope-nope"
        assert posts[2]["headers"].get("authorization") == f"Bearer {token}"
        reads = [r for r in tab.requests if r["method"] == "GET" and "/v1/" in r["url"]]
        assert reads and not [r for r in reads if "authorization" in r["headers"]], "reads go without the token"
        tab.check_no_script_errors()
        say(capsys, "token screenshots: " + ", ".join(str(p) for p in shots))
    finally:
        tab.context.close()


# --- a fleet of 30 at 10 Hz -----------------------------------------------------------------------------------


def browser_cpu_ticks() -> Tuple[int, int]:
    """CPU ticks (user + system) of every Chromium process started under this test process, and their count."""
    me = os.getpid()
    parent: Dict[int, int] = {}
    comm: Dict[int, str] = {}
    ticks: Dict[int, int] = {}
    for d in Path("/proc").iterdir():
        if not d.name.isdigit():
            continue
        try:
            stat = (d / "stat").read_text()
        except OSError:
            continue
        name = stat[stat.index("(") + 1 : stat.rindex(")")]
        fields = stat[stat.rindex(")") + 2 :].split()
        pid = int(d.name)
        parent[pid] = int(fields[1])
        comm[pid] = name
        ticks[pid] = int(fields[11]) + int(fields[12])

    def mine(pid: int) -> bool:
        seen = 0
        while pid > 1 and seen < 64:
            if pid == me:
                return True
            pid = parent.get(pid, 1)
            seen += 1
        return False

    pids = [p for p in ticks if "chrom" in comm[p].lower() and mine(p)]
    return sum(ticks[p] for p in pids), len(pids)


def free_spots(grid: Dict[str, Any], n: int, clearance: float) -> List[Tuple[float, float]]:
    """``n`` points of the grid's free floor at least ``clearance`` metres from anything not free, spread out."""
    res, (ox, oy), w, h = grid["resolution"], grid["origin"], grid["width"], grid["height"]
    cells = grid["cells"]
    k = int(math.ceil(clearance / res))

    def clear(c: int, r: int) -> bool:
        return all(
            0 <= c + dc < w and 0 <= r + dr < h and cells[(r + dr) * w + c + dc] == 0
            for dr in range(-k, k + 1)
            for dc in range(-k, k + 1)
        )

    step = max(1, int(min(w, h) / (2 * math.sqrt(n) + 2)))
    spots = [
        (ox + (c + 0.5) * res, oy + (r + 0.5) * res)
        for r in range(k, h - k, step)
        for c in range(k, w - k, step)
        if clear(c, r)
    ]
    assert len(spots) >= n, f"only {len(spots)} free spots for {n} robots"
    return [spots[int(i * len(spots) / n)] for i in range(n)]


class Fleet:
    """``n`` robots on one Zenoh session: a liveliness token and JSON odometry each, driving small circles
    around ``centres``."""

    def __init__(self, endpoint: str, names: Sequence[str], centres: Sequence[Tuple[float, float]]) -> None:
        self.keys = KeySpace()
        self.names = list(names)
        self.centres = list(centres)
        self.session = zenoh.open(peer_config(endpoint))
        self.tokens = [self.session.liveliness().declare_token(self.keys.alive(n)) for n in self.names]
        self.pubs = [self.session.declare_publisher(self.keys.odom(n)) for n in self.names]
        self.last: Dict[str, Tuple[float, float]] = {}

    def pose(self, i: int, t: float) -> Tuple[float, float, float]:
        cx, cy = self.centres[i]
        a = t * 0.8 + i
        return cx + 0.15 * math.cos(a), cy + 0.15 * math.sin(a), a + math.pi / 2

    def publish(self, t: float) -> None:
        stamp = time.time()
        for i, (n, pub) in enumerate(zip(self.names, self.pubs)):
            x, y, yaw = self.pose(i, t)
            body = {"x": x, "y": y, "yaw": yaw, "vx": 0.12, "vy": 0.0, "wz": 0.8, "stamp": stamp}
            pub.put(json.dumps(body).encode("utf-8"))
            self.last[n] = (x, y)

    def close(self) -> None:
        for t in self.tokens:
            t.undeclare()
        self.session.close()  # type: ignore[no-untyped-call]


def test_a_fleet_of_30_at_10_hz_keeps_the_page_under_one_core(
    daemon: Daemon, browser: Browser, artefacts: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    names = [f"perf-{i:02d}" for i in range(30)]
    fleet = Fleet(daemon.zenoh_endpoint, names, free_spots(api_get(daemon, "/v1/sites/demo/map"), 30, 0.3))
    tab = open_tab(browser, daemon)
    page = tab.page
    try:
        # Robots with no plan feed the daemon's default site (`[zenoh] site`, "demo").
        t0 = time.monotonic()
        fleet.publish(0.0)
        poll(
            lambda: True
            if sum(1 for r in api_get(daemon, "/v1/robots") if r["robot"] in names and r.get("pose")) == 30
            else None,
            "30 robots with a pose",
            60,
        )
        page.goto(f"{daemon.url}/#site=demo")
        fp = first_paint(tab)
        tab.wait(lambda s: s["site"] == "demo" and s["sse"] == "live", "the demo site live", 30)

        cdp = tab.context.new_cdp_session(page)
        cdp.send("Performance.enable", {"timeDomain": "timeTicks"})

        def metrics() -> Dict[str, float]:
            return {m["name"]: m["value"] for m in cdp.send("Performance.getMetrics")["metrics"]}

        # Warm up: every robot drawn.
        deadline = time.monotonic() + 30
        next_t = time.monotonic()
        while True:
            fleet.publish(time.monotonic() - t0)
            next_t += 0.1
            time.sleep(max(0.0, next_t - time.monotonic()))
            s = tab.shift()
            if sum(1 for n in names if n in s["robots"] and s["robots"][n]["drawn"]) == 30:
                break
            assert time.monotonic() < deadline, f"30 robots not drawn: {sorted(s['robots'])}"

        page.evaluate(
            """() => { window.__longtasks = 0; window.__longtaskMs = 0;
                new PerformanceObserver(l => { for (const e of l.getEntries()) { window.__longtasks++;
                    window.__longtaskMs += e.duration; } }).observe({entryTypes: ['longtask']}); }"""
        )
        before = tab.shift()
        m0 = metrics()
        cpu0, nproc = browser_cpu_ticks()
        w0 = time.monotonic()
        sent = 0
        next_t = time.monotonic()
        while time.monotonic() - w0 < 5.0:
            fleet.publish(time.monotonic() - t0)
            sent += 1
            next_t += 0.1
            time.sleep(max(0.0, next_t - time.monotonic()))
        m1 = metrics()
        cpu1, _ = browser_cpu_ticks()
        wall = time.monotonic() - w0
        after = tab.shift()
        long_tasks = page.evaluate("() => [window.__longtasks, window.__longtaskMs]")

        busy = (m1["TaskDuration"] - m0["TaskDuration"]) / (m1["Timestamp"] - m0["Timestamp"])
        script = (m1["ScriptDuration"] - m0["ScriptDuration"]) / (m1["Timestamp"] - m0["Timestamp"])
        cores = (cpu1 - cpu0) / os.sysconf("SC_CLK_TCK") / wall
        frames = after["frames"] - before["frames"]
        robot_events = after["sseEvents"]["robots"] - before["sseEvents"]["robots"]
        shot = tab.screenshot(artefacts, "20-fleet-30.png")
        say(
            capsys,
            f"30 robots × 10 Hz for {wall:.1f} s ({sent} rounds): main thread busy {busy:.3f} of a core "
            f"(script {script:.3f}), all {nproc} Chromium processes {cores:.3f} cores, {frames} frames "
            f"({frames / wall:.1f}/s), {robot_events} robots events ({robot_events / wall:.1f}/s), "
            f"long tasks {long_tasks[0]} ({long_tasks[1]:.0f} ms), first paint {fp:.0f} ms; screenshot {shot}",
        )
        assert busy < 1.0
        assert fp < 1000.0
        # The page really followed the fleet meanwhile: updates at 5 Hz or more, every robot where it was sent.
        assert robot_events / wall >= 5.0
        assert frames / wall >= 5.0
        final = tab.wait(
            lambda s: s
            if all(
                n in s["robots"] and math.dist((s["robots"][n]["x"], s["robots"][n]["y"]), fleet.last[n]) < 1e-9
                for n in names
            )
            else None,
            "every robot at its last pose",
            10,
        )
        assert final["robotsDrawn"] >= 30
        tab.check_no_script_errors()
    finally:
        tab.context.close()
        fleet.close()
