#!/usr/bin/env python3
"""Makes docs/images/serve/page.png: glint serve's page after a click on the
glass sphere of scenes/whitted.txt, with the binary SAH BVH's walk shown.

    cargo build --release && python3 scripts/serve-screenshot.py

Needs what the browser tests need (Debian's chromium, `pip install
playwright`); GLINT_BIN names the binary (default target/release/glint),
CHROMIUM the browser (default /usr/bin/chromium).
"""

import os
import re
import subprocess
import sys
from pathlib import Path

from playwright.sync_api import sync_playwright

REPO = Path(__file__).resolve().parents[1]
GLINT = os.environ.get("GLINT_BIN", str(REPO / "target" / "release" / "glint"))
CHROMIUM = os.environ.get("CHROMIUM", "/usr/bin/chromium")
OUT = REPO / "docs" / "images" / "serve" / "page.png"
PIXEL = (236, 140)


def main():
    server = subprocess.Popen(
        [GLINT, "serve", str(REPO / "scenes" / "whitted.txt"), "--port", "0", "--size", "400", "300",
         "--shadows", "--shade-back", "--spp", "16"],
        stdout=subprocess.PIPE, text=True,
    )
    try:
        m = re.search(r"http://127\.0\.0\.1:\d+/", server.stdout.readline())
        if not m:
            sys.exit("serve-screenshot: the server printed no address")
        with sync_playwright() as pw:
            browser = pw.chromium.launch(executable_path=CHROMIUM, args=["--no-sandbox"])
            page = browser.new_page(viewport={"width": 1300, "height": 740}, device_scale_factor=1)
            page.goto(m.group(0))
            page.wait_for_function("window.glint && glint.done", timeout=120000)
            page.select_option("select[name=accel]", "bvh")
            page.wait_for_function("glint.done && !glint.rendering", timeout=120000)
            box = page.locator("#image").bounding_box()
            page.mouse.click(box["x"] + PIXEL[0], box["y"] + PIXEL[1])
            page.wait_for_function(
                f"glint.tree && glint.tree.pixel[0] === {PIXEL[0]} && glint.walk && glint.done", timeout=120000)
            page.wait_for_timeout(300)
            OUT.parent.mkdir(parents=True, exist_ok=True)
            page.screenshot(path=str(OUT))
            browser.close()
        print(f"wrote {OUT.relative_to(REPO)}")
    finally:
        server.terminate()
        server.wait(timeout=20)


if __name__ == "__main__":
    main()
