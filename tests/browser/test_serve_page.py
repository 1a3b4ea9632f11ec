"""glint serve's page in a real browser: Playwright driving Debian's chromium.

Run by `cargo test --test suite serve::browser` (tests/serve.rs), which sets
GLINT_BIN to the glint binary under test and GLINT_SHOTS to the folder the
screenshots are saved in (target/serve-screenshots/, not committed). By hand:

    GLINT_BIN=target/debug/glint python3 -m pytest -q tests/browser

Chromium: `apt-get install chromium` (Playwright's own browser download is not
used: CHROMIUM, default /usr/bin/chromium, is launched instead).
"""

import io
import os
import re
import shutil
import subprocess
import tempfile
import time
from pathlib import Path

import pytest
from PIL import Image
from playwright.sync_api import sync_playwright

REPO = Path(__file__).resolve().parents[2]
GLINT = os.environ.get("GLINT_BIN", str(REPO / "target" / "debug" / "glint"))
SHOTS = Path(os.environ.get("GLINT_SHOTS", REPO / "target" / "serve-screenshots"))
CHROMIUM = os.environ.get("CHROMIUM", "/usr/bin/chromium")
SIZE = (200, 150)
EYE = (178, 178, 178)  # the course's eye-ray grey, 0.7 (viz::raytree::kind_style)


def shot(page, name, locator=None):
    SHOTS.mkdir(parents=True, exist_ok=True)
    path = SHOTS / f"{name}.png"
    (locator or page).screenshot(path=str(path))
    return Image.open(path).convert("RGB")


@pytest.fixture(scope="module")
def scene_dir():
    d = Path(tempfile.mkdtemp(prefix="glint-browser-"))
    shutil.copy(REPO / "scenes" / "whitted.txt", d / "whitted.txt")
    yield d
    shutil.rmtree(d, ignore_errors=True)


@pytest.fixture(scope="module")
def server(scene_dir):
    p = subprocess.Popen(
        [GLINT, "serve", str(scene_dir / "whitted.txt"), "--port", "0", "--size", str(SIZE[0]), str(SIZE[1]),
         "--shadows", "--spp", "64"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )
    line = p.stdout.readline()
    m = re.search(r"http://127\.0\.0\.1:\d+/", line)
    assert m, f"no address in {line!r}"
    yield m.group(0)
    p.terminate()
    p.wait(timeout=20)


@pytest.fixture(scope="module")
def page(server):
    with sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=CHROMIUM, args=["--no-sandbox"])
        pg = browser.new_page(viewport={"width": 1300, "height": 950}, device_scale_factor=1)
        errors = []
        pg.on("pageerror", lambda e: errors.append(str(e)))
        pg.goto(server)
        pg.errors = errors
        yield pg
        browser.close()


def canvas_now(page):
    """The image canvas's pixels and the samples per pixel they hold, read in
    one script turn (so the two agree)."""
    r = page.evaluate("""() => ({ spp: glint.spp, url: document.getElementById('image').toDataURL('image/png') })""")
    import base64
    data = base64.b64decode(r["url"].split(",", 1)[1])
    return r["spp"], Image.open(io.BytesIO(data)).convert("RGB")


def mean_abs(a, b):
    pa, pb = a.tobytes(), b.tobytes()
    assert len(pa) == len(pb)
    return sum(abs(x - y) for x, y in zip(pa, pb)) / len(pa)


def test_page_loads(page):
    page.wait_for_function("window.glint && glint.spp >= 1", timeout=60000)
    assert "whitted.txt" in page.title()
    assert page.locator("#scene-name").inner_text() == "whitted.txt"
    spp, img = canvas_now(page)
    assert img.size == SIZE
    assert max(img.getextrema()[2]) > 100, "the image is dark"
    shot(page, "01-loaded")
    assert page.errors == []


def test_image_refines(page, scene_dir, tmp_path):
    # Start over and catch an early pass.
    page.select_option("select[name=spp]", "64")
    page.check("input[name=shade_back]")
    page.wait_for_function("glint.spp >= 1 && glint.spp < 64", timeout=60000, polling=5)
    early_spp, early = canvas_now(page)
    first = shot(page, "02-refine-early", page.locator("#image"))
    page.wait_for_function("glint.done && glint.spp === 64", timeout=180000)
    late_spp, late = canvas_now(page)
    second = shot(page, "03-refine-late", page.locator("#image"))
    assert early_spp < late_spp == 64
    assert first.tobytes() != second.tobytes(), "two successive screenshots are the same"
    # A 64-spp render of the same view by `glint render` (Sobol, box filter).
    ref_path = tmp_path / "ref64.png"
    subprocess.run(
        [GLINT, "render", str(scene_dir / "whitted.txt"), "-o", str(ref_path), "--size", str(SIZE[0]), str(SIZE[1]),
         "--shadows", "--shade-back", "--bounces", "5", "--spp", "64", "-q"],
        check=True,
    )
    ref = Image.open(ref_path).convert("RGB")
    e_early, e_late = mean_abs(early, ref), mean_abs(late, ref)
    print(f"mean |difference| to the 64-spp render: {e_early:.3f} at {early_spp} spp, {e_late:.3f} at 64 spp")
    assert e_late < e_early, (e_early, e_late)
    assert e_late < 2.0, e_late


def test_click_draws_the_ray_tree(page):
    box = page.locator("#image").bounding_box()
    # The glass sphere: the tree has reflected and transmitted rays.
    page.mouse.click(box["x"] + 118, box["y"] + 70)
    page.wait_for_function("glint.tree && glint.eye3d && glint.tree.pixel[0] === 118", timeout=60000)
    page.wait_for_timeout(200)
    tree = page.evaluate("glint.tree")
    kinds = {r["kind"] for r in tree["rays"]}
    assert {"eye", "shadow"} <= kinds, kinds
    rows = page.locator("#rays tbody tr").count()
    assert rows == len(tree["rays"])
    full = shot(page, "04-ray-tree")
    seg = page.evaluate("glint.eye3d")
    c = page.locator("#view3d").bounding_box()
    x0, y0, x1, y1 = seg
    assert abs(x1 - x0) + abs(y1 - y0) > 20, f"the eye ray is a point in the 3-D view: {seg}"
    hits = 0
    samples = 0
    for k in range(10, 91, 5):
        t = k / 100
        x, y = c["x"] + x0 + (x1 - x0) * t, c["y"] + y0 + (y1 - y0) * t
        if not (c["x"] + 1 < x < c["x"] + c["width"] - 1 and c["y"] + 1 < y < c["y"] + c["height"] - 1):
            continue
        samples += 1
        near = [full.getpixel((int(x) + dx, int(y) + dy)) for dx in (-1, 0, 1) for dy in (-1, 0, 1)]
        if any(all(abs(p[i] - EYE[i]) <= 10 for i in range(3)) for p in near):
            hits += 1
    assert samples >= 5, "the eye ray is outside the 3-D view"
    assert hits >= 0.8 * samples, f"eye-ray grey at {hits} of {samples} points along its segment"
    # The image overlay holds the tree's colours.
    over = shot(page, "05-overlay", page.locator("#overlay"))
    assert over.size[0] == SIZE[0]


def overlay_colours(page):
    return page.evaluate("""() => {
        const c = document.getElementById('overlay');
        const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
        const seen = {};
        for (let i = 0; i < d.length; i += 4) if (d[i + 3] > 200) seen[[d[i], d[i+1], d[i+2]].join(',')] = 1;
        return Object.keys(seen);
    }""")


def test_accelerator_switch_shows_its_walk(page):
    assert page.evaluate("glint.pick !== null")
    for accel, word in [("grid", "grid"), ("octree", "octree"), ("bvh", "bvh")]:
        page.select_option("select[name=accel]", accel)
        page.wait_for_function(f"glint.walk && glint.walk.accel.startsWith('{word}')", timeout=60000)
        page.wait_for_timeout(150)
        walk = page.evaluate("glint.walk")
        assert walk["visits"] > 0
        assert word in page.locator("#walk-text").inner_text()
        colours = overlay_colours(page)
        seg_colours = {",".join(str(round(v * 255)) for v in s[6:9]) for s in walk["segments"]}
        drawn = [s for s in seg_colours if s in colours]
        assert drawn, f"{accel}: none of the walk's colours {seg_colours} is on the overlay"
        shot(page, f"06-walk-{accel}")
    page.check("#show-grid")
    page.select_option("select[name=accel]", "grid")
    page.wait_for_function("glint.grid && glint.grid.occupied > 0", timeout=60000)
    page.check("#show-cost")
    page.wait_for_function("document.getElementById('cost').naturalWidth > 0", timeout=60000)
    shot(page, "07-grid-and-cost")
    page.uncheck("#show-grid")
    page.uncheck("#show-cost")


def test_edited_scene_rerenders(page, scene_dir):
    v0 = page.evaluate("glint.version")
    page.wait_for_function("glint.done", timeout=180000)
    _, before = canvas_now(page)
    scene = scene_dir / "whitted.txt"
    text = scene.read_text()
    assert "color 0.35 0.55 0.85" in text
    scene.write_text(text.replace("color 0.35 0.55 0.85", "color 0.9 0.2 0.1"))
    # An image of the new version, two passes into its refinement.
    page.wait_for_function(f"glint.imageVersion > {v0} && glint.spp >= 2", timeout=60000)
    _, after = canvas_now(page)
    # The top row is sky: blue before, red after.
    r0, g0, b0 = before.getpixel((SIZE[0] // 2, 0))
    r1, g1, b1 = after.getpixel((SIZE[0] // 2, 0))
    assert b0 > r0 and r1 > b1, ((r0, g0, b0), (r1, g1, b1))
    shot(page, "08-edited")


def test_broken_scene_shows_line_and_column(page, scene_dir):
    page.wait_for_function("glint.done", timeout=180000)
    _, good = canvas_now(page)
    scene = scene_dir / "whitted.txt"
    lines = scene.read_text().split("\n")
    # Line 8 is "    center 0 1.6 7": break its number.
    assert lines[7].strip() == "center 0 1.6 7", lines[7]
    lines[7] = "    center 0 1.6 seven"
    scene.write_text("\n".join(lines))
    page.wait_for_selector("#error:not([hidden])", timeout=30000)
    where = page.locator("#error-where").inner_text()
    col = lines[7].index("seven") + 1
    assert f"whitted.txt, line 8, column {col}" in where, where
    text = page.locator("#error-text").inner_text()
    assert "center 0 1.6 seven" in text and "^" in text, text
    # The caret stands under the column of the source line quoted above it.
    rows = text.split("\n")
    src = next(i for i, l in enumerate(rows) if "center 0 1.6 seven" in l)
    caret = rows[src + 1]
    assert caret.index("^") == rows[src].index("seven"), text
    _, still = canvas_now(page)
    assert still.tobytes() == good.tobytes(), "the last good image did not stay"
    shot(page, "09-broken")
    # Fixing it clears the error.
    lines[7] = "    center 0 1.6 7"
    scene.write_text("\n".join(lines))
    page.wait_for_selector("#error[hidden]", state="attached", timeout=30000)
    assert page.errors == []


def test_path_integrator(page):
    """The integrator menu offers the path tracer; its bounces follow the
    command line's default (64), the image changes, and a click's tree says
    it is the Whitted one."""
    assert page.evaluate("[...document.querySelector('select[name=integrator]').options].map(o => o.value)") == [
        "whitted", "ao", "path"]
    gen = page.evaluate("glint.gen")
    page.select_option("select[name=spp]", "4")
    page.wait_for_function(f"glint.gen > {gen} && glint.done && glint.spp === 4", timeout=120000)
    _, whitted = canvas_now(page)
    assert page.input_value("input[name=bounces]") == "5"
    gen = page.evaluate("glint.gen")
    page.select_option("select[name=integrator]", "path")
    assert page.input_value("input[name=bounces]") == "64"
    page.wait_for_function(f"glint.gen > {gen} && glint.done && glint.spp === 4 && !glint.rendering",
                           timeout=180000)
    _, path = canvas_now(page)
    assert mean_abs(path, whitted) > 2.0, mean_abs(path, whitted)
    page.wait_for_function("glint.tree !== null", timeout=60000)
    assert "Whitted ray tree" in page.locator("#tree-text").inner_text()
    shot(page, "10-path")
    gen = page.evaluate("glint.gen")
    page.select_option("select[name=integrator]", "whitted")
    assert page.input_value("input[name=bounces]") == "5"
    page.wait_for_function(f"glint.gen > {gen} && glint.done && !glint.rendering", timeout=120000)


def test_camera_moves_and_resets(page):
    """Drag orbits, arrow keys orbit, the wheel zooms: each starts a render
    of the new view; r returns to the scene's camera and its exact image."""
    page.wait_for_function("glint.done && !glint.rendering", timeout=120000)
    assert page.evaluate("glint.cam") is None
    _, start = canvas_now(page)
    gen = [page.evaluate("glint.gen")]
    box = page.locator("#image").bounding_box()
    cx, cy = box["x"] + box["width"] / 2, box["y"] + box["height"] / 2

    def moved(before_eye):
        # A new render of the moved view, to its last pass.
        page.wait_for_function(f"glint.cam !== null && glint.gen > {gen[0]} && glint.done && !glint.rendering",
                               timeout=120000)
        gen[0] = page.evaluate("glint.gen")
        eye = page.evaluate("glint.cam.eye")
        assert eye != before_eye, eye
        return eye

    page.mouse.move(cx, cy)
    page.mouse.down()
    page.mouse.move(cx + 40, cy, steps=8)
    page.mouse.up()
    eye = moved(None)
    _, orbited = canvas_now(page)
    assert mean_abs(orbited, start) > 2.0, "the image did not follow the drag"
    page.locator("#image").focus()
    page.keyboard.press("ArrowUp")
    eye = moved(eye)
    page.mouse.move(cx, cy)
    page.mouse.wheel(0, -200)
    eye2 = moved(eye)
    centre = page.evaluate("glint.scene.bounds")
    mid = [(a + b) / 2 for a, b in zip(centre["min"], centre["max"])]
    dist = lambda e: sum((x - m) ** 2 for x, m in zip(e, mid)) ** 0.5
    assert dist(eye2) < dist(eye), (eye, eye2)
    shot(page, "11-camera-moved")
    page.locator("#image").focus()
    page.keyboard.press("r")
    page.wait_for_function(f"glint.cam === null && glint.gen > {gen[0]} && glint.done && !glint.rendering",
                           timeout=120000)
    _, back = canvas_now(page)
    assert back.tobytes() == start.tobytes(), "r did not return to the scene's image"
    assert page.errors == []
