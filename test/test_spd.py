"""Tests of the benchmark scenes: tools/genbench.py, rtcl_tools.spd (Haines' SPD
balls, tetra, mount), rtcl_tools.benchscenes and rtcl_tools.ply."""
import itertools
import os
import pathlib
import subprocess
import sys

import numpy as np
import pytest

ROOT = pathlib.Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tools"))
from rtcl_tools import benchscenes, genscene, ply, scene, spd  # noqa: E402

GENBENCH = ROOT / "tools" / "genbench.py"
RTCL = os.environ.get("RTCL", str(ROOT / "rtcl"))


def genbench(*args, check=True):
    return subprocess.run([sys.executable, str(GENBENCH), *map(str, args)],
                          capture_output=True, text=True, check=check)


needs_models = pytest.mark.skipif(
    not os.path.isdir(benchscenes.ASSIMP_MODELS), reason="assimp-testmodels not installed")


def flake_count(size):
    return sum(9 ** k for k in range(size + 1))


# ---- balls: the sphereflake ---------------------------------------------------------------

@pytest.mark.parametrize("size, count", [(1, 10), (2, 91), (3, 820), (4, 7381)])
def test_sphereflake_has_the_published_sphere_count(size, count):
    assert flake_count(size) == count
    bench = spd.balls(size)
    assert len(bench.scene["spheres"]) == count
    assert len(bench.scene["planes"]) == 1 and bench.scene["version"] == 1
    scene.validate(bench.scene)


def parents(centers, radii):
    """Each sphere's parent, found from the output order alone: balls.c writes a sphere
    before its children, so the parent is the latest earlier sphere that is larger."""
    stack, out = [], [None]
    for i, r in enumerate(radii):
        while stack and radii[stack[-1]] <= r * (1 + 1e-9):
            stack.pop()
        if i:
            out.append(stack[-1])
        stack.append(i)
    return out


def test_every_child_touches_its_parent_at_a_third_of_its_radius():
    centers, radii = spd.sphereflake_spheres(3)
    owner = parents(centers, radii)
    children = {}
    for i, p in enumerate(owner[1:], start=1):
        children.setdefault(p, []).append(i)
        assert radii[i] / radii[p] == pytest.approx(1 / 3, rel=1e-12)
        gap = np.linalg.norm(centers[i] - centers[p]) - radii[i] - radii[p]
        assert abs(gap) < 1e-12, (i, p, gap)
    assert all(len(kids) == 9 for kids in children.values())
    assert len(children) == flake_count(2)
    for kids in children.values():
        for a, b in itertools.combinations(kids, 2):
            assert np.linalg.norm(centers[a] - centers[b]) > radii[a] + radii[b]


def test_the_root_and_the_floor_follow_balls_c():
    bench = spd.balls(2)
    root = bench.scene["spheres"][0]
    assert root["center"] == [0, 0, 0] and root["radius"] == 0.5
    (floor,) = bench.scene["planes"]
    assert floor["point"] == [0, 0, -0.5] and floor["normal"] == [0, 0, 1]
    # The root rests on the floor; no sphere reaches below it.
    lowest = [s["center"][2] - s["radius"] for s in bench.scene["spheres"]]
    assert lowest[0] == -0.5 and min(lowest) >= -0.5 - 1e-9
    mirror = bench.scene["materials"]["mirror"]
    assert mirror["reflect"] == 0.5 and mirror["diffuse"] == 0.5
    assert [light["color"][0] for light in bench.scene["lights"]] == [0.57735] * 3
    assert bench.scene["camera"]["up"] == [0, 0, 1]


# ---- tetra -----------------------------------------------------------------------------

@pytest.mark.parametrize("size", [1, 2, 3, 4, 6])
def test_tetra_has_4_to_the_size_triangles_facing_out(size):
    vertices, faces = spd.tetra_mesh(size)
    assert len(faces) == 4 ** size
    tris = vertices[faces].astype(np.float64)
    normals = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
    areas = np.linalg.norm(normals, axis=1) / 2
    assert np.allclose(areas, areas[0]) and areas[0] > 0
    # Each tetrahedron's 4 faces point away from its centre.
    centre = vertices.reshape(-1, 4, 3).mean(axis=1).repeat(4, axis=0)
    assert np.all(np.einsum("ij,ij->i", normals, tris.mean(axis=1) - centre) > 0)
    assert np.abs(vertices).max() == 1.0


def test_tetra_inline_and_ply_hold_the_same_triangles(tmp_path):
    inline = spd.tetra(3, triangles="inline")
    as_ply = spd.tetra(3, triangles="ply")
    assert len(inline.scene["triangles"]) == 64 and "meshes" not in inline.scene
    assert as_ply.scene["meshes"][0]["file"] == "spd-tetra-3.ply"
    vertices, faces = as_ply.meshes["spd-tetra-3.ply"]
    assert [t["vertices"] for t in inline.scene["triangles"]] == \
        vertices[faces].astype(np.float64).tolist()


# ---- mount -------------------------------------------------------------------------------

@pytest.mark.parametrize("size", [1, 2, 4, 7, 8])
def test_mountain_has_2_4_to_the_size_triangles_tiling_the_square(size):
    vertices, faces = spd.mountain_mesh(size)
    assert len(faces) == 2 * 4 ** size
    assert len(vertices) == (2 ** size + 1) ** 2
    tris = vertices[faces].astype(np.float64)
    normals = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
    assert np.all(normals[:, 2] > 0), "every triangle faces up"
    assert normals[:, 2].sum() / 2 == pytest.approx(4.0), "the xy projections tile [-1, 1]^2"
    assert np.all(np.isfinite(vertices))
    corners = vertices[[0, 2 ** size, -1 - 2 ** size, -1]]
    assert np.all(corners[:, 2] == 0)


def test_mountain_matches_mount_c():
    # The first triangles and the extremes that mount.c (its grow_mountain, hash_rand
    # and lib_gauss_rand, compiled) writes: the old hash at size <= 7, Jenkins' above.
    vertices, faces = spd.mountain_mesh(2)
    assert vertices[faces[0]].astype(np.float64).ravel().tolist() == pytest.approx(np.ravel(
        [[-1, -1, 0], [-0.5, -1, -0.46658886452388137], [-0.5, -0.5, 0.34363894892653657]]),
        abs=1e-7)
    heights = spd.mountain_heights(6)
    assert heights.max() == pytest.approx(0.9231396181687912, abs=1e-15)
    assert heights.min() == pytest.approx(-0.7029532627401189, abs=1e-15)
    vertices, faces = spd.mountain_mesh(8)
    assert vertices[faces[0]].astype(np.float64).ravel().tolist() == pytest.approx(np.ravel(
        [[-1, -1, 0], [-0.9921875, -1, -0.021204962602136928],
         [-0.9921875, -0.9921875, -0.0034744984776383402]]), abs=1e-7)


def test_crystal_spheres_touch_each_other():
    spheres = spd.crystal_spheres((-0.8, 0.8, 1.0), 0.17)
    assert len(spheres) == 4
    for (a, r), (b, _) in itertools.combinations(spheres, 2):
        assert np.linalg.norm(a - b) == pytest.approx(2 * r, rel=1e-12)


def test_mount_scene_small_inline_large_ply():
    small, large = spd.mount(4), spd.mount(6)
    assert len(small.scene["triangles"]) == 512 and not small.meshes
    assert large.scene["meshes"] == [{"file": "spd-mount-6.ply", "material": "mountain",
                                      "smooth": False}]
    for bench in (small, large):
        glass = bench.scene["materials"]["glass"]
        assert glass["transmit"] == 0.9 and glass["ior"] == 1.5
        assert len(bench.scene["spheres"]) == 4
        scene.validate(bench.scene)


# ---- PLY ---------------------------------------------------------------------------------

def test_ply_round_trip_and_header(tmp_path):
    vertices, faces = spd.mountain_mesh(3)
    path = tmp_path / "m.ply"
    ply.write(path, vertices, faces, comment="a\ntest")
    data = path.read_bytes()
    head = data[:data.index(b"end_header\n")].decode("ascii").split("\n")
    assert head[:3] == ["ply", "format binary_little_endian 1.0", "comment a test"]
    assert "element vertex 81" in head and "element face 128" in head
    back_vertices, back_faces = ply.read(path)
    assert np.array_equal(back_vertices, vertices) and np.array_equal(back_faces, faces)


def test_ply_reader_refuses_a_truncated_file(tmp_path):
    vertices, faces = spd.tetra_mesh(2)
    data = ply.encode(vertices, faces)
    with pytest.raises(ply.PlyError, match="body is"):
        ply.decode(data[:-1])
    with pytest.raises(ply.PlyError):
        ply.decode(data.replace(b"binary_little_endian", b"binary_big_endian___"))
    with pytest.raises(ValueError):
        ply.encode(vertices, faces + len(vertices))


# ---- the set, the command line -------------------------------------------------------------

@pytest.fixture(scope="module")
def lake(tmp_path_factory):
    folder = tmp_path_factory.mktemp("lake")
    bench = spd.lake(10)
    return bench, benchscenes.write(bench, folder)


def test_lake_has_a_million_triangles_glass_and_mirror(lake):
    bench, path = lake
    loaded = scene.load_scene(path)
    vertices, faces = ply.read(loaded["meshes"][0]["file"])
    assert len(faces) == 2 * 4 ** 10 >= 1_000_000
    assert np.all(np.isfinite(vertices))
    materials = [o["material"] for o in loaded["spheres"] + loaded["planes"] + loaded["meshes"]]
    assert any(m["transmit"] > 0.5 for m in materials), "glass"
    assert any(m["reflect"] >= 0.5 and m["transmit"] == 0 for m in materials), "mirror"


@pytest.mark.slow  # make test's 3 minutes (cold, 2-core VM)
@needs_models
def test_every_scene_of_the_set_passes_the_validator(tmp_path):
    names = []
    for bench in benchscenes.standard_set(with_lake=False):
        loaded = scene.load_scene(benchscenes.write(bench, tmp_path))
        names.append(bench.name)
        for mesh in loaded["meshes"]:
            if mesh["file"].startswith(str(tmp_path)):
                vertices, faces = ply.read(mesh["file"])
                assert len(faces) and np.all(np.isfinite(vertices))
    assert len(names) == len(set(names)) == 13


def test_the_same_options_give_the_same_bytes(tmp_path):
    for run in ("a", "b"):
        for args in (["balls", "--size", "2"], ["tetra", "--size", "3"],
                     ["mount", "--size", "5", "--triangles", "ply"],
                     ["random-balls", "--balls", "60,200"]):
            genbench(*args, "-o", tmp_path / run)
    names = sorted(p.name for p in (tmp_path / "a").iterdir())
    assert names == sorted(p.name for p in (tmp_path / "b").iterdir())
    assert "spd-mount-5.ply" in names and len(names) == 6
    for name in names:
        assert (tmp_path / "a" / name).read_bytes() == (tmp_path / "b" / name).read_bytes()


def test_random_balls_are_genscene_s_scenes(tmp_path):
    done = genbench("random-balls", "--balls", "0,7,60", "-o", tmp_path)
    assert done.stdout.count(".json") == 3
    for n in (7, 60):
        text = (tmp_path / ("random-balls-%d.json" % n)).read_text()
        assert text == genscene.to_json(genscene.build_scene(n))
        assert len(scene.load_scene(tmp_path / ("random-balls-%d.json" % n))["spheres"]) == n


@pytest.mark.slow  # make test's 3 minutes (cold, 2-core VM)
def test_random_ball_series_reaches_20000_without_overlap():
    balls = genscene.build_scene(20000)["spheres"]
    assert len(balls) == 20000
    centers = np.array([b["center"] for b in balls])
    radii = np.array([b["radius"] for b in balls])
    order = np.argsort(centers[:, 0])
    centers, radii = centers[order], radii[order]
    reach = 2 * genscene.R_MAX + genscene.GAP
    shift = 1
    # Every pair closer than reach in x is compared: sorted by x, pairs shift apart.
    while shift < len(balls) and (centers[shift:, 0] - centers[:-shift, 0]).min() < reach:
        gap = (np.linalg.norm(centers[shift:] - centers[:-shift], axis=1)
               - radii[shift:] - radii[:-shift])
        assert gap.min() > 0
        shift += 1
    assert shift > 1


@needs_models
def test_assimp_scene_names_installed_models(tmp_path):
    genbench("assimp", "-o", tmp_path)
    loaded = scene.load_scene(tmp_path / "assimp-models.json")
    files = [m["file"] for m in loaded["meshes"]]
    assert len(files) == 4 and all(os.path.isabs(f) and os.path.isfile(f) for f in files)
    assert {os.path.splitext(f)[1].lower() for f in files} == {".ply", ".obj", ".stl"}
    materials = [m["material"] for m in loaded["meshes"]]
    assert any(m["transmit"] > 0 for m in materials) and any(m["reflect"] > 0.5
                                                             for m in materials)


def test_missing_models_are_one_error_line(tmp_path):
    done = genbench("assimp", "--models", tmp_path / "none", "-o", tmp_path, check=False)
    assert done.returncode == 1 and done.stdout == ""
    assert done.stderr.count("\n") == 1
    assert "genbench.py: error: " in done.stderr and "assimp-testmodels" in done.stderr
    assert not (tmp_path / "assimp-models.json").exists()


@pytest.mark.parametrize("args", [["balls", "--size", "7"], ["balls", "--size", "0"],
                                  ["tetra", "--size", "x"], ["mount", "--triangles", "obj"],
                                  ["random-balls", "--balls", "-1"], ["balls"], ["nosuch"],
                                  ["mount", "--depth", "65"], ["tetra", "--image", "0x5"]])
def test_bad_options_exit_2(tmp_path, args):
    if args != ["balls"]:
        args = args + ["-o", str(tmp_path / "out")]
    done = genbench(*args, check=False)
    assert done.returncode == 2 and done.stdout == ""
    assert "error" in done.stderr
    assert not (tmp_path / "out").exists()


def test_help_names_every_scene_and_the_sizes():
    text = genbench("--help").stdout
    for word in ("balls", "tetra", "mount", "lake", "random-balls", "assimp", "all",
                 "9^k", "4^size", "2 * 4^size", "-o build/bench-scenes"):
        assert word in text


# ---- rendering the version 1 scenes with today's rtcl ----------------------------------------

@pytest.mark.parametrize("args, name", [(["balls", "--size", "2"], "spd-balls-2"),
                                        (["random-balls", "--balls", "200"],
                                         "random-balls-200")])
def test_version_1_scenes_render(tmp_path, args, name):
    genbench(*args, "-o", tmp_path)
    out = tmp_path / "out.ppm"
    done = subprocess.run([RTCL, "-s", tmp_path / (name + ".json"), "--size", "24x24",
                           "-o", out], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    data = out.read_bytes()
    pixels = np.frombuffer(data[-24 * 24 * 3:], dtype=np.uint8).reshape(-1, 3)
    background = pixels[0]
    assert len({tuple(p) for p in pixels}) > 10, "more than the background"
    assert np.any(np.any(pixels != background, axis=1))
