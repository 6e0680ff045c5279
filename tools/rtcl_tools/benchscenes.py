"""The benchmark scene set (issue 11 item 7): the SPD scenes (spd.py), the paper's
random balls at 60 ... 20,000, models from Debian's assimp-testmodels, and the
million-triangle lake; and the writer that puts a Bench into a folder.

tools/genbench.py is the command line; docs/benchmark-scenes.md lists the set.
"""

import os

from . import files, genscene, ply, spd
from .spd import Bench

RANDOM_BALL_SERIES = (60, 200, 400, 2000, 20000)
ASSIMP_MODELS = "/usr/share/assimp/models"

# Three formats of one model (Wuson, 3732 triangles: y up, x in +-0.46, y in 0 ... 1.52,
# z in +-1.62 in assimp-testmodels 5.2.5) and a binary STL spider (1368 triangles,
# x in +-3.11, y in +-4, z in +-1.65), each with its own material.
ASSIMP_PLACEMENTS = (
    ("PLY/Wuson.ply", "glass", {"rotate": [0, 35, 0], "translate": [-1.6, 0.001, 0.6]}),
    ("OBJ/WusonOBJ.obj", "mirror", {"rotate": [0, -20, 0], "translate": [0, 0.001, 1.2]}),
    ("STL/Wuson.stl", "red", {"rotate": [0, -60, 0], "translate": [1.6, 0.001, 0.4]}),
    ("STL/Spider_binary.stl", "mirror",
     {"scale": 0.3, "rotate": [-90, 0, 0], "translate": [0.2, 0.495, -1.3]}),
)
ASSIMP_MATERIALS = {
    "glass": {"color": [1, 1, 1], "ambient": 0.1, "diffuse": 0.05, "specular": 0.8,
              "shininess": 200, "reflect": 0.1, "transmit": 0.85, "ior": 1.5},
    "mirror": {"color": [0.9, 0.9, 0.95], "diffuse": 0.1, "specular": 0.6, "shininess": 120,
               "reflect": 0.8},
    "red": {"color": [0.8, 0.15, 0.1], "diffuse": 0.8, "specular": 0.3, "shininess": 40},
    "floor": {"color": [0.9, 0.9, 0.85], "diffuse": 0.8, "specular": 0.1, "reflect": 0.2},
}


class MissingModels(FileNotFoundError):
    """assimp-testmodels is not where the scene needs it."""


def random_balls(n, seed=genscene.DEFAULT_SEED, image=(2000, 2000), depth=5):
    """The 2009 paper's scene with n balls (tools/genscene.py's, same seed, same bytes)."""
    return Bench("random-balls-%d" % n, genscene.build_scene(n, seed, image, depth))


def assimp_models(models=ASSIMP_MODELS, image=(800, 600), depth=5):
    """Models of assimp-testmodels on a checkered floor, in glass, mirror and red; the
    files are referenced by absolute path where the package installed them."""
    paths = [os.path.join(os.path.abspath(models), name) for name, _, _ in ASSIMP_PLACEMENTS]
    for path in paths:
        if not os.path.isfile(path):
            raise MissingModels("%s is missing: install Debian's assimp-testmodels, "
                                "or give the folder of its models" % path)
    scene = {"format": "rtcl-scene", "version": 2,
             "image": {"width": image[0], "height": image[1]},
             "camera": {"eye": [0, 3.2, -6.5], "look_at": [0, 0.6, 0], "fov": 40},
             "background": [0.12, 0.16, 0.24], "ambient": [0.1, 0.1, 0.1],
             "max_depth": depth, "materials": ASSIMP_MATERIALS,
             "lights": [{"position": [-8, 12, -10], "color": [0.8, 0.8, 0.8]},
                        {"position": [10, 8, -4], "color": [0.4, 0.4, 0.45]}],
             "planes": [{"point": [0, 0, 0], "normal": [0, 1, 0], "material": "floor",
                         "checker": {"size": 1, "color": [0.2, 0.2, 0.2]}}],
             "meshes": [dict({"file": path, "material": material}, **placement)
                        for path, (_, material, placement) in zip(paths, ASSIMP_PLACEMENTS)]}
    return Bench("assimp-models", scene)


def write(bench, folder):
    """Writes the bench's meshes, then its scene (so that the scene never names a file
    not yet there), into folder; returns the scene's path."""
    for name, (vertices, faces) in bench.meshes.items():
        ply.write(os.path.join(folder, name), vertices, faces,
                  comment="rtcl tools/genbench.py " + bench.name)
    path = os.path.join(folder, bench.name + ".json")
    files.write_text(path, genscene.to_json(bench.scene))
    return path


def standard_set(models=ASSIMP_MODELS, with_lake=True):
    """Yields every Bench of `make bench-scenes`, one at a time (the lake is large)."""
    for size in (3, 4):
        yield spd.balls(size)
    for size in (4, 6):
        yield spd.tetra(size)
    for size in (4, 6, 8):
        yield spd.mount(size)
    for n in RANDOM_BALL_SERIES:
        yield random_balls(n)
    yield assimp_models(models)
    if with_lake:
        yield spd.lake(10)
