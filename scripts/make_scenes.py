#!/usr/bin/env python3
"""Generate chainlight's scene set (glTF 2.0) deterministically.

Usage:  python3 scripts/make_scenes.py [OUTPUT_DIR]      (default: <repo>/scenes)

Standard library only. Every scene is written as `<name>.gltf` (JSON) plus `<name>.bin` (the
binary buffer) next to it; base-colour textures are PNG files under `textures/`. Re-running
gives byte-identical files. Conventions (see docs/scenes.md):

* meters, +Y up, right-handed; all mesh geometry is baked into world space (mesh nodes carry
  no transform); the camera is a perspective camera node looking down its local -Z;
* diffuse  = pbrMetallicRoughness, metallic 0, roughness 1;
* metal    = metallic 1, roughness r (glTF roughness, alpha = r^2 in GGX terms);
* glass    = KHR_materials_transmission (1) + KHR_materials_ior, roughness 0, double-sided;
* emitters = emissiveFactor normalised to max component 1, times
  KHR_materials_emissive_strength = the radiance scale; base colour black; one-sided, they
  emit on the side of the geometric normal (counter-clockwise winding), which the per-vertex
  NORMALs agree with;
* thin lens / motion blur parameters live in the camera node's `extras`.
"""

import json
import math
import os
import struct
import sys

# ----------------------------------------------------------------------------------------------
# small vector helpers


def add(a, b):
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])


def sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def mul(a, s):
    return (a[0] * s, a[1] * s, a[2] * s)


def dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def length(a):
    return math.sqrt(dot(a, a))


def normalize(a):
    n = length(a)
    return (a[0] / n, a[1] / n, a[2] / n)


def rot_y(p, deg):
    """Rotate a point/vector about +Y by `deg` degrees (right-handed: +X towards -Z)."""
    c, s = math.cos(math.radians(deg)), math.sin(math.radians(deg))
    return (c * p[0] + s * p[2], p[1], -s * p[0] + c * p[2])


def f32(x):
    """Round to the nearest float32 (what ends up in the .bin), returned as a Python float."""
    return struct.unpack("<f", struct.pack("<f", x))[0]


def jf(x):
    """A float for the JSON: rounded to 7 significant digits (about float32 precision)."""
    v = float("%.7g" % x)
    return 0.0 if v == 0 else v


# ----------------------------------------------------------------------------------------------
# geometry


class Geom:
    """Triangles of one material, in world space, with per-vertex normals (and maybe UVs)."""

    def __init__(self, with_uv=False):
        self.pos = []
        self.nrm = []
        self.uv = [] if with_uv else None
        self.idx = []

    def vert(self, p, n, uv=None):
        self.pos.append(p)
        self.nrm.append(normalize(n))
        if self.uv is not None:
            self.uv.append(uv if uv is not None else (0.0, 0.0))
        return len(self.pos) - 1

    def tri(self, a, b, c):
        """Add a triangle, ordering it so its winding agrees with its vertex normals."""
        pa, pb, pc = self.pos[a], self.pos[b], self.pos[c]
        g = cross(sub(pb, pa), sub(pc, pa))
        navg = add(add(self.nrm[a], self.nrm[b]), self.nrm[c])
        if dot(g, navg) < 0:
            b, c = c, b
        self.idx.extend((a, b, c))

    def extend(self, other):
        base = len(self.pos)
        self.pos.extend(other.pos)
        self.nrm.extend(other.nrm)
        if self.uv is not None:
            self.uv.extend(other.uv if other.uv is not None else [(0.0, 0.0)] * len(other.pos))
        self.idx.extend(i + base for i in other.idx)
        return self

    def triangles(self):
        return len(self.idx) // 3


def quad(p0, p1, p2, p3, facing=None, uvs=None, with_uv=False):
    """A planar quad p0-p1-p2-p3 (in order around the boundary), flat normal.

    The normal is cross(p1-p0, p2-p0); if `facing` is given it is flipped to agree with it.
    """
    n = normalize(cross(sub(p1, p0), sub(p2, p0)))
    if facing is not None and dot(n, facing) < 0:
        n = mul(n, -1.0)
    g = Geom(with_uv=with_uv or uvs is not None)
    uvs = uvs or [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]
    v = [g.vert(p, n, uv) for p, uv in zip((p0, p1, p2, p3), uvs)]
    g.tri(v[0], v[1], v[2])
    g.tri(v[0], v[2], v[3])
    return g


def box(center, size, rot_deg=0.0, bottom=True):
    """An axis-aligned box (rotated about +Y around its centre), outward flat normals."""
    hx, hy, hz = size[0] / 2, size[1] / 2, size[2] / 2
    g = Geom()
    faces = [  # (normal, two tangent half-extents)
        ((1, 0, 0), (0, hy, 0), (0, 0, hz), hx),
        ((-1, 0, 0), (0, hy, 0), (0, 0, hz), hx),
        ((0, 1, 0), (hx, 0, 0), (0, 0, hz), hy),
        ((0, -1, 0), (hx, 0, 0), (0, 0, hz), hy),
        ((0, 0, 1), (hx, 0, 0), (0, hy, 0), hz),
        ((0, 0, -1), (hx, 0, 0), (0, hy, 0), hz),
    ]
    for n, t1, t2, d in faces:
        if not bottom and n == (0, -1, 0):
            continue
        c = mul(n, d)
        corners = [add(add(c, mul(t1, s1)), mul(t2, s2)) for s1, s2 in ((-1, -1), (1, -1), (1, 1), (-1, 1))]
        corners = [add(center, rot_y(p, rot_deg)) for p in corners]
        g.extend(quad(*corners, facing=rot_y(n, rot_deg)))
    return g


def uv_sphere(center, radius, nu=64, nv=32):
    """A UV sphere with smooth (analytic) per-vertex normals; poles are single vertices."""
    g = Geom()
    top = g.vert(add(center, (0.0, radius, 0.0)), (0.0, 1.0, 0.0))
    rings = []
    for j in range(1, nv):
        theta = math.pi * j / nv
        ring = []
        for i in range(nu):
            phi = 2.0 * math.pi * i / nu
            n = (math.sin(theta) * math.cos(phi), math.cos(theta), -math.sin(theta) * math.sin(phi))
            ring.append(g.vert(add(center, mul(n, radius)), n))
        rings.append(ring)
    bottom = g.vert(add(center, (0.0, -radius, 0.0)), (0.0, -1.0, 0.0))
    for i in range(nu):
        i2 = (i + 1) % nu
        g.tri(top, rings[0][i], rings[0][i2])
        g.tri(bottom, rings[-1][i2], rings[-1][i])
        for j in range(nv - 2):
            a, b = rings[j][i], rings[j][i2]
            c, d = rings[j + 1][i], rings[j + 1][i2]
            g.tri(a, c, d)
            g.tri(a, d, b)
    return g


def torus(center, major, minor, axis, ref, nu=48, nv=16):
    """A torus around `axis` (unit), `ref` a unit vector perpendicular to it; smooth normals."""
    e1 = normalize(ref)
    e2 = normalize(cross(axis, e1))
    g = Geom()
    grid = []
    for i in range(nu):
        u = 2.0 * math.pi * i / nu
        radial = add(mul(e1, math.cos(u)), mul(e2, math.sin(u)))
        row = []
        for j in range(nv):
            v = 2.0 * math.pi * j / nv
            n = add(mul(radial, math.cos(v)), mul(axis, math.sin(v)))
            p = add(center, add(mul(radial, major), mul(n, minor)))
            row.append(g.vert(p, n))
        grid.append(row)
    for i in range(nu):
        for j in range(nv):
            a, b = grid[i][j], grid[(i + 1) % nu][j]
            c, d = grid[i][(j + 1) % nv], grid[(i + 1) % nu][(j + 1) % nv]
            g.tri(a, b, d)
            g.tri(a, d, c)
    return g


def heightfield(x0, x1, z0, z1, n, height, grad, with_uv=False):
    """A regular n x n grid over [x0,x1]x[z0,z1] at y = height(x, z), normals from grad (+Y side)."""
    g = Geom(with_uv=with_uv)
    ids = []
    for j in range(n + 1):
        z = z0 + (z1 - z0) * j / n
        row = []
        for i in range(n + 1):
            x = x0 + (x1 - x0) * i / n
            dx, dz = grad(x, z)
            row.append(g.vert((x, height(x, z), z), (-dx, 1.0, -dz), (i / n, j / n)))
        ids.append(row)
    for j in range(n):
        for i in range(n):
            a, b, c, d = ids[j][i], ids[j][i + 1], ids[j + 1][i], ids[j + 1][i + 1]
            g.tri(a, c, d)
            g.tri(a, d, b)
    return g


# ----------------------------------------------------------------------------------------------
# PNG (uncompressed deflate blocks, so the bytes do not depend on a zlib version)


def _crc_table():
    table = []
    for n in range(256):
        c = n
        for _ in range(8):
            c = (0xEDB88320 ^ (c >> 1)) if c & 1 else (c >> 1)
        table.append(c)
    return table


_CRC = _crc_table()


def crc32(data):
    c = 0xFFFFFFFF
    for byte in data:
        c = _CRC[(c ^ byte) & 0xFF] ^ (c >> 8)
    return c ^ 0xFFFFFFFF


def adler32(data):
    a, b = 1, 0
    for byte in data:
        a = (a + byte) % 65521
        b = (b + a) % 65521
    return (b << 16) | a


def png_rgb(width, height, pixel):
    """Encode an 8-bit RGB PNG; pixel(x, y) -> (r, g, b) in 0..255 (sRGB-encoded)."""
    raw = bytearray()
    for y in range(height):
        raw.append(0)  # filter: none
        for x in range(width):
            raw.extend(pixel(x, y))
    raw = bytes(raw)
    z = bytearray(b"\x78\x01")
    pos = 0
    while True:
        block = raw[pos:pos + 65535]
        pos += len(block)
        final = pos >= len(raw)
        z.append(1 if final else 0)
        z.extend(struct.pack("<HH", len(block), len(block) ^ 0xFFFF))
        z.extend(block)
        if final:
            break
    z.extend(struct.pack(">I", adler32(raw)))

    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", crc32(kind + data))

    ihdr = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", bytes(z)) + chunk(b"IEND", b"")


def pool_tiles_png():
    """128x128: 8x8 pool tiles (white / pale blue checker) with 1-px grey-blue grout lines."""
    def px(x, y):
        if x % 16 == 0 or y % 16 == 0:
            return (110, 130, 140)
        return (235, 240, 240) if ((x // 16) + (y // 16)) % 2 == 0 else (120, 185, 215)
    return png_rgb(128, 128, px)


def checker_png():
    """128x128: 8x8 high-contrast checker (light grey / dark grey)."""
    def px(x, y):
        return (200, 200, 200) if ((x // 16) + (y // 16)) % 2 == 0 else (40, 40, 40)
    return png_rgb(128, 128, px)


TEXTURES = {"textures/pool-tiles.png": pool_tiles_png, "textures/checker.png": checker_png}

# ----------------------------------------------------------------------------------------------
# glTF writer


def look_at_quaternion(eye, target, up):
    """Rotation (x, y, z, w) taking the camera's local -Z to (target - eye), +Y towards up."""
    f = normalize(sub(target, eye))
    zc = mul(f, -1.0)
    xc = normalize(cross(up, zc))
    yc = cross(zc, xc)
    m00, m01, m02 = xc[0], yc[0], zc[0]
    m10, m11, m12 = xc[1], yc[1], zc[1]
    m20, m21, m22 = xc[2], yc[2], zc[2]
    tr = m00 + m11 + m22
    if tr > 0:
        s = math.sqrt(tr + 1.0) * 2
        w, x, y, z = 0.25 * s, (m21 - m12) / s, (m02 - m20) / s, (m10 - m01) / s
    elif m00 > m11 and m00 > m22:
        s = math.sqrt(1.0 + m00 - m11 - m22) * 2
        w, x, y, z = (m21 - m12) / s, 0.25 * s, (m01 + m10) / s, (m02 + m20) / s
    elif m11 > m22:
        s = math.sqrt(1.0 + m11 - m00 - m22) * 2
        w, x, y, z = (m02 - m20) / s, (m01 + m10) / s, 0.25 * s, (m12 + m21) / s
    else:
        s = math.sqrt(1.0 + m22 - m00 - m11) * 2
        w, x, y, z = (m10 - m01) / s, (m02 + m20) / s, (m12 + m21) / s, 0.25 * s
    q = (x, y, z, w)
    n = math.sqrt(sum(c * c for c in q))
    return [jf(c / n) for c in q]


class Scene:
    def __init__(self, name, description):
        self.name = name
        self.description = description
        self.bin = bytearray()
        self.buffer_views = []
        self.accessors = []
        self.materials = []
        self.meshes = []
        self.nodes = []
        self.textures = []
        self.images = []
        self.samplers = []
        self.cameras = []
        self.ext_used = set()
        self.material_ids = {}
        self.triangles = 0

    # -- materials ------------------------------------------------------------------------------
    def _material(self, name, mat):
        mat = dict(name=name, **mat)
        self.material_ids[name] = len(self.materials)
        self.materials.append(mat)
        return self.material_ids[name]

    def texture(self, uri):
        for i, img in enumerate(self.images):
            if img["uri"] == uri:
                return i
        if not self.samplers:
            # linear magnification, trilinear minification, repeat (UVs stay in [0, 1] anyway)
            self.samplers.append({"magFilter": 9729, "minFilter": 9987, "wrapS": 10497, "wrapT": 10497})
        self.images.append({"uri": uri, "mimeType": "image/png"})
        self.textures.append({"sampler": 0, "source": len(self.images) - 1})
        return len(self.textures) - 1

    def diffuse(self, name, rgb, texture=None):
        pbr = {"baseColorFactor": [jf(c) for c in rgb] + [1.0], "metallicFactor": 0.0, "roughnessFactor": 1.0}
        if texture is not None:
            pbr["baseColorTexture"] = {"index": self.texture(texture)}
        return self._material(name, {"pbrMetallicRoughness": pbr})

    def metal(self, name, rgb, roughness):
        pbr = {"baseColorFactor": [jf(c) for c in rgb] + [1.0], "metallicFactor": 1.0,
               "roughnessFactor": jf(roughness)}
        return self._material(name, {"pbrMetallicRoughness": pbr})

    def glass(self, name, ior, roughness=0.0):
        self.ext_used.update(("KHR_materials_transmission", "KHR_materials_ior"))
        pbr = {"baseColorFactor": [1.0, 1.0, 1.0, 1.0], "metallicFactor": 0.0, "roughnessFactor": jf(roughness)}
        return self._material(name, {
            "pbrMetallicRoughness": pbr,
            "doubleSided": True,
            "extensions": {
                "KHR_materials_transmission": {"transmissionFactor": 1.0},
                "KHR_materials_ior": {"ior": jf(ior)},
            },
        })

    def emitter(self, name, radiance):
        """A one-sided emitter of RGB radiance `radiance` (factor normalised, strength = max)."""
        self.ext_used.add("KHR_materials_emissive_strength")
        s = max(radiance)
        pbr = {"baseColorFactor": [0.0, 0.0, 0.0, 1.0], "metallicFactor": 0.0, "roughnessFactor": 1.0}
        return self._material(name, {
            "pbrMetallicRoughness": pbr,
            "emissiveFactor": [jf(c / s) for c in radiance],
            "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": jf(s)}},
        })

    # -- buffers --------------------------------------------------------------------------------
    def _view(self, data, target):
        while len(self.bin) % 4:
            self.bin.append(0)
        view = {"buffer": 0, "byteOffset": len(self.bin), "byteLength": len(data), "target": target}
        self.bin.extend(data)
        self.buffer_views.append(view)
        return len(self.buffer_views) - 1

    def _vec_accessor(self, values, kind, with_bounds):
        n = len(values[0])
        flat = [f32(c) for v in values for c in v]
        data = struct.pack("<%df" % len(flat), *flat)
        acc = {"bufferView": self._view(data, 34962), "componentType": 5126, "count": len(values), "type": kind}
        if with_bounds:
            acc["min"] = [min(flat[k::n]) for k in range(n)]
            acc["max"] = [max(flat[k::n]) for k in range(n)]
        self.accessors.append(acc)
        return len(self.accessors) - 1

    def _index_accessor(self, idx, vertex_count):
        if vertex_count <= 65535:
            data, ctype = struct.pack("<%dH" % len(idx), *idx), 5123
        else:
            data, ctype = struct.pack("<%dI" % len(idx), *idx), 5125
        acc = {"bufferView": self._view(data, 34963), "componentType": ctype, "count": len(idx), "type": "SCALAR"}
        self.accessors.append(acc)
        return len(self.accessors) - 1

    def mesh(self, name, geom, material):
        check_geom(self.name + "/" + name, geom)
        attrs = {
            "POSITION": self._vec_accessor(geom.pos, "VEC3", True),
            "NORMAL": self._vec_accessor(geom.nrm, "VEC3", False),
        }
        if geom.uv is not None:
            attrs["TEXCOORD_0"] = self._vec_accessor(geom.uv, "VEC2", False)
        prim = {"attributes": attrs, "indices": self._index_accessor(geom.idx, len(geom.pos)),
                "material": self.material_ids[material], "mode": 4}
        self.meshes.append({"name": name, "primitives": [prim]})
        self.nodes.append({"name": name, "mesh": len(self.meshes) - 1})
        self.triangles += geom.triangles()

    def camera(self, eye, target, yfov_deg, up=(0.0, 1.0, 0.0), extras=None, znear=0.01):
        self.cameras.append({"name": "camera", "type": "perspective",
                             "perspective": {"aspectRatio": 1.0, "yfov": jf(math.radians(yfov_deg)),
                                             "znear": znear}})
        node = {"name": "camera", "camera": 0, "rotation": look_at_quaternion(eye, target, up),
                "translation": [jf(c) for c in eye]}
        if extras:
            node["extras"] = extras
        self.nodes.append(node)

    # -- output ---------------------------------------------------------------------------------
    def write(self, out_dir):
        assert len(self.cameras) == 1, self.name
        assert self.triangles < 100_000, (self.name, self.triangles)
        while len(self.bin) % 4:
            self.bin.append(0)
        doc = {
            "asset": {"version": "2.0", "generator": "chainlight scripts/make_scenes.py",
                      "extras": {"description": self.description}},
        }
        if self.ext_used:
            doc["extensionsUsed"] = sorted(self.ext_used)
        doc["scene"] = 0
        doc["scenes"] = [{"name": self.name, "nodes": list(range(len(self.nodes)))}]
        doc["nodes"] = self.nodes
        doc["cameras"] = self.cameras
        doc["meshes"] = self.meshes
        doc["materials"] = self.materials
        if self.textures:
            doc["textures"] = self.textures
            doc["images"] = self.images
            doc["samplers"] = self.samplers
        doc["accessors"] = self.accessors
        doc["bufferViews"] = self.buffer_views
        doc["buffers"] = [{"uri": self.name + ".bin", "byteLength": len(self.bin)}]
        text = json.dumps(doc, indent=1, ensure_ascii=True) + "\n"
        write_if_changed(os.path.join(out_dir, self.name + ".gltf"), text.encode("ascii"))
        write_if_changed(os.path.join(out_dir, self.name + ".bin"), bytes(self.bin))
        return self.triangles


def write_if_changed(path, data):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    try:
        with open(path, "rb") as f:
            if f.read() == data:
                return
    except FileNotFoundError:
        pass
    with open(path, "wb") as f:
        f.write(data)


def check_geom(label, g):
    """Every triangle non-degenerate, its winding agreeing with all three vertex normals."""
    assert g.idx and len(g.idx) % 3 == 0, label
    for t in range(0, len(g.idx), 3):
        a, b, c = g.idx[t:t + 3]
        n = cross(sub(g.pos[b], g.pos[a]), sub(g.pos[c], g.pos[a]))
        area2 = length(n)
        assert area2 > 1e-10, (label, "degenerate triangle", t // 3)
        for v in (a, b, c):
            assert dot(n, g.nrm[v]) > 0, (label, "normal disagrees with winding", t // 3)


# ----------------------------------------------------------------------------------------------
# the scenes

CORNELL_EYE, CORNELL_TARGET, CORNELL_FOV = (0.0, 1.0, 3.5), (0.0, 1.0, 0.0), 39.0


def cornell_room(s):
    """Walls, light and camera exactly as in ../shared/notes/peer-cornell-glass.pbrt."""
    s.emitter("light", (17.0, 12.0, 4.0))
    s.diffuse("white", (0.73, 0.73, 0.73))
    s.diffuse("red", (0.65, 0.05, 0.05))
    s.diffuse("green", (0.12, 0.45, 0.15))
    # the peer's vertex order (its winding already faces into the room, light faces down)
    s.mesh("light", quad((-0.25, 1.98, -0.25), (0.25, 1.98, -0.25), (0.25, 1.98, 0.25), (-0.25, 1.98, 0.25),
                         facing=(0, -1, 0)), "light")
    s.mesh("floor", quad((-1, 0, -1), (-1, 0, 1), (1, 0, 1), (1, 0, -1), facing=(0, 1, 0)), "white")
    s.mesh("ceiling", quad((-1, 2, -1), (1, 2, -1), (1, 2, 1), (-1, 2, 1), facing=(0, -1, 0)), "white")
    s.mesh("back-wall", quad((-1, 0, -1), (1, 0, -1), (1, 2, -1), (-1, 2, -1), facing=(0, 0, 1)), "white")
    s.mesh("left-wall", quad((-1, 0, -1), (-1, 2, -1), (-1, 2, 1), (-1, 0, 1), facing=(1, 0, 0)), "red")
    s.mesh("right-wall", quad((1, 0, -1), (1, 0, 1), (1, 2, 1), (1, 2, -1), facing=(-1, 0, 0)), "green")
    s.camera(CORNELL_EYE, CORNELL_TARGET, CORNELL_FOV)


def scene_cornell():
    s = Scene("cornell", "Classic diffuse Cornell box: the peer-cornell-glass room with a short and a tall "
                         "rotated diffuse box instead of the two spheres.")
    cornell_room(s)
    # classic proportions (Cornell data scaled 555 -> 2): short block in front on the right,
    # tall block at the back on the left, each turned by ~17 degrees
    s.mesh("short-box", box((0.33, 0.3, 0.35), (0.6, 0.6, 0.6), rot_deg=-17.0, bottom=False), "white")
    s.mesh("tall-box", box((-0.35, 0.6, -0.3), (0.6, 1.2, 0.6), rot_deg=17.0, bottom=False), "white")
    return s


def scene_cornell_glass():
    s = Scene("cornell-glass", "Cornell box with a glass (ior 1.5) and a diffuse sphere, matching "
                               "../shared/notes/peer-cornell-glass.pbrt for side-by-side comparison.")
    cornell_room(s)
    s.glass("glass", 1.5)
    s.mesh("glass-sphere", uv_sphere((0.4, 0.35, 0.3), 0.35, 128, 64), "glass")
    s.mesh("diffuse-sphere", uv_sphere((-0.4, 0.35, -0.3), 0.35, 128, 64), "white")
    return s


def scene_caustic_pool():
    s = Scene("caustic-pool", "Caustics through a smooth, wavy water surface (ior 1.33) onto a tiled pool "
                              "floor, lit by a small bright area light.")
    s.emitter("light", (135.0, 128.0, 115.0))
    s.diffuse("pool-floor", (1.0, 1.0, 1.0), texture="textures/pool-tiles.png")
    s.diffuse("pool-wall", (0.45, 0.65, 0.75))
    s.diffuse("deck", (0.6, 0.58, 0.55))
    s.glass("water", 1.33)
    depth, rim = 0.6, 0.8  # water level, top of the pool walls (the deck)
    s.mesh("pool-floor", quad((-1, 0, -1), (-1, 0, 1), (1, 0, 1), (1, 0, -1), facing=(0, 1, 0),
                              uvs=[(0, 0), (0, 1), (1, 1), (1, 0)]), "pool-floor")
    walls = Geom()
    walls.extend(quad((-1, 0, -1), (1, 0, -1), (1, rim, -1), (-1, rim, -1), facing=(0, 0, 1)))
    walls.extend(quad((-1, 0, 1), (1, 0, 1), (1, rim, 1), (-1, rim, 1), facing=(0, 0, -1)))
    walls.extend(quad((-1, 0, -1), (-1, 0, 1), (-1, rim, 1), (-1, rim, -1), facing=(1, 0, 0)))
    walls.extend(quad((1, 0, -1), (1, 0, 1), (1, rim, 1), (1, rim, -1), facing=(-1, 0, 0)))
    s.mesh("pool-walls", walls, "pool-wall")
    deck = Geom()
    E = 4.0
    deck.extend(quad((-E, rim, -E), (E, rim, -E), (E, rim, -1), (-E, rim, -1), facing=(0, 1, 0)))
    deck.extend(quad((-E, rim, 1), (E, rim, 1), (E, rim, E), (-E, rim, E), facing=(0, 1, 0)))
    deck.extend(quad((-E, rim, -1), (-1, rim, -1), (-1, rim, 1), (-E, rim, 1), facing=(0, 1, 0)))
    deck.extend(quad((1, rim, -1), (E, rim, -1), (E, rim, 1), (1, rim, 1), facing=(0, 1, 0)))
    s.mesh("deck", deck, "deck")

    # a sum of travelling-wave sines; amplitude * k^2 ~ 5-7 puts the focal length of the
    # crests (~ n / ((n - 1) * curvature)) near the pool depth, so the caustic network is sharp
    waves = [  # (amplitude, wavelength, direction angle in degrees, phase)
        (0.012, 0.42, 20.0, 0.0),
        (0.008, 0.31, 115.0, 1.3),
        (0.006, 0.23, 65.0, 2.1),
        (0.004, 0.17, 160.0, 0.4),
    ]

    def height(x, z):
        h = depth
        for a, lam, ang, ph in waves:
            k = 2 * math.pi / lam
            dx, dz = math.cos(math.radians(ang)), math.sin(math.radians(ang))
            h += a * math.sin(k * (dx * x + dz * z) + ph)
        return h

    def grad(x, z):
        gx = gz = 0.0
        for a, lam, ang, ph in waves:
            k = 2 * math.pi / lam
            dx, dz = math.cos(math.radians(ang)), math.sin(math.radians(ang))
            c = a * k * math.cos(k * (dx * x + dz * z) + ph)
            gx += c * dx
            gz += c * dz
        return gx, gz

    s.mesh("water-surface", heightfield(-1, 1, -1, 1, 160, height, grad), "water")
    # small, bright light high above, slightly off-centre so the caustics are not symmetric
    y, h = 3.0, 0.15
    cx, cz = 0.4, -0.5
    s.mesh("light", quad((cx - h, y, cz - h), (cx + h, y, cz - h), (cx + h, y, cz + h), (cx - h, y, cz + h),
                         facing=(0, -1, 0)), "light")
    s.camera((0.0, 2.3, 2.4), (0.0, 0.15, -0.1), 45.0)
    return s


def scene_ajar_door():
    s = Scene("ajar-door", "Difficult visibility (Veach's ajar door): the light is in a second room; the "
                           "camera's room is lit only through the gap of a slightly open door.")
    s.emitter("light", (2500.0, 2250.0, 1875.0))
    s.diffuse("wall", (0.7, 0.7, 0.68))
    s.diffuse("floor", (0.45, 0.33, 0.22))
    s.diffuse("door", (0.55, 0.42, 0.3))
    s.diffuse("table", (0.5, 0.4, 0.3))
    s.metal("brass", (0.91, 0.78, 0.42), 0.2)
    s.diffuse("vase", (0.2, 0.35, 0.6))
    W, H, L = 2.0, 2.5, 4.0  # half width, height, half length of the two-room box
    t = 0.05  # half thickness of the dividing wall at z = 0
    d0, d1, dh = 0.3, 1.2, 2.0  # doorway x range and height
    # outer shell: faces point inwards
    s.mesh("floor", quad((-W, 0, -L), (W, 0, -L), (W, 0, L), (-W, 0, L), facing=(0, 1, 0)), "floor")
    shell = Geom()
    shell.extend(quad((-W, H, -L), (W, H, -L), (W, H, L), (-W, H, L), facing=(0, -1, 0)))
    shell.extend(quad((-W, 0, -L), (W, 0, -L), (W, H, -L), (-W, H, -L), facing=(0, 0, 1)))
    shell.extend(quad((-W, 0, L), (W, 0, L), (W, H, L), (-W, H, L), facing=(0, 0, -1)))
    shell.extend(quad((-W, 0, -L), (-W, 0, L), (-W, H, L), (-W, H, -L), facing=(1, 0, 0)))
    shell.extend(quad((W, 0, -L), (W, 0, L), (W, H, L), (W, H, -L), facing=(-1, 0, 0)))
    # dividing wall with a doorway: three boxes (left part, right part, lintel)
    shell.extend(box(((-W + d0) / 2, H / 2, 0), (d0 + W, H, 2 * t), bottom=False))
    shell.extend(box(((W + d1) / 2, H / 2, 0), (W - d1, H, 2 * t), bottom=False))
    shell.extend(box(((d0 + d1) / 2, (dh + H) / 2, 0), (d1 - d0, H - dh, 2 * t)))
    s.mesh("walls", shell, "wall")
    # the door: on the far side of the wall, larger than the doorway (it overlaps the wall by
    # 3 cm at the hinge and at the top, so no light leaks around it), hinged at x = d0 - 0.03,
    # opened by 12 degrees into room 2: the only opening is the slit at the free edge
    dw, dt, ang, hinge = d1 - d0 + 0.02, 0.04, 12.0, d0 - 0.03
    local = box((dw / 2, (dh + 0.03) / 2, -dt / 2), (dw, dh + 0.03, dt), bottom=True)
    door = Geom()
    for p, n in zip(local.pos, local.nrm):
        door.vert(add((hinge, 0.002, -t - 0.0005), rot_y(p, ang)), rot_y(n, ang))
    door.idx = list(local.idx)
    s.mesh("door", door, "door")
    # furniture in the camera's room (z > 0): a table with a brass sphere and a blue vase
    tab = Geom()
    tx, tz = 0.2, 1.6
    tab.extend(box((tx, 0.72, tz), (1.2, 0.05, 0.7)))
    for sx in (-0.53, 0.53):
        for sz in (-0.28, 0.28):
            tab.extend(box((tx + sx, 0.3475, tz + sz), (0.06, 0.695, 0.06), bottom=False))
    s.mesh("table", tab, "table")
    s.mesh("brass-sphere", uv_sphere((tx - 0.25, 0.745 + 0.15, tz), 0.15, 64, 32), "brass")
    s.mesh("vase", box((tx + 0.3, 0.745 + 0.175, tz - 0.1), (0.14, 0.35, 0.14), rot_deg=30.0, bottom=False), "vase")
    # the light: a ceiling panel in room 2, away from the door, facing down
    lx, lz, h = -1.0, -2.6, 0.3
    s.mesh("light", quad((lx - h, H - 0.01, lz - h), (lx + h, H - 0.01, lz - h), (lx + h, H - 0.01, lz + h),
                         (lx - h, H - 0.01, lz + h), facing=(0, -1, 0)), "light")
    s.camera((-1.6, 1.5, 3.8), (0.45, 0.85, 0.6), 60.0)
    return s


def scene_glossy_highlight():
    s = Scene("glossy-highlight", "A thin highlight on a low-roughness metal plate: the reflection of a long, "
                                  "thin, bright light strip seen at a grazing angle (Kelemen's failure case, "
                                  "DR paper Fig. 10).")
    s.emitter("strip", (30.0, 30.0, 28.8))
    s.emitter("fill", (3.0, 3.0, 3.0))
    s.metal("plate", (0.95, 0.93, 0.88), 0.08)
    s.diffuse("floor", (0.5, 0.5, 0.5))
    s.diffuse("backdrop", (0.65, 0.62, 0.58))
    s.diffuse("block", (0.7, 0.25, 0.1))
    E = 4.0
    s.mesh("floor", quad((-E, 0, -2.5), (E, 0, -2.5), (E, 0, E), (-E, 0, E), facing=(0, 1, 0)), "floor")
    s.mesh("backdrop", quad((-E, 0, -2.5), (E, 0, -2.5), (E, 3, -2.5), (-E, 3, -2.5), facing=(0, 0, 1)), "backdrop")
    s.mesh("plate", box((0.0, 0.005, 0.2), (1.6, 0.01, 1.4), bottom=False), "plate")
    s.mesh("block", box((-0.55, 0.1 + 0.01, -0.25), (0.2, 0.2, 0.2), rot_deg=25.0, bottom=True), "block")
    # the strip: 1.4 m x 1.2 cm, along x, tilted to face the point of the plate that mirrors it
    # into the camera
    eye = (0.0, 0.4, 2.0)
    sc = (0.0, 0.55, -1.3)
    mirror_eye = (eye[0], 2 * 0.01 - eye[1], eye[2])
    tt = (sc[1] - 0.01) / (sc[1] - mirror_eye[1])
    hit = add(sc, mul(sub(mirror_eye, sc), tt))  # the mirror point on the plate's top face
    nrm = normalize(sub(hit, sc))  # the strip faces the mirror point
    across = normalize(cross(nrm, (1.0, 0.0, 0.0)))
    hl, hw = 0.7, 0.006
    corners = [add(sc, add(mul((1.0, 0.0, 0.0), sx * hl), mul(across, sy * hw)))
               for sx, sy in ((-1, -1), (1, -1), (1, 1), (-1, 1))]
    s.mesh("strip", quad(*corners, facing=nrm), "strip")
    # a dim, large fill panel overhead behind the camera lights the backdrop; the plate cannot
    # mirror it into the camera (the camera sees the plate reflect the backdrop)
    s.mesh("fill", quad((-2, 3, 0.5), (2, 3, 0.5), (2, 3, 3.0), (-2, 3, 3.0), facing=(0, -1, 0)), "fill")
    s.camera(eye, (0.0, 0.08, -0.3), 35.0)
    return s


THIN_EYE = (0.0, 0.4, 2.0)
THIN_STRIP_CENTRE = (0.0, 0.55, -1.3)


def thin_strip(s, eye, sc):
    """The thin scenes' strip: 1.4 m x 2 mm of white diffuse along x centred at `sc`, tilted to
    face the point of a mirror 1 cm above the floor that reflects it into a camera at `eye`;
    returns that mirror point."""
    mirror_eye = (eye[0], 2 * 0.01 - eye[1], eye[2])
    tt = (sc[1] - 0.01) / (sc[1] - mirror_eye[1])
    hit = add(sc, mul(sub(mirror_eye, sc), tt))
    nrm = normalize(sub(hit, sc))
    across = normalize(cross(nrm, (1.0, 0.0, 0.0)))
    hl, hw = 0.7, 0.001
    corners = [add(sc, add(mul((1.0, 0.0, 0.0), sx * hl), mul(across, sy * hw)))
               for sx, sy in ((-1, -1), (1, -1), (1, 1), (-1, 1))]
    s.mesh("strip", quad(*corners, facing=nrm), "strip")
    return hit


def thin_lamp(s, sc):
    """The thin scenes' lamp: a 1.5 m x 8 cm panel below and in front of the strip at `sc`,
    facing up at it."""
    lc = add(sc, (0.0, -0.25, 0.25))
    ln = normalize(sub(sc, lc))
    lacross = normalize(cross(ln, (1.0, 0.0, 0.0)))
    ll, lw = 0.75, 0.04
    lcorners = [add(lc, add(mul((1.0, 0.0, 0.0), sx * ll), mul(lacross, sy * lw)))
                for sx, sy in ((-1, -1), (1, -1), (1, 1), (-1, 1))]
    s.mesh("lamp", quad(*lcorners, facing=ln), "lamp")


def scene_thin_highlight():
    s = Scene("thin-highlight", "A thin glossy highlight spanning many pixels, reached only by paths of two or more "
                                "bounces: a low-roughness metal plate seen at a grazing angle mirrors a long, thin, "
                                "brightly lit white strip (itself lit by a hidden emitter), over dimly and diffusely "
                                "lit surroundings (built to show the premise of the DR paper's Fig. 10).")
    s.emitter("lamp", (600.0, 590.0, 560.0))
    s.emitter("fill", (0.5, 0.5, 0.5))
    s.metal("plate", (0.95, 0.93, 0.88), 0.03)
    s.diffuse("strip", (0.9, 0.9, 0.9))
    s.diffuse("floor", (0.5, 0.5, 0.5))
    s.diffuse("backdrop", (0.01, 0.01, 0.01))
    s.diffuse("block", (0.2, 0.35, 0.6))
    E = 4.0
    s.mesh("floor", quad((-E, 0, -2.5), (E, 0, -2.5), (E, 0, E), (-E, 0, E), facing=(0, 1, 0)), "floor")
    s.mesh("backdrop", quad((-E, 0, -2.5), (E, 0, -2.5), (E, 3, -2.5), (-E, 3, -2.5), facing=(0, 0, 1)), "backdrop")
    s.mesh("plate", box((0.0, 0.005, 0.2), (1.6, 0.01, 1.4), bottom=False), "plate")
    s.mesh("block", box((0.55, 0.1 + 0.01, -0.35), (0.2, 0.2, 0.2), rot_deg=-20.0, bottom=True), "block")
    # the strip: 1.4 m x 2 mm of white diffuse, along x, tilted to face the point of the plate that
    # mirrors it into the camera; the camera sees it only in the plate (two bounces to a light)
    eye, sc = THIN_EYE, THIN_STRIP_CENTRE
    thin_strip(s, eye, sc)
    # the lamp: a 1.5 m x 8 cm panel below and in front of the strip, facing up at it, under
    # the strip-to-plate rays; the camera sees only its back, the plate not its face
    thin_lamp(s, sc)
    # a dim, large fill panel overhead behind the camera lights the surroundings diffusely
    s.mesh("fill", quad((-2, 3, 0.5), (2, 3, 0.5), (2, 3, 3.0), (-2, 3, 3.0), facing=(0, -1, 0)), "fill")
    s.camera(eye, (0.0, 0.08, -0.3), 35.0)
    return s


def scene_thin_bar():
    s = Scene("thin-bar", "A thin glossy highlight spanning many pixels on a narrow bar of metal, reached only by "
                          "paths of two or more bounces: the bar, seen at a grazing angle, mirrors a long, thin, "
                          "brightly lit white strip (itself lit by a hidden emitter) and nothing else bright "
                          "(built to show the premise of the DR paper's Fig. 10 without a broad glossy surface).")
    s.emitter("lamp", (600.0, 590.0, 560.0))
    s.emitter("fill", (0.5, 0.5, 0.5))
    s.metal("bar", (0.95, 0.93, 0.88), 0.03)
    s.diffuse("strip", (0.9, 0.9, 0.9))
    s.diffuse("floor", (0.2, 0.2, 0.2))
    s.diffuse("block", (0.2, 0.35, 0.6))
    E = 4.0
    s.mesh("floor", quad((-E, 0, -2.5), (E, 0, -2.5), (E, 0, E), (-E, 0, E), facing=(0, 1, 0)), "floor")
    s.mesh("block", box((0.55, 0.1 + 0.01, -0.35), (0.2, 0.2, 0.2), rot_deg=-20.0, bottom=True), "block")
    # the strip and lamp as in thin-highlight: 1.4 m x 2 mm of white diffuse along x, tilted to face
    # the point of the floor-level mirror that reflects it into the camera
    eye, sc = THIN_EYE, THIN_STRIP_CENTRE
    hit = thin_strip(s, eye, sc)
    # the bar: 1.6 m long, 20 cm deep and 1 cm tall, centred on the mirror point; around it the
    # camera sees the floor, and the bar mirrors the open sky behind the strip (black: no backdrop)
    # and the strip, so no broad glossy band surrounds the highlight
    s.mesh("bar", box((0.0, 0.005, hit[2]), (1.6, 0.01, 0.2), bottom=False), "bar")
    thin_lamp(s, sc)
    s.mesh("fill", quad((-2, 3, 0.5), (2, 3, 0.5), (2, 3, 3.0), (-2, 3, 3.0), facing=(0, -1, 0)), "fill")
    s.camera(eye, (0.0, 0.08, -0.3), 35.0)
    return s


def scene_glossy_diffuse():
    s = Scene("glossy-diffuse", "Glossy + diffuse mix (the regional-adaptive paper's Necklace situation): a "
                                "necklace of glossy metal beads and links on a diffuse floor, between coloured "
                                "diffuse walls, lit by an area light.")
    s.emitter("light", (12.0, 11.5, 10.5))
    s.diffuse("floor", (0.7, 0.7, 0.7))
    s.diffuse("blue-wall", (0.15, 0.25, 0.6))
    s.diffuse("red-wall", (0.6, 0.15, 0.1))
    s.diffuse("back-wall", (0.65, 0.62, 0.55))
    s.metal("gold", (1.0, 0.78, 0.34), 0.2)
    s.metal("silver", (0.95, 0.94, 0.92), 0.1)
    s.diffuse("cube", (0.9, 0.85, 0.2))
    E = 1.2
    s.mesh("floor", quad((-E, 0, -E), (E, 0, -E), (E, 0, E), (-E, 0, E), facing=(0, 1, 0)), "floor")
    s.mesh("back-wall", quad((-E, 0, -E), (E, 0, -E), (E, 1.5, -E), (-E, 1.5, -E), facing=(0, 0, 1)), "back-wall")
    s.mesh("left-wall", quad((-E, 0, -E), (-E, 0, E), (-E, 1.5, E), (-E, 1.5, -E), facing=(1, 0, 0)), "red-wall")
    s.mesh("right-wall", quad((E, 0, -E), (E, 0, E), (E, 1.5, E), (E, 1.5, -E), facing=(-1, 0, 0)), "blue-wall")
    s.mesh("cube", box((0.0, 0.09, -0.05), (0.18, 0.18, 0.18), rot_deg=35.0, bottom=False), "cube")
    # the necklace: a closed, wobbly curve on the floor, beads and links at equal arc length
    n_beads, rb, R, r = 16, 0.035, 0.026, 0.008

    def curve(u):
        rad = 0.36 * (1.0 + 0.12 * math.sin(2 * u) + 0.06 * math.cos(3 * u))
        return (rad * math.cos(u) * 1.15, 0.0, -rad * math.sin(u) * 0.85 + 0.05)

    samples = 4096
    pts = [curve(2 * math.pi * i / samples) for i in range(samples + 1)]
    cum = [0.0]
    for i in range(samples):
        cum.append(cum[-1] + length(sub(pts[i + 1], pts[i])))

    def at_length(sl):
        lo, hi = 0, samples
        while hi - lo > 1:
            mid = (lo + hi) // 2
            if cum[mid] <= sl:
                lo = mid
            else:
                hi = mid
        f = (sl - cum[lo]) / (cum[hi] - cum[lo])
        p = add(pts[lo], mul(sub(pts[hi], pts[lo]), f))
        tangent = normalize(sub(pts[hi], pts[lo]))
        return p, tangent

    total = cum[-1]
    beads, links = Geom(), Geom()
    for k in range(2 * n_beads):
        p, tangent = at_length(total * k / (2 * n_beads))
        if k % 2 == 0:
            beads.extend(uv_sphere((p[0], rb, p[2]), rb, 64, 32))
        else:
            # a link standing upright, its ring in the vertical plane containing the tangent
            axis = normalize(cross(tangent, (0.0, 1.0, 0.0)))
            links.extend(torus((p[0], R + r, p[2]), R, r, axis, tangent, 48, 16))
    s.mesh("beads", beads, "gold")
    s.mesh("links", links, "silver")
    lx, ly, lz, h = 0.35, 1.3, 0.25, 0.25
    s.mesh("light", quad((lx - h, ly, lz - h), (lx + h, ly, lz - h), (lx + h, ly, lz + h), (lx - h, ly, lz + h),
                         facing=(0, -1, 0)), "light")
    s.camera((0.0, 0.95, 1.15), (0.0, 0.02, -0.02), 38.0)
    return s


def scene_dof():
    eye, target = (0.3, 0.9, 3.4), (0.0, 0.4, -1.0)
    focus = length(sub(target, eye))
    s = Scene("dof", "Depth of field: objects at several depths on a checker floor, a thin lens focused on "
                     "the middle sphere, small emitters in the background for bokeh.")
    s.emitter("light", (10.0, 10.0, 9.4))
    s.emitter("bokeh", (40.0, 30.0, 12.0))
    s.diffuse("floor", (1.0, 1.0, 1.0), texture="textures/checker.png")
    s.diffuse("backdrop", (0.5, 0.5, 0.55))
    s.diffuse("red", (0.7, 0.1, 0.08))
    s.diffuse("white", (0.75, 0.75, 0.75))
    s.diffuse("blue", (0.1, 0.2, 0.7))
    s.metal("chrome", (0.9, 0.9, 0.9), 0.05)
    s.mesh("floor", quad((-4, 0, -7), (-4, 0, 1), (4, 0, 1), (4, 0, -7), facing=(0, 1, 0),
                         uvs=[(0, 0), (0, 1), (1, 1), (1, 0)]), "floor")
    s.mesh("backdrop", quad((-4, 0, -7), (4, 0, -7), (4, 4, -7), (-4, 4, -7), facing=(0, 0, 1)), "backdrop")
    s.mesh("near-sphere", uv_sphere((-0.2, 0.22, 1.4), 0.22, 64, 32), "red")
    s.mesh("middle-sphere", uv_sphere(target, 0.4, 96, 48), "white")
    s.mesh("middle-chrome", uv_sphere((0.75, 0.25, -0.9), 0.25, 64, 32), "chrome")
    s.mesh("far-box", box((0.95, 0.35, -4.2), (0.7, 0.7, 0.7), rot_deg=30.0, bottom=False), "blue")
    s.mesh("far-sphere", uv_sphere((-1.3, 0.5, -5.0), 0.5, 64, 32), "white")
    bokeh = Geom()
    for i in range(7):
        x = -2.4 + 0.8 * i
        y = 1.5 + 0.35 * math.sin(1.7 * i)
        bokeh.extend(uv_sphere((x, y, -6.6), 0.03, 24, 12))
    s.mesh("bokeh-lights", bokeh, "bokeh")
    h = 1.0
    s.mesh("light", quad((-h, 3.5, -1 - h), (h, 3.5, -1 - h), (h, 3.5, -1 + h), (-h, 3.5, -1 + h),
                         facing=(0, -1, 0)), "light")
    s.camera(eye, target, 32.0, extras={"aperture_radius": 0.08, "focus_distance": jf(focus)})
    return s


def scene_motion_blur():
    eye = (0.0, 1.0, 3.0)
    s = Scene("motion-blur", "Camera motion blur: the camera translates 0.15 m to the right during the shutter "
                             "over a scene of high-contrast vertical bars and boxes.")
    s.emitter("light", (15.0, 15.0, 14.0))
    s.diffuse("floor", (0.55, 0.55, 0.55))
    s.diffuse("white", (0.8, 0.8, 0.8))
    s.diffuse("black", (0.03, 0.03, 0.03))
    s.diffuse("orange", (0.8, 0.35, 0.05))
    s.diffuse("teal", (0.05, 0.45, 0.45))
    s.mesh("floor", quad((-3, 0, -2), (3, 0, -2), (3, 0, 4), (-3, 0, 4), facing=(0, 1, 0)), "floor")
    # back wall at z = -2 made of 12 vertical bars, alternating white and black
    white, black = Geom(), Geom()
    n, x0, x1 = 12, -3.0, 3.0
    for i in range(n):
        a, b = x0 + (x1 - x0) * i / n, x0 + (x1 - x0) * (i + 1) / n
        (white if i % 2 == 0 else black).extend(quad((a, 0, -2), (b, 0, -2), (b, 2.5, -2), (a, 2.5, -2),
                                                     facing=(0, 0, 1)))
    s.mesh("bars-white", white, "white")
    s.mesh("bars-black", black, "black")
    s.mesh("near-box", box((-0.55, 0.25, 1.0), (0.5, 0.5, 0.5), rot_deg=20.0, bottom=False), "orange")
    s.mesh("mid-box", box((0.6, 0.4, -0.5), (0.4, 0.8, 0.4), rot_deg=-15.0, bottom=False), "teal")
    s.mesh("sphere", uv_sphere((0.05, 0.3, 0.2), 0.3, 64, 32), "white")
    h = 0.6
    s.mesh("light", quad((-h, 2.5, 0.5 - h), (h, 2.5, 0.5 - h), (h, 2.5, 0.5 + h), (-h, 2.5, 0.5 + h),
                         facing=(0, -1, 0)), "light")
    end = add(eye, (0.15, 0.0, 0.0))
    s.camera(eye, (0.0, 0.8, 0.0), 40.0, extras={
        "shutter_open": 0.0, "shutter_close": 1.0, "motion_end_translation": [jf(c) for c in end]})
    return s


SCENES = [scene_cornell, scene_cornell_glass, scene_caustic_pool, scene_ajar_door, scene_glossy_highlight,
          scene_glossy_diffuse, scene_dof, scene_motion_blur, scene_thin_highlight,
          scene_thin_bar]


def main():
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    out_dir = sys.argv[1] if len(sys.argv) > 1 else os.path.join(root, "scenes")
    for uri, make in TEXTURES.items():
        write_if_changed(os.path.join(out_dir, uri), make())
    for make in SCENES:
        s = make()
        tris = s.write(out_dir)
        print("%-18s %7d triangles  %s" % (s.name + ".gltf", tris, os.path.join(out_dir, s.name + ".gltf")))


if __name__ == "__main__":
    main()
