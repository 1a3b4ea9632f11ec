#!/usr/bin/env python3
"""Writes PLY and glTF test files: the fuzz seed corpora
(fuzz/corpus/ply_loader, fuzz/corpus/gltf_loader) and a conformance set
(a folder given as the first argument) in the layouts of the Stanford
scanning repository's PLY files (big-endian binary with `confidence` and
`intensity`, `range_grid` elements, triangle strips, ASCII) and of glTF
(embedded, external buffer, GLB), with broken and hostile variants.

    python3 scripts/make_asset_files.py /tmp/conformance   # then
    scripts/conformance.sh /tmp/conformance
"""
import base64, json, math, os, struct, sys

def sphere(n):
    pos, tri = [], []
    for i in range(n + 1):
        for j in range(2 * n):
            th, ph = math.pi * i / n, math.pi * j / n
            pos.append((math.sin(th) * math.cos(ph), math.cos(th), math.sin(th) * math.sin(ph)))
    k = lambda i, j: i * 2 * n + j % (2 * n)
    for i in range(n):
        for j in range(2 * n):
            tri.append((k(i, j), k(i + 1, j), k(i + 1, j + 1)))
            tri.append((k(i, j), k(i + 1, j + 1), k(i, j + 1)))
    return pos, tri

def ply(pos, tri, fmt, extra=(), normals=False, colors=False, face_type="int", strips=False, range_grid=False):
    e = {"ascii": "<", "binary_little_endian": "<", "binary_big_endian": ">"}[fmt]
    h = ["ply", f"format {fmt} 1.0", "comment made by glint's make_asset_files.py"]
    if range_grid:
        h += ["obj_info num_cols 4", "obj_info num_rows 1", "element range_grid 4",
              "property list uchar int vertex_indices"]
    h += [f"element vertex {len(pos)}", "property float x", "property float y", "property float z"]
    h += [f"property float {x}" for x in extra]
    if normals:
        h += ["property float nx", "property float ny", "property float nz"]
    if colors:
        h += ["property uchar red", "property uchar green", "property uchar blue"]
    if strips:
        flat = []
        for t in tri:
            flat += list(t) + [-1]
        h += ["element tristrips 1", "property list int int vertex_indices"]
    else:
        h += [f"element face {len(tri)}", f"property list uchar {face_type} vertex_indices"]
    h.append("end_header")
    out = ("\n".join(h) + "\n").encode()
    ic = {"int": "i", "uint": "I", "int32": "i", "uint32": "I", "ushort": "H"}[face_type]
    if fmt == "ascii":
        lines = []
        if range_grid:
            lines += ["1 0", "0", "1 1", "1 2"]
        for p in pos:
            v = list(p) + [0.5] * len(extra) + (list(p) if normals else []) + ([200, 100, 50] if colors else [])
            lines.append(" ".join(repr(float(x)) if i < 3 + len(extra) + 3 * normals else str(x) for i, x in enumerate(v)))
        if strips:
            lines.append(" ".join(map(str, [len(flat)] + flat)))
        else:
            lines += [" ".join(map(str, (3,) + t)) for t in tri]
        return out + ("\n".join(lines) + "\n").encode()
    b = bytearray(out)
    if range_grid:
        b += struct.pack(e + "Bi", 1, 0) + struct.pack("B", 0) + struct.pack(e + "Bi", 1, 1) + struct.pack(e + "Bi", 1, 2)
    for p in pos:
        b += struct.pack(e + "3f", *p)
        b += struct.pack(e + f"{len(extra)}f", *([0.5] * len(extra)))
        if normals:
            b += struct.pack(e + "3f", *p)
        if colors:
            b += bytes([200, 100, 50])
    if strips:
        b += struct.pack(e + "i", len(flat)) + struct.pack(e + f"{len(flat)}i", *flat)
    else:
        for t in tri:
            b += struct.pack(e + "B", 3) + struct.pack(e + "3" + ic, *t)
    return bytes(b)

def gltf(pos, tri, uri=None, normals=False, extra=None):
    buf = b"".join(struct.pack("<3f", *p) for p in pos)
    nb = len(buf)
    if normals:
        buf += b"".join(struct.pack("<3f", *p) for p in pos)
    ib = b"".join(struct.pack("<3I", *t) for t in tri)
    off = len(buf)
    buf += ib
    attrs = {"POSITION": 0}
    acc = [{"bufferView": 0, "componentType": 5126, "count": len(pos), "type": "VEC3",
            "min": [min(p[i] for p in pos) for i in range(3)], "max": [max(p[i] for p in pos) for i in range(3)]},
           {"bufferView": 1, "componentType": 5125, "count": 3 * len(tri), "type": "SCALAR"}]
    views = [{"buffer": 0, "byteOffset": 0, "byteLength": nb}, {"buffer": 0, "byteOffset": off, "byteLength": len(ib)}]
    if normals:
        attrs["NORMAL"] = 2
        acc.append({"bufferView": 2, "componentType": 5126, "count": len(pos), "type": "VEC3"})
        views.append({"buffer": 0, "byteOffset": nb, "byteLength": nb})
    doc = {"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
           "nodes": [{"children": [1], "rotation": [0, 0.3826834, 0, 0.9238795]}, {"mesh": 0, "translation": [0, 0.5, 0]}],
           "meshes": [{"primitives": [{"attributes": attrs, "indices": 1, "material": 0}]}],
           "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [0.9, 0.5, 0.2, 1], "metallicFactor": 0.2, "roughnessFactor": 0.4}}],
           "buffers": [{"byteLength": len(buf)}], "bufferViews": views, "accessors": acc}
    if uri == "data":
        doc["buffers"][0]["uri"] = "data:application/octet-stream;base64," + base64.b64encode(buf).decode()
    elif uri:
        doc["buffers"][0]["uri"] = uri
    if extra:
        extra(doc)
    return doc, buf

def glb(doc, buf):
    j = json.dumps(doc).encode()
    j += b" " * (-len(j) % 4)
    buf = buf + b"\0" * (-len(buf) % 4)
    return b"glTF" + struct.pack("<II", 2, 12 + 8 + len(j) + 8 + len(buf)) + struct.pack("<I", len(j)) + b"JSON" + j + struct.pack("<I", len(buf)) + b"BIN\0" + buf

def files():
    pos, tri = sphere(6)
    out = {}
    # PLY, as the Stanford repository's files are laid out.
    out["bunny_like_be.ply"] = ply(pos, tri, "binary_big_endian", extra=("confidence", "intensity"))
    out["dragon_like_le.ply"] = ply(pos, tri, "binary_little_endian", extra=("confidence",))
    out["ascii.ply"] = ply(pos, tri, "ascii")
    out["normals_colors.ply"] = ply(pos, tri, "binary_little_endian", normals=True, colors=True)
    out["ascii_normals.ply"] = ply(pos, tri, "ascii", normals=True)
    out["range_grid_ascii.ply"] = ply(pos, tri, "ascii", range_grid=True)
    out["range_grid_be.ply"] = ply(pos, tri, "binary_big_endian", range_grid=True)
    out["tristrips_be.ply"] = ply(pos, tri, "binary_big_endian", strips=True)
    out["uint_faces.ply"] = ply(pos, tri, "binary_little_endian", face_type="uint")
    good = out["bunny_like_be.ply"]
    out["bad_truncated.ply"] = good[:-7]
    out["bad_count_2e32.ply"] = good.replace(f"element vertex {len(pos)}".encode(), b"element vertex 4294967296")
    out["bad_face_count.ply"] = good.replace(f"element face {len(tri)}".encode(), b"element face 99999999999")
    out["bad_index.ply"] = ply(pos, [(0, 1, len(pos))] + tri, "ascii")
    out["bad_no_header_end.ply"] = b"ply\nformat ascii 1.0\nelement vertex 1\n"
    out["bad_type.ply"] = out["ascii.ply"].replace(b"property float y", b"property quad y")
    out["bad_nan.ply"] = out["ascii.ply"].replace(b"\n0.0 1.0 0.0\n", b"\nnan 1.0 0.0\n", 1)
    # glTF.
    d, b = gltf(pos, tri, uri="data")
    out["embedded.gltf"] = json.dumps(d).encode()
    d, b = gltf(pos, tri, uri="data", normals=True)
    out["embedded_normals.gltf"] = json.dumps(d).encode()
    d, b = gltf(pos, tri)
    out["binary.glb"] = glb(d, b)
    d, b = gltf(pos, tri, normals=True, extra=lambda d: d.update({
        "extensionsUsed": ["KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": [{"type": "directional", "intensity": 3}, {"type": "point", "intensity": 20, "color": [1, 0.8, 0.6]}]}},
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.7, "znear": 0.01, "aspectRatio": 1.5}}]}) or d["nodes"].extend([
            {"camera": 0, "translation": [0, 1, 5]}, {"extensions": {"KHR_lights_punctual": {"light": 0}}, "rotation": [-0.38, 0, 0, 0.92]},
            {"extensions": {"KHR_lights_punctual": {"light": 1}}, "translation": [2, 3, 2]}]) or d["scenes"][0]["nodes"].extend([2, 3, 4]))
    out["camera_lights.glb"] = glb(d, b)
    d, b = gltf(pos, tri, uri="sphere.bin")
    out["external.gltf"] = json.dumps(d).encode()
    out["sphere.bin"] = b
    d, b = gltf(pos, tri, uri="../outside.bin")
    out["bad_uri_parent.gltf"] = json.dumps(d).encode()
    d, b = gltf(pos, tri, uri="/etc/passwd")
    out["bad_uri_absolute.gltf"] = json.dumps(d).encode()
    d, b = gltf(pos, tri, uri="missing.bin")
    out["bad_uri_missing.gltf"] = json.dumps(d).encode()
    d, b = gltf(pos, tri)
    out["bad_truncated.glb"] = glb(d, b)[:-40]
    d, b = gltf(pos, tri, uri="data", extra=lambda d: d["accessors"][1].update({"count": 4294967295}))
    out["bad_count.gltf"] = json.dumps(d).encode()
    bad = [list(t) for t in tri]
    bad[0][2] = 99999
    d, b = gltf(pos, [tuple(t) for t in bad], uri="data")
    out["bad_index.gltf"] = json.dumps(d).encode()
    d, b = gltf(pos, tri, uri="data", extra=lambda d: d["nodes"][1].update({"children": [0]}))
    out["bad_cycle.gltf"] = json.dumps(d).encode()
    d, b = gltf(pos, tri, uri="data", extra=lambda d: d["meshes"][0]["primitives"][0]["attributes"].update({"POSITION": 7}))
    out["bad_dangling_accessor.gltf"] = json.dumps(d).encode()
    out["bad_json.gltf"] = b'{"asset": {"version": "2.0"}, "nodes": [}'
    return out

def main():
    here = os.path.dirname(os.path.abspath(__file__))
    fs = files()
    for name, data in fs.items():
        kind = "ply_loader" if name.endswith(".ply") else "gltf_loader" if name.endswith((".gltf", ".glb")) else None
        if kind:
            with open(os.path.join(here, "..", "fuzz", "corpus", kind, name), "wb") as f:
                f.write(data)
    if len(sys.argv) > 1:
        os.makedirs(sys.argv[1], exist_ok=True)
        for name, data in fs.items():
            with open(os.path.join(sys.argv[1], name), "wb") as f:
                f.write(data)

main()
