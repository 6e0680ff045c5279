#!/usr/bin/env python3
"""Writes the textured floor of scenes/materials_path.json into scenes/models/
(or the folder given): tiles.obj, a 12 x 12 square at y = 0 whose texture
coordinates repeat tiles.png 4 times each way, tiles.mtl (Kd 1, map_Kd
tiles.png: an opaque diffuse material without reflection, which the path
integrator renders as the diffuse lobe of the texture's colour) and
tiles.png, 32 x 32 texels: 2 x 2 tiles of terracotta and slate with light
grout. Deterministic, standard library only (studio_models.py's PNG writer).

    /usr/bin/python3 tools/build/materials_models.py [FOLDER]
"""
import pathlib
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
from studio_models import png  # noqa: E402


def tiles(size=32):
    """2 x 2 tiles, terracotta and slate in a checker, grout 2 texels wide."""
    colours = [(178, 86, 52), (72, 84, 96)]
    rows = []
    for y in range(size):
        row = []
        for x in range(size):
            half = size // 2
            if x % half < 2 or y % half < 2:
                row.append((214, 206, 190, 255))  # the grout
            else:
                r, g, b = colours[(x // half + y // half) % 2]
                shade = 12 * (((x * 7 + y * 3) % 5) - 2)  # a little mottling
                row.append((r + shade, g + shade, b + shade, 255))
        rows.append(row)
    return rows


OBJ = """# A 12 x 12 floor at y = 0, facing +y, its texture repeated 4 times each way
# (tools/build/materials_models.py)
mtllib tiles.mtl
v -6 0 6
v 6 0 6
v 6 0 -6
v -6 0 -6
vt 0 0
vt 4 0
vt 4 4
vt 0 4
usemtl tiles
f 1/1 2/2 3/3 4/4
"""

MTL = """newmtl tiles
Kd 1 1 1
illum 1
map_Kd tiles.png
"""


def main(argv):
    folder = pathlib.Path(argv[1] if len(argv) > 1 else "scenes/models")
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "tiles.png").write_bytes(png(tiles()))
    (folder / "tiles.obj").write_text(OBJ)
    (folder / "tiles.mtl").write_text(MTL)


if __name__ == "__main__":
    main(sys.argv)
