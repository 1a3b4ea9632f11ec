#!/usr/bin/env python3
"""Writes the OBJ meshes of glint's own example scenes (scenes/meshes/).

A (2,3) torus knot tube, at three tessellations, so that one shape gives a
small, a medium and a large mesh for comparing accelerators; and a unit cube
(the Cornell boxes' blocks), its faces counter-clockwise seen from outside.
Deterministic:
rerunning it reproduces the committed files byte for byte.

    python3 scripts/make_meshes.py
"""
import math
import os

SIZES = {"knot_1k": (96, 6), "knot_16k": (512, 16), "knot_64k": (1024, 32)}
P, Q = 2, 3
R_TUBE = 0.28


def curve(t):
    r = math.cos(Q * t) + 2.0
    return (r * math.cos(P * t), r * math.sin(P * t), -math.sin(Q * t))


def sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def norm(a):
    l = math.sqrt(a[0] ** 2 + a[1] ** 2 + a[2] ** 2)
    return (a[0] / l, a[1] / l, a[2] / l)


def write(name, nu, nv):
    lines = [f"# (2,3) torus knot tube, {nu}x{nv} quads, {2 * nu * nv} triangles (scripts/make_meshes.py)"]
    for i in range(nu):
        t = 2 * math.pi * i / nu
        c = curve(t)
        tangent = norm(sub(curve(t + 1e-4), curve(t - 1e-4)))
        # Frame from the direction to the knot's centre line: twist-free enough
        # for a closed tube, and the same at t and t + 2*pi.
        b = norm(cross(tangent, c))
        n = cross(b, tangent)
        for j in range(nv):
            s = 2 * math.pi * j / nv
            cs, sn = math.cos(s), math.sin(s)
            p = tuple(c[k] + R_TUBE * (cs * n[k] + sn * b[k]) for k in range(3))
            lines.append("v %.6f %.6f %.6f" % p)
    for i in range(nu):
        for j in range(nv):
            a = i * nv + j + 1
            b_ = ((i + 1) % nu) * nv + j + 1
            c_ = ((i + 1) % nu) * nv + (j + 1) % nv + 1
            d = i * nv + (j + 1) % nv + 1
            lines.append(f"f {a} {c_} {b_}")
            lines.append(f"f {a} {d} {c_}")
    here = os.path.dirname(os.path.abspath(__file__))
    out = os.path.join(here, "..", "scenes", "meshes", name + ".obj")
    with open(out, "w") as f:
        f.write("\n".join(lines) + "\n")
    print(out, 2 * nu * nv, "triangles")


for name, (nu, nv) in SIZES.items():
    write(name, nu, nv)


def write_cube():
    corners = [(x, y, z) for x in (-0.5, 0.5) for y in (-0.5, 0.5) for z in (-0.5, 0.5)]
    lines = ["# unit cube centred at the origin, 12 triangles, outward counter-clockwise (scripts/make_meshes.py)"]
    lines += ["v %g %g %g" % c for c in corners]
    # corner index = 4*(x>0) + 2*(y>0) + (z>0), 1-based in the file
    quads = [(1, 2, 4, 3), (5, 7, 8, 6), (1, 5, 6, 2), (3, 4, 8, 7), (1, 3, 7, 5), (2, 6, 8, 4)]
    for a, b, c, d in quads:
        lines.append(f"f {a} {b} {c}")
        lines.append(f"f {a} {c} {d}")
    here = os.path.dirname(os.path.abspath(__file__))
    out = os.path.join(here, "..", "scenes", "meshes", "cube.obj")
    with open(out, "w") as f:
        f.write("\n".join(lines) + "\n")
    print(out, 12, "triangles")


write_cube()
