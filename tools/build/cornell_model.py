#!/usr/bin/env python3
"""Writes scenes/models/cornell/room.obj, boxes.obj and cornell.mtl: the
geometry and colours of Mitsuba 3's Cornell box (`mi.cornell_box()`), exported triangle for
triangle, so that rtcl and Mitsuba render the same box (docs/oracle.md).

Each of Mitsuba's shapes becomes an OBJ object whose `usemtl` names its
material, the walls and the light in room.obj, the two boxes in boxes.obj (the
test scenes put spheres in the room instead): `white` (floor, ceiling, back
wall, the two boxes), `red` (the wall at x = -1), `green` (x = +1) and `light`
(the emissive quad under the ceiling, white, with Mitsuba's radiance as `Ke`).
A rectangle is Mitsuba's [-1, 1]^2 square at z = 0 with normal +z, placed by
its `to_world`; a cube is the mesh Mitsuba builds for it (12 triangles, 24
vertices), read back through `mi.traverse`. The vertex order keeps Mitsuba's faces, so each face's
(v1 - v0) x (v2 - v0) points where Mitsuba's normal does: into the box for the
walls, down for the light, out of the two boxes.

    python3 tools/build/cornell_model.py      # needs `pip install mitsuba`

Mitsuba's version goes into the header of both files; the output is
deterministic (coordinates printed with 6 significant digits, which also rounds
the float error of Mitsuba's rotations away: -0.9999999 is written -1).
"""
import pathlib

import mitsuba as mi

mi.set_variant("scalar_rgb")

ROOT = pathlib.Path(__file__).resolve().parents[2]
OUT = ROOT / "scenes" / "models" / "cornell"

# Mitsuba's shape ids in mi.cornell_box(), in the order written.
FILES = {"room.obj": ("floor", "ceiling", "back", "green-wall", "red-wall", "light"),
         "boxes.obj": ("small-box", "large-box")}
SQUARE = ((-1, -1, 0), (1, -1, 0), (1, 1, 0), (-1, 1, 0))


def number(x):
    text = f"{x:.6g}"
    return "0" if text == "-0" else text


def shape_mesh(entry):
    """(vertices, faces) of one of mi.cornell_box()'s shapes, in world space."""
    to_world = entry["to_world"]
    if entry["type"] == "rectangle":
        return [list(to_world @ mi.ScalarPoint3f(*p)) for p in SQUARE], [(0, 1, 2, 3)]
    assert entry["type"] == "cube", entry["type"]
    params = mi.traverse(mi.load_dict({"type": "cube", "to_world": to_world}))
    flat = list(params["vertex_positions"])
    faces = list(params["faces"])
    vertices = [flat[i:i + 3] for i in range(0, len(flat), 3)]
    return vertices, [tuple(faces[i:i + 3]) for i in range(0, len(faces), 3)]


def material_of(box, name):
    if name == "light":
        return "light"
    return box[name]["bsdf"]["id"]


def main():
    box = mi.cornell_box()
    OUT.mkdir(parents=True, exist_ok=True)
    header = (f"# Mitsuba {mi.__version__}'s mi.cornell_box(), written by "
              "tools/build/cornell_model.py (docs/oracle.md)\n")
    for file, shapes in FILES.items():
        lines = [header, "mtllib cornell.mtl\n"]
        base = 1
        for name in shapes:
            vertices, faces = shape_mesh(box[name])
            lines.append(f"o {name}\nusemtl {material_of(box, name)}\n")
            lines += [f"v {' '.join(number(c) for c in v)}\n" for v in vertices]
            lines += [f"f {' '.join(str(base + i) for i in face)}\n" for face in faces]
            base += len(vertices)
        (OUT / file).write_text("".join(lines))

    def rgb(bsdf_id):
        return " ".join(number(c) for c in box[bsdf_id]["reflectance"]["value"])

    radiance = box["light"]["emitter"]["radiance"]["value"]
    mtl = [header]
    for name in ("white", "red", "green"):
        mtl.append(f"newmtl {name}\nKd {rgb(name)}\nKs 0 0 0\nillum 1\n\n")
    mtl.append(f"newmtl light\nKd {rgb(box['light']['bsdf']['id'])}\nKs 0 0 0\n"
               f"Ke {' '.join(number(c) for c in radiance)}\nillum 1\n")
    (OUT / "cornell.mtl").write_text("".join(mtl))


if __name__ == "__main__":
    main()
