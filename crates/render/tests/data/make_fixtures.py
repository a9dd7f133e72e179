#!/usr/bin/env python3
"""Writes the tiny glTF fixtures of the render crate's scene-loading and fuzz tests.

tiny.gltf (+ tiny.bin, checker.png): external buffer and image; tiny-embedded.gltf: the same
scene with data URIs; tiny.glb: binary container with the image in a buffer view.
The scene: a textured floor quad and an emissive quad (one mesh, two primitives) under a
translated parent node, a transmissive triangle (KHR_materials_transmission + ior) in a rotated
child node, and a perspective camera. Run from this directory; output is deterministic.
"""
import base64
import json
import struct
import zlib


def png_rgb(w, h, pixels):
    raw = b''.join(b'\x00' + bytes(sum(pixels[y * w:(y + 1) * w], ())) for y in range(h))

    def chunk(t, d):
        c = struct.pack('>I', len(d)) + t + d
        return c + struct.pack('>I', zlib.crc32(t + d) & 0xffffffff)
    return (b'\x89PNG\r\n\x1a\n' + chunk(b'IHDR', struct.pack('>IIBBBBB', w, h, 8, 2, 0, 0, 0))
            + chunk(b'IDAT', zlib.compress(raw)) + chunk(b'IEND', b''))


png = png_rgb(2, 2, [(255, 255, 255), (40, 40, 40), (40, 40, 40), (255, 255, 255)])

floor_p = [(-1, 0, -1), (-1, 0, 1), (1, 0, 1), (1, 0, -1)]
floor_n = [(0, 1, 0)] * 4
floor_uv = [(0, 0), (0, 1), (1, 1), (1, 0)]
light_p = [(-0.25, 1.5, -0.25), (0.25, 1.5, -0.25), (0.25, 1.5, 0.25), (-0.25, 1.5, 0.25)]
light_n = [(0, -1, 0)] * 4
light_uv = [(0, 0)] * 4
tri_p = [(-0.5, 0.2, 0), (0.5, 0.2, 0), (0, 0.8, 0)]
tri_n = [(0, 0, 1)] * 3
tri_uv = [(0, 0)] * 3
quad_idx = [0, 1, 2, 0, 2, 3]
tri_idx = [0, 1, 2]

buf = b''
views = []
accessors = []


def add_view(data, target=None):
    global buf
    while len(buf) % 4:
        buf += b'\x00'
    off = len(buf)
    buf += data
    v = {"buffer": 0, "byteOffset": off, "byteLength": len(data)}
    if target:
        v["target"] = target
    views.append(v)
    return len(views) - 1


def add_acc(vals, comp, typ, fmt, minmax=False, target=34962):
    data = b''.join(struct.pack('<' + fmt * len(v if isinstance(v, tuple) else (v,)),
                                *(v if isinstance(v, tuple) else (v,))) for v in vals)
    view = add_view(data, target)
    a = {"bufferView": view, "componentType": comp, "count": len(vals), "type": typ}
    if minmax:
        a["min"] = [min(v[i] for v in vals) for i in range(3)]
        a["max"] = [max(v[i] for v in vals) for i in range(3)]
    accessors.append(a)
    return len(accessors) - 1


prims = []
for (p, n, uv, idx, mat) in [(floor_p, floor_n, floor_uv, quad_idx, 0),
                             (light_p, light_n, light_uv, quad_idx, 1),
                             (tri_p, tri_n, tri_uv, tri_idx, 2)]:
    P = add_acc([tuple(map(float, v)) for v in p], 5126, "VEC3", 'f', True)
    N = add_acc([tuple(map(float, v)) for v in n], 5126, "VEC3", 'f')
    T = add_acc([tuple(map(float, v)) for v in uv], 5126, "VEC2", 'f')
    I = add_acc(idx, 5123, "SCALAR", 'H', target=34963)
    prims.append({"attributes": {"POSITION": P, "NORMAL": N, "TEXCOORD_0": T}, "indices": I,
                  "material": mat, "mode": 4})
while len(buf) % 4:
    buf += b'\x00'


def doc(buffer_uri, image_uri):
    return {
        "asset": {"version": "2.0", "generator": "chainlight render tests"},
        "extensionsUsed": ["KHR_materials_emissive_strength", "KHR_materials_transmission",
                           "KHR_materials_ior"],
        "scene": 0,
        "scenes": [{"nodes": [0, 3]}],
        "nodes": [
            {"name": "group", "translation": [0.0, -0.5, 0.0], "children": [1, 2]},
            {"name": "geometry", "mesh": 0},
            {"name": "glass", "mesh": 1, "rotation": [0.0, 0.38268343, 0.0, 0.92387953]},
            {"name": "camera", "camera": 0, "translation": [0.0, 0.5, 3.0]},
        ],
        "cameras": [{"type": "perspective",
                     "perspective": {"yfov": 0.8, "aspectRatio": 1.5, "znear": 0.01}}],
        "meshes": [{"name": "floor+light", "primitives": prims[:2]},
                   {"name": "glass", "primitives": prims[2:]}],
        "materials": [
            {"name": "floor", "pbrMetallicRoughness": {
                "baseColorFactor": [0.8, 0.8, 0.8, 1.0], "metallicFactor": 0.0,
                "roughnessFactor": 1.0, "baseColorTexture": {"index": 0}}},
            {"name": "light", "pbrMetallicRoughness": {
                "baseColorFactor": [0.0, 0.0, 0.0, 1.0], "metallicFactor": 0.0},
             "emissiveFactor": [1.0, 0.9, 0.8],
             "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 10.0}}},
            {"name": "glass", "pbrMetallicRoughness": {
                "baseColorFactor": [1.0, 1.0, 1.0, 1.0], "metallicFactor": 0.0,
                "roughnessFactor": 0.0},
             "extensions": {"KHR_materials_transmission": {"transmissionFactor": 1.0},
                            "KHR_materials_ior": {"ior": 1.5}}},
        ],
        "textures": [{"sampler": 0, "source": 0}],
        "samplers": [{"magFilter": 9728, "wrapS": 10497, "wrapT": 33071}],
        "images": [image_uri],
        "buffers": [dict(byteLength=len(buf), **({"uri": buffer_uri} if buffer_uri else {}))],
        "bufferViews": views,
        "accessors": accessors,
    }


open('tiny.bin', 'wb').write(buf)
open('checker.png', 'wb').write(png)
open('tiny.gltf', 'w').write(
    json.dumps(doc("tiny.bin", {"uri": "checker.png", "mimeType": "image/png"}), indent=1))
open('tiny-embedded.gltf', 'w').write(json.dumps(
    doc("data:application/octet-stream;base64," + base64.b64encode(buf).decode(),
        {"uri": "data:image/png;base64," + base64.b64encode(png).decode(),
         "mimeType": "image/png"}), separators=(',', ':')))
buf2 = buf + png
while len(buf2) % 4:
    buf2 += b'\x00'
d = doc(None, None)
views.append({"buffer": 0, "byteOffset": len(buf), "byteLength": len(png)})
d["bufferViews"] = views
d["images"] = [{"bufferView": len(views) - 1, "mimeType": "image/png"}]
d["buffers"] = [{"byteLength": len(buf2)}]
j = json.dumps(d, separators=(',', ':')).encode()
while len(j) % 4:
    j += b' '
glb = (struct.pack('<4sII', b'glTF', 2, 12 + 8 + len(j) + 8 + len(buf2))
       + struct.pack('<I4s', len(j), b'JSON') + j + struct.pack('<I4s', len(buf2), b'BIN\x00') + buf2)
open('tiny.glb', 'wb').write(glb)
