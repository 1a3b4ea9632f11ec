#!/usr/bin/env python3
"""Renders a glint scene (MIT 6.837 format) with Mitsuba 3's path tracer: the twin of
`glint render --integrator path` on the subset of the format that both read the same way.

usage: python3 scripts/mitsuba_twin.py SCENE OUT.exr [--size W [H]] [--spp N] [--seed S]
                                       [--max-depth D] [--threads T] [--variant V]
                                       [--albedo-scale F] [--move-emitters DX DY DZ] [--whitted]

Needs the PyPI package mitsuba (`pip install mitsuba`; measured with 3.9.1, variant scalar_rgb).
Writes a linear RGB float32 OpenEXR image and prints the render time (scene loading excluded).

The subset, and how each part is read (docs/scene-format.md, "Emission and units"):
- PerspectiveCamera (center, direction, up, angle = full field of view across the longer image
  side; aperture and focusDistance make a thin lens): `perspective` or `thinlens`, box filter of
  radius 0.5 pixel (glint's default `--filter box:0.5`), independent sampler.
- Background color: a `constant` environment of that radiance (none when black).
- PhongMaterial / Material with only one of: diffuseColor (Lambert: `diffuse`, two-sided as
  glint's BSDFs are), reflectiveColor with a black diffuse (mirror: `conductor` with material
  `none` and that specular reflectance), transparentColor with a black diffuse (glass:
  `dielectric`, interior index indexOfRefraction, exterior 1, that specular transmittance).
  emittedColor adds an `area` emitter of that radiance to every shape with the material (front
  side only, as in glint). specularColor, glossiness and textures are outside the subset.
- Sphere (also under a Transform that keeps it a sphere: rotations, translations, uniform
  scales), Triangle and TriangleMesh (OBJ, under any Transform; flat-shaded), Group nesting.
  Triangles are baked into world space and grouped per material into one mesh each.
- Lights: AreaLight sphere (radiance color*power/(pi*A), black surface), PointLight with
  attenuation 0 0 1 (intensity = color), DirectionalLight (irradiance = color).
Anything else (planes, orthographic cameras, shutters, keyframes, flat area lights, which glint
makes two-sided) is refused with a message naming it.

--whitted: the twin of glint's Whitted tree (`glint render --shadows`, the default integrator)
instead, on scenes lit by sphere AreaLights only, with diffuse materials, a black background and no
ambient light (anything else is refused): Mitsuba's `direct` integrator with emitter sampling only
(`bsdf_samples` 0), `emitter_samples` = the scene's `Samples shadow` x the number of lights (glint
sends `shadow` rays to each light; Mitsuba sends as many rays in all, each to a light picked at
random), emitters hidden from camera rays (the Whitted tree's area lights are not seen; keep them out
of view, where Mitsuba's still block rays), every light's radiance times pi (the Whitted diffuse
term has no 1/pi), `Samples lens` x --spp camera samples per pixel (glint's `spp x lens`). A
`Samples` block with other fields is refused.

--albedo-scale and --move-emitters make deliberately wrong twins (every diffuse albedo scaled;
every emitter moved), which the comparison tests must tell apart from the right one.
"""
import argparse
import math
import os
import sys
import tempfile
import time


class Unsupported(Exception):
    pass


# --- reading the scene file --------------------------------------------------------------------

def tokens(text):
    out = []
    for line in text.splitlines():
        line = line.split("#", 1)[0]
        out += line.replace("{", " { ").replace("}", " } ").split()
    return out


def tree(toks):
    """Nested lists: a word followed by '{' becomes (word, [children])."""
    stack = [[]]
    i = 0
    while i < len(toks):
        t = toks[i]
        if t == "}":
            children = stack.pop()
            name = stack[-1].pop()
            stack[-1].append((name, children))
        elif t == "{":
            stack.append([])
        else:
            stack[-1].append(t)
        i += 1
    if len(stack) != 1:
        raise SystemExit("unbalanced braces")
    return stack[0]


def fields(children):
    """Maps each word of a block to the numbers after it (and blocks to their children)."""
    out = {}
    i = 0
    while i < len(children):
        c = children[i]
        if isinstance(c, tuple):
            out.setdefault(c[0], []).append(c[1])
            i += 1
            continue
        nums = []
        j = i + 1
        while j < len(children) and isinstance(children[j], str) and is_number(children[j]):
            nums.append(float(children[j]))
            j += 1
        out.setdefault(c, []).append(nums)
        i = j
    return out


def is_number(s):
    try:
        float(s)
        return True
    except ValueError:
        return False


# --- 4x4 matrices as nested lists (row-major, column vectors) -----------------------------------

def matmul(a, b):
    return [[sum(a[i][k] * b[k][j] for k in range(4)) for j in range(4)] for i in range(4)]


IDENTITY = [[1.0 if i == j else 0.0 for j in range(4)] for i in range(4)]


def translate(v):
    m = [r[:] for r in IDENTITY]
    for i in range(3):
        m[i][3] = v[i]
    return m


def scale(v):
    m = [r[:] for r in IDENTITY]
    for i in range(3):
        m[i][i] = v[i]
    return m


def rotate(axis, deg):
    x, y, z = axis
    n = math.sqrt(x * x + y * y + z * z)
    x, y, z = x / n, y / n, z / n
    c, s = math.cos(math.radians(deg)), math.sin(math.radians(deg))
    t = 1 - c
    return [
        [t * x * x + c, t * x * y - s * z, t * x * z + s * y, 0],
        [t * x * y + s * z, t * y * y + c, t * y * z - s * x, 0],
        [t * x * z - s * y, t * y * z + s * x, t * z * z + c, 0],
        [0, 0, 0, 1],
    ]


def apply(m, p):
    return [sum(m[i][k] * p[k] for k in range(3)) + m[i][3] for i in range(3)]


def transform_commands(children):
    """The matrix of a Transform's commands (first listed acts last) and its object."""
    m = IDENTITY
    obj = None
    i = 0
    while i < len(children):
        c = children[i]
        if isinstance(c, tuple):
            name, sub = c
            if name in ("Rotate", "Matrix"):
                nums = [float(x) for x in sub]
                m = matmul(m, rotate(nums[:3], nums[3]) if name == "Rotate" else
                           [nums[4 * r:4 * r + 4] for r in range(4)])
            else:
                if obj is not None:
                    raise SystemExit("a Transform holds one object")
                obj = c
            i += 1
            continue
        arity = {"Translate": 3, "Scale": 3, "UniformScale": 1, "XRotate": 1, "YRotate": 1,
                 "ZRotate": 1, "Rotate": 4, "Matrix": 16}
        if c not in arity:
            raise Unsupported(f"transform command {c}")
        nums = [float(x) for x in children[i + 1:i + 1 + arity[c]]]
        i += 1 + arity[c]
        if c == "Translate":
            x = translate(nums)
        elif c == "Scale":
            x = scale(nums)
        elif c == "UniformScale":
            x = scale([nums[0]] * 3)
        elif c in ("XRotate", "YRotate", "ZRotate"):
            x = rotate({"X": [1, 0, 0], "Y": [0, 1, 0], "Z": [0, 0, 1]}[c[0]], nums[0])
        elif c == "Rotate":
            x = rotate(nums[:3], nums[3])
        else:
            x = [nums[4 * r:4 * r + 4] for r in range(4)]
        m = matmul(m, x)
    return m, obj


def read_obj(path):
    verts, faces = [], []
    with open(path) as f:
        for line in f:
            t = line.split()
            if not t:
                continue
            if t[0] == "v":
                verts.append([float(x) for x in t[1:4]])
            elif t[0] == "f":
                idx = []
                for c in t[1:]:
                    k = int(c.split("/")[0])
                    idx.append(k - 1 if k > 0 else len(verts) + k)
                for j in range(1, len(idx) - 1):
                    faces.append((idx[0], idx[j], idx[j + 1]))
    return verts, faces


class Twin:
    def __init__(self, path, albedo_scale=1.0, move=(0.0, 0.0, 0.0), whitted=False):
        self.dir = os.path.dirname(os.path.abspath(path))
        self.albedo_scale = albedo_scale
        self.move = move
        self.whitted = whitted
        with open(path) as f:
            top = fields(tree(tokens(f.read())))
        blocks = ("PerspectiveCamera", "Background", "Materials", "Group", "Lights")
        for name in top:
            if name not in blocks + (("Samples",) if whitted else ()):
                raise Unsupported(f"block {name}")
        self.camera = fields(top["PerspectiveCamera"][0])
        bg = fields(top["Background"][0]) if "Background" in top else {}
        self.background = bg.get("color", [[0.5, 0.5, 0.5]])[0]
        samples = fields(top["Samples"][0]) if "Samples" in top else {}
        for k in samples:
            if k not in ("shadow", "lens"):
                raise Unsupported(f"Samples {k}")
        self.shadow_samples = int(samples.get("shadow", [[1]])[0][0])
        self.lens_samples = int(samples.get("lens", [[1]])[0][0])
        if whitted and (any(self.background) or any(bg.get("ambientLight", [[0, 0, 0]])[0])):
            raise Unsupported("a background colour or ambient light (--whitted: black, none)")
        self.materials = []
        if "Materials" in top:
            for c in top["Materials"][0]:
                if isinstance(c, tuple):
                    if c[0] not in ("PhongMaterial", "Material"):
                        raise Unsupported(f"material {c[0]}")
                    self.materials.append(self.material(fields(c[1])))
        self.spheres = []  # (center, radius, material)
        self.triangles = {}  # material -> list of 3 vertices
        self.group(top["Group"][0], IDENTITY, None)
        self.lights = []
        if "Lights" in top:
            for c in top["Lights"][0]:
                if isinstance(c, tuple):
                    self.lights.append(c)

    def material(self, f):
        get = lambda k, d: f[k][0] if k in f else d
        diffuse = get("diffuseColor", [1.0, 1.0, 1.0])
        specular = get("specularColor", [0.0, 0.0, 0.0])
        reflective = get("reflectiveColor", [0.0, 0.0, 0.0])
        transparent = get("transparentColor", [0.0, 0.0, 0.0])
        ior = get("indexOfRefraction", [1.0])[0]
        emission = get("emittedColor", [0.0, 0.0, 0.0])
        if self.whitted and (any(reflective) or any(transparent) or any(emission)):
            raise Unsupported("a mirror, glass or emitting material (--whitted: diffuse only)")
        if any(specular) or get("glossiness", [0.0])[0] > 0:
            raise Unsupported("specularColor or glossiness (a Phong lobe)")
        kinds = [k for k, v in (("diffuse", diffuse), ("mirror", reflective), ("glass", transparent)) if any(v)]
        if len(kinds) > 1:
            raise Unsupported(f"a material that mixes lobes ({', '.join(kinds)})")
        kind = kinds[0] if kinds else "diffuse"
        if kind == "diffuse":
            bsdf = {"type": "twosided", "bsdf": {"type": "diffuse", "reflectance": rgb([
                min(1.0, x * self.albedo_scale) for x in diffuse])}}
        elif kind == "mirror":
            bsdf = {"type": "conductor", "material": "none", "specular_reflectance": rgb(reflective)}
        else:
            bsdf = {"type": "dielectric", "int_ior": ior, "ext_ior": 1.0,
                    "specular_transmittance": rgb(transparent)}
        return {"bsdf": bsdf, "emission": emission if any(emission) else None}

    def group(self, children, m, mat):
        i = 0
        while i < len(children):
            c = children[i]
            if isinstance(c, str):
                if c == "MaterialIndex":
                    mat = int(children[i + 1])
                    i += 2
                    continue
                if c == "numObjects":
                    i += 2
                    continue
                raise SystemExit(f"unexpected {c} in Group")
            self.object(c, m, mat)
            i += 1

    def object(self, c, m, mat):
        name, sub = c
        if name == "Group":
            self.group(sub, m, mat)
        elif name == "Transform":
            x, obj = transform_commands(sub)
            self.object(obj, matmul(m, x), mat)
        elif name == "Sphere":
            f = fields(sub)
            center, radius = f["center"][0], f["radius"][0][0]
            cols = [[m[r][k] for r in range(3)] for k in range(3)]
            lens = [math.sqrt(sum(x * x for x in col)) for col in cols]
            dots = [sum(cols[a][r] * cols[b][r] for r in range(3)) for a, b in ((0, 1), (0, 2), (1, 2))]
            if max(lens) - min(lens) > 1e-6 * max(lens) or max(abs(d) for d in dots) > 1e-6 * max(lens) ** 2:
                raise Unsupported("a sphere under a non-uniform transform")
            self.spheres.append((apply(m, center), radius * lens[0], mat))
        elif name == "Triangle":
            f = fields(sub)
            tri = [apply(m, f[k][0]) for k in ("vertex0", "vertex1", "vertex2")]
            self.triangles.setdefault(mat, []).append(tri)
        elif name == "TriangleMesh":
            obj_file = sub[sub.index("obj_file") + 1]
            verts, faces = read_obj(os.path.join(self.dir, obj_file))
            w = [apply(m, v) for v in verts]
            self.triangles.setdefault(mat, []).extend([[w[a], w[b], w[d]] for a, b, d in faces])
        else:
            raise Unsupported(f"object {name}")

    def moved(self, p):
        return [p[i] + self.move[i] for i in range(3)]

    def scene_dict(self, width, height, spp, max_depth, tmp):
        import mitsuba as mi
        T = mi.ScalarTransform4f
        cam = self.camera
        for k in cam:
            if k not in ("center", "direction", "up", "angle", "aperture", "focusDistance"):
                raise Unsupported(f"camera field {k}")
        eye, d = cam["center"][0], cam["direction"][0]
        target = [eye[i] + d[i] for i in range(3)]
        sensor = {
            "type": "perspective",
            "fov": cam["angle"][0][0],
            "fov_axis": "larger",
            "to_world": T().look_at(origin=eye, target=target, up=cam["up"][0]),
            "film": {"type": "hdrfilm", "width": width, "height": height, "pixel_format": "rgb",
                     "component_format": "float32", "rfilter": {"type": "box"}},
            "sampler": {"type": "independent", "sample_count": spp},
        }
        # The Whitted tree's diffuse term has no 1/pi: its lights count pi times as bright.
        boost = math.pi if self.whitted else 1.0
        if "aperture" in cam and cam["aperture"][0][0] > 0:
            sensor["type"] = "thinlens"
            sensor["aperture_radius"] = cam["aperture"][0][0]
            # glint's focus distance is measured along `direction`, as Mitsuba's.
            sensor["focus_distance"] = cam["focusDistance"][0][0]
        scene = {"type": "scene", "sensor": sensor,
                 "integrator": {"type": "path", "max_depth": max_depth}}
        if self.whitted:
            if not self.lights or any(k != "AreaLight" or "sphere" not in fields(sub)
                                      for k, sub in self.lights):
                raise Unsupported("lights other than sphere AreaLights (--whitted)")
            scene["integrator"] = {"type": "direct", "bsdf_samples": 0, "hide_emitters": True,
                                   "emitter_samples": self.shadow_samples * len(self.lights)}
        if any(self.background):
            scene["environment"] = {"type": "constant", "radiance": rgb(self.background)}
        default = {"bsdf": {"type": "twosided", "bsdf": {"type": "diffuse", "reflectance": rgb(
            [min(1.0, self.albedo_scale)] * 3)}}, "emission": None}
        mat = lambda i: default if i is None else self.materials[i]
        for n, (c, r, i) in enumerate(self.spheres):
            m = mat(i)
            shape = {"type": "sphere", "center": c, "radius": r, "bsdf": m["bsdf"]}
            if m["emission"]:
                shape["center"] = self.moved(c)
                shape["emitter"] = {"type": "area", "radiance": rgb(m["emission"])}
            scene[f"sphere{n}"] = shape
        for i, tris in self.triangles.items():
            m = mat(i)
            path = os.path.join(tmp, f"mesh{i}.obj")
            shift = self.move if m["emission"] else (0.0, 0.0, 0.0)
            with open(path, "w") as f:
                for t in tris:
                    for v in t:
                        f.write("v %.9g %.9g %.9g\n" % tuple(v[k] + shift[k] for k in range(3)))
                for k in range(len(tris)):
                    f.write(f"f {3 * k + 1} {3 * k + 2} {3 * k + 3}\n")
            shape = {"type": "obj", "filename": path, "face_normals": True, "bsdf": m["bsdf"]}
            if m["emission"]:
                shape["emitter"] = {"type": "area", "radiance": rgb(m["emission"])}
            scene[f"mesh{'none' if i is None else i}"] = shape
        for n, (kind, sub) in enumerate(self.lights):
            f = fields(sub)
            if kind == "AreaLight":
                if "sphere" not in f:
                    raise Unsupported("a flat AreaLight (glint's emit from both faces)")
                s = fields(f["sphere"][0])
                c, r = s["center"][0], s["radius"][0][0]
                color, power = f["color"][0], f["power"][0][0]
                radiance = [boost * x * power / (math.pi * 4 * math.pi * r * r) for x in color]
                scene[f"light{n}"] = {"type": "sphere", "center": self.moved(c), "radius": r,
                                      "bsdf": {"type": "diffuse", "reflectance": rgb([0, 0, 0])},
                                      "emitter": {"type": "area", "radiance": rgb(radiance)}}
            elif kind == "PointLight":
                if f.get("attenuation", [[1, 0, 0]])[0] != [0, 0, 1]:
                    raise Unsupported("a point light without attenuation 0 0 1")
                scene[f"light{n}"] = {"type": "point", "position": self.moved(f["position"][0]),
                                      "intensity": rgb(f["color"][0])}
            elif kind == "DirectionalLight":
                scene[f"light{n}"] = {"type": "directional", "direction": f["direction"][0],
                                      "irradiance": rgb(f["color"][0])}
            else:
                raise Unsupported(f"light {kind}")
        return scene


def rgb(v):
    return {"type": "rgb", "value": [float(x) for x in v]}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("scene")
    ap.add_argument("out")
    ap.add_argument("--size", type=int, nargs="+", default=[128])
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--max-depth", type=int, default=-1,
                    help="longest path in vertices after the camera, as Mitsuba counts (-1: no limit)")
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--variant", default="scalar_rgb")
    ap.add_argument("--albedo-scale", type=float, default=1.0)
    ap.add_argument("--move-emitters", type=float, nargs=3, default=[0.0, 0.0, 0.0])
    ap.add_argument("--whitted", action="store_true",
                    help="the twin of glint's Whitted tree (direct lighting from sphere lights)")
    a = ap.parse_args()
    width = a.size[0]
    height = a.size[1] if len(a.size) > 1 else width
    try:
        twin = Twin(a.scene, a.albedo_scale, a.move_emitters, a.whitted)
    except Unsupported as e:
        raise SystemExit(f"{a.scene}: outside the Mitsuba twin's subset: {e}")
    import drjit as dr
    import mitsuba as mi
    mi.set_variant(a.variant)
    pool = dr.thread_count()
    dr.set_thread_count(a.threads)
    spp = a.spp * twin.lens_samples if a.whitted else a.spp
    with tempfile.TemporaryDirectory() as tmp:
        try:
            d = twin.scene_dict(width, height, spp, a.max_depth, tmp)
        except Unsupported as e:
            raise SystemExit(f"{a.scene}: outside the Mitsuba twin's subset: {e}")
        scene = mi.load_dict(d)
        t0 = time.time()
        img = mi.render(scene, seed=a.seed, spp=spp)
        dt = time.time() - t0
    # (Writing an EXR with a pool of one thread deadlocks in 3.9.1: restore the pool first.)
    dr.set_thread_count(pool)
    mi.Bitmap(img).write(a.out)
    print(f"mitsuba {mi.__version__} {mi.variant()} {width}x{height} spp {spp} seed {a.seed} "
          f"threads {a.threads}: {dt:.4f} s")


if __name__ == "__main__":
    main()
