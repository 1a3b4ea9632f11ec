#!/usr/bin/env python3
"""The figures of docs/path-tracing.md: glint's path tracer beside Mitsuba 3's on the three
scenes with Mitsuba references (tests/mitsuba/NAME_ref.exr, 1024 samples), error images, and
RMSE against the reference as a function of render time.

usage: PYTHON scripts/path_tracing_figures.py [OUTDIR]   (default docs/images/path)

PYTHON is a Python with the PyPI packages mitsuba, numpy and matplotlib (e.g. the virtual
environment `scripts/bench-vs-mitsuba.sh path` creates: target/mitsuba-venv/bin/python, then
`target/mitsuba-venv/bin/pip install matplotlib`). Builds glint (release) and renders, at
128x128 on 2 threads: glint at 4, 16, 64 and 256 Sobol samples per pixel, Mitsuba 3's scalar_rgb
path tracer (scripts/mitsuba_twin.py, independent sampler, seed 7) at 4, 16, 64 and 256. Times are
each renderer's own (scene loading and acceleration-structure build excluded) and depend on the
machine's load, which the script prints. Writes:
  NAME.png      reference | glint 64 spp | Mitsuba 64 spp | |glint - ref| | |Mitsuba - ref|
                (error images: RMS over the channels, white = 0.25)
  error_vs_time.png   RMSE against the reference (log-log) against seconds, both renderers
  error_vs_time.csv   the numbers plotted
"""
import csv
import json
import os
import subprocess
import sys
import tempfile

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import mitsuba as mi  # noqa: E402
import numpy as np  # noqa: E402

mi.set_variant("scalar_rgb")
SCENES = ["cornell_box", "cornell_caustics", "mesh_sphere_light"]
SPPS = [4, 16, 64, 256]
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def read(path):
    return np.array(mi.Bitmap(path)).astype(np.float64)[..., :3]


def glint(name, spp, out, tmp):
    stats = os.path.join(tmp, "stats.json")
    subprocess.run(
        ["target/release/glint", "render", f"scenes/{name}.txt", "-o", out, "--size", "128", "128",
         "--integrator", "path", "--spp", str(spp), "--threads", "2", "--quiet",
         "--stats-json", stats],
        check=True, cwd=ROOT, stdout=subprocess.DEVNULL)
    with open(stats) as f:
        return json.load(f)["render_ms"] / 1e3


def mitsuba(name, spp, out):
    r = subprocess.run(
        [sys.executable, "scripts/mitsuba_twin.py", f"scenes/{name}.txt", out, "--size", "128",
         "--threads", "2", "--seed", "7", "--spp", str(spp)],
        check=True, cwd=ROOT, capture_output=True, text=True)
    return float(r.stdout.strip().rsplit(":", 1)[1].split()[0])


def tone(a):
    return np.clip(a, 0, 1) ** (1 / 2.2)


def err_image(a, ref):
    e = np.sqrt(((a - ref) ** 2).mean(-1)) / 0.25
    return np.repeat(np.clip(e, 0, 1)[..., None], 3, -1)


def main():
    out = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "docs/images/path"))
    os.makedirs(out, exist_ok=True)
    with open("/proc/loadavg") as f:
        print("load average before:", " ".join(f.read().split()[:3]))
    subprocess.run(["cargo", "build", "--release", "--quiet", "--bin", "glint"], check=True, cwd=ROOT)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for name in SCENES:
            ref = read(os.path.join(ROOT, f"tests/mitsuba/{name}_ref.exr"))
            rmse = lambda a: float(np.sqrt(((a - ref) ** 2).mean()))  # noqa: E731
            shown = {}
            for spp in SPPS:
                for who in ("glint", "mitsuba"):
                    path = os.path.join(tmp, f"{who}{spp}.exr")
                    t = glint(name, spp, path, tmp) if who == "glint" else mitsuba(name, spp, path)
                    img = read(path)
                    rows.append((name, who, spp, t, rmse(img)))
                    print(f"{name:18} {who:8} {spp:4} spp {t:7.2f} s  RMSE {rmse(img):.4f}")
                    if spp == 64:
                        shown[who] = img
            strip = np.concatenate(
                [tone(ref), tone(shown["glint"]), tone(shown["mitsuba"]),
                 err_image(shown["glint"], ref), err_image(shown["mitsuba"], ref)], 1)
            mi.Bitmap((strip * 255 + 0.5).astype(np.uint8)).write(os.path.join(out, f"{name}.png"))
    with open(os.path.join(out, "error_vs_time.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["scene", "renderer", "spp", "seconds", "rmse"])
        for r in rows:
            w.writerow([r[0], r[1], r[2], f"{r[3]:.3f}", f"{r[4]:.5f}"])
    fig, axes = plt.subplots(1, 3, figsize=(12, 3.6))
    for ax, name in zip(axes, SCENES):
        for who, style in (("glint", "o-"), ("mitsuba", "s--")):
            pts = [(r[3], r[4]) for r in rows if r[0] == name and r[1] == who]
            ax.loglog(*zip(*pts), style, label=who)
        ax.set_title(name)
        ax.set_xlabel("render time (s, 2 threads)")
        ax.grid(True, which="both", alpha=0.3)
    axes[0].set_ylabel("RMSE vs 1024-spp Mitsuba reference")
    axes[0].legend()
    fig.tight_layout()
    fig.savefig(os.path.join(out, "error_vs_time.png"), dpi=90)
    with open("/proc/loadavg") as f:
        print("load average after:", " ".join(f.read().split()[:3]))


if __name__ == "__main__":
    main()
