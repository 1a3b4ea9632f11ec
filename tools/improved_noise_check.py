#!/usr/bin/env python3
"""Independent check of src/material/noise.rs.

A separate transcription of Ken Perlin's Java reference ImprovedNoise (2002), in
double precision, used to compute the expected values in noise.rs's test
`known_values_of_the_reference_algorithm`. It also checks that the permutation
table in noise.rs is a permutation of 0..255.

Run from the crate root:  python3 tools/improved_noise_check.py
"""
import math
import re

src = open("src/material/noise.rs").read()
table = re.search(r"PERMUTATION: \[u8; 256\] = \[(.*?)\];", src, re.S).group(1)
P = [int(v) for v in table.replace("\n", " ").split(",") if v.strip()]
assert sorted(P) == list(range(256)), "not a permutation of 0..255"
p = P + P  # the reference's doubled table


def fade(t):
    return t * t * t * (t * (t * 6 - 15) + 10)


def lerp(t, a, b):
    return a + t * (b - a)


def grad(h, x, y, z):
    h &= 15
    u = x if h < 8 else y
    v = y if h < 4 else (x if h in (12, 14) else z)
    return (u if h & 1 == 0 else -u) + (v if h & 2 == 0 else -v)


def noise(x, y, z):
    X, Y, Z = (int(math.floor(c)) & 255 for c in (x, y, z))
    x, y, z = x - math.floor(x), y - math.floor(y), z - math.floor(z)
    u, v, w = fade(x), fade(y), fade(z)
    A = p[X] + Y
    AA, AB = p[A] + Z, p[A + 1] + Z
    B = p[X + 1] + Y
    BA, BB = p[B] + Z, p[B + 1] + Z
    return lerp(w,
                lerp(v, lerp(u, grad(p[AA], x, y, z), grad(p[BA], x - 1, y, z)),
                     lerp(u, grad(p[AB], x, y - 1, z), grad(p[BB], x - 1, y - 1, z))),
                lerp(v, lerp(u, grad(p[AA + 1], x, y, z - 1), grad(p[BA + 1], x - 1, y, z - 1)),
                     lerp(u, grad(p[AB + 1], x, y - 1, z - 1), grad(p[BB + 1], x - 1, y - 1, z - 1))))


for pt in [(0, 0, 0.5), (0.5, 0.5, 0.5), (3.7, 42.0, 7.0), (-1.3, 2.7, -0.4), (10.25, -3.75, 100.5)]:
    print(pt, repr(noise(*pt)))
