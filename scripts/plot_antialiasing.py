#!/usr/bin/env python3
"""Draws docs/images/aa/rmse.png from docs/images/aa/results.csv (written by
`cargo run --release --example antialiasing_study`). Needs matplotlib
(`pip install matplotlib` in a virtual environment; not a glint dependency)."""
import csv
import collections
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

rows = collections.defaultdict(list)
with open("docs/images/aa/results.csv") as f:
    for r in csv.DictReader(f):
        rows[(r["scene"], r["method"])].append((float(r["rays_per_pixel"]), float(r["rmse"])))

scenes = ["sphere_triangle", "checkerboard"]
styles = {
    "uniform": ("tab:gray", "s"),
    "random": ("tab:red", "o"),
    "jittered": ("tab:blue", "^"),
    "sobol": ("tab:green", "D"),
    "adaptive_d2": ("tab:purple", "x"),
    "adaptive_d3": ("tab:orange", "+"),
}
fig, axes = plt.subplots(1, 2, figsize=(11, 4.5))
for ax, scene in zip(axes, scenes):
    for method, (color, marker) in styles.items():
        pts = sorted(rows.get((scene, method), []))
        if not pts:
            continue
        ax.plot([p[0] for p in pts], [p[1] for p in pts], color=color, marker=marker, label=method)
    ax.set_xscale("log", base=2)
    ax.set_yscale("log")
    ax.set_xlabel("camera rays per pixel")
    ax.set_ylabel("RMSE vs 1024 spp (linear, clamped)")
    ax.set_title(scene.replace("_", " ") + " (96x96)")
    ax.grid(True, which="both", alpha=0.3)
axes[0].legend()
fig.tight_layout()
fig.savefig("docs/images/aa/rmse.png", dpi=100)
print("wrote docs/images/aa/rmse.png")
