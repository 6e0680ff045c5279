#!/usr/bin/env python3
"""Writes the textured models of scenes/studio.json into scenes/models/ (or the
folder given): crate.obj with crate.mtl and crate.png, a box of planks (a base
colour texture, OBJ/MTL), and trellis.gltf, a trellis panel whose texture's alpha
cuts out the gaps between its laths (glTF alphaMode MASK, the PNG embedded).
Deterministic, standard library only: the PNGs are written with zlib.

    /usr/bin/python3 tools/build/studio_models.py [FOLDER]
"""
import base64
import json
import pathlib
import struct
import sys
import zlib


def png(rows):
    """A PNG of RGBA rows of 8 bits, top row first."""
    h, w = len(rows), len(rows[0])
    raw = b"".join(b"\0" + bytes(c for p in row for c in p) for row in rows)

    def chunk(kind, data):
        return (struct.pack(">I", len(data)) + kind + data
                + struct.pack(">I", zlib.crc32(kind + data) & 0xffffffff))
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 6, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))


def planks(size=16):
    """Four planks across, each its own brown, a dark seam between them and a
    few darker knots; opaque."""
    browns = [(150, 96, 52), (170, 112, 62), (138, 88, 46), (160, 104, 58)]
    rows = []
    for y in range(size):
        row = []
        for x in range(size):
            r, g, b = browns[y // 4]
            if y % 4 == 3:
                r, g, b = r // 3, g // 3, b // 3  # the seam
            elif (x * 7 + y * 3) % 11 == 0:
                r, g, b = r * 3 // 4, g * 3 // 4, b * 3 // 4  # grain
            row.append((r, g, b, 255))
        rows.append(row)
    return rows


def trellis(size=16):
    """Two laths crossing diagonally, green-painted; alpha 0 in the gaps."""
    rows = []
    for y in range(size):
        row = []
        for x in range(size):
            lath = (x - y) % size < 3 or (x + y) % size < 3
            row.append((60, 120, 50, 255) if lath else (0, 0, 0, 0))
        rows.append(row)
    return rows


CRATE_OBJ = """# A unit box of planks, its faces mapped to the whole texture (tools/build/studio_models.py)
mtllib crate.mtl
v -0.5 -0.5 -0.5
v 0.5 -0.5 -0.5
v 0.5 0.5 -0.5
v -0.5 0.5 -0.5
v -0.5 -0.5 0.5
v 0.5 -0.5 0.5
v 0.5 0.5 0.5
v -0.5 0.5 0.5
vt 0 0
vt 1 0
vt 1 1
vt 0 1
usemtl planks
f 1/1 4/4 3/3 2/2
f 5/1 6/2 7/3 8/4
f 1/1 5/2 8/3 4/4
f 2/1 3/4 7/3 6/2
f 4/1 8/2 7/3 3/4
f 1/1 2/2 6/3 5/4
"""

CRATE_MTL = """newmtl planks
Kd 1 1 1
Ka 1 1 1
Ks 0.1 0.1 0.1
Ns 20
map_Kd crate.png
"""


def trellis_gltf(texture):
    """A 1 × 1 panel in the xy-plane (normal +z), its coordinates 0 ... 2: the
    texture twice across each way (sampler REPEAT)."""
    pos = struct.pack("<12f", -0.5, 0, 0, 0.5, 0, 0, 0.5, 1, 0, -0.5, 1, 0)
    uv = struct.pack("<8f", 0, 2, 2, 2, 2, 0, 0, 0)
    idx = struct.pack("<6H", 0, 1, 2, 0, 2, 3)
    buf = pos + uv + idx
    doc = {
        "asset": {"version": "2.0", "generator": "rtcl tools/build/studio_models.py"},
        "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1},
                                    "indices": 2, "material": 0}]}],
        "materials": [{"name": "lath",
                       "pbrMetallicRoughness": {"baseColorTexture": {"index": 0},
                                                "metallicFactor": 0, "roughnessFactor": 0.7},
                       "alphaMode": "MASK", "alphaCutoff": 0.5, "doubleSided": True}],
        "buffers": [{"byteLength": len(buf), "uri": "data:application/octet-stream;base64,"
                     + base64.b64encode(buf).decode()}],
        "bufferViews": [{"buffer": 0, "byteLength": 48},
                        {"buffer": 0, "byteOffset": 48, "byteLength": 32},
                        {"buffer": 0, "byteOffset": 80, "byteLength": 12}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
                       "min": [-0.5, 0, 0], "max": [0.5, 1, 0]},
                      {"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC2"},
                      {"bufferView": 2, "componentType": 5123, "count": 6, "type": "SCALAR"}],
        "samplers": [{"wrapS": 10497, "wrapT": 10497}],
        "textures": [{"source": 0, "sampler": 0}],
        "images": [{"uri": "data:image/png;base64," + base64.b64encode(texture).decode()}],
    }
    return json.dumps(doc, indent=1) + "\n"


def main():
    folder = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else
                          pathlib.Path(__file__).resolve().parents[2] / "scenes" / "models")
    (folder / "crate.png").write_bytes(png(planks()))
    (folder / "crate.obj").write_text(CRATE_OBJ)
    (folder / "crate.mtl").write_text(CRATE_MTL)
    (folder / "trellis.gltf").write_text(trellis_gltf(png(trellis())))


if __name__ == "__main__":
    main()
