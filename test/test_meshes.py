"""Version 2 scenes end to end (docs/SCENE.md "Version 2: triangle meshes"): a
mesh scene renders with every option that counts work, -v reports the
triangles, and a refused mesh leaves no output."""
import json
import math
import os
import pathlib
import random
import struct
import subprocess
import time

import pytest

import builds

ROOT = pathlib.Path(__file__).resolve().parent.parent
RTCL = os.environ.get("RTCL", str(ROOT / "rtcl"))
MESH_SCENE = ROOT / "test" / "meshes" / "mesh_scene.json"


def rtcl(*args):
    return subprocess.run([RTCL, *args], capture_output=True, text=True, cwd=ROOT, timeout=300)


def test_verbose_counts_triangles_and_skipped_ones(tmp_path):
    scene = tmp_path / "s.json"
    scene.write_text(json.dumps({
        "format": "rtcl-scene", "version": 2,
        "camera": {"eye": [0, 0, -5], "look_at": [0, 0, 0]},
        "meshes": [{"file": str(ROOT / "test" / "meshes" / "degenerate.obj")}]}))
    result = rtcl("-s", str(scene), "-o", str(tmp_path / "o.ppm"), "--size", "8x6", "-v")
    assert result.returncode == 0, result.stderr
    assert "rtcl: 1 triangles; 1 of area 0 (after placement) skipped from mesh files" \
        in result.stderr


def test_mesh_scene_counts_flops_and_writes_a_work_map(tmp_path):
    stats = tmp_path / "stats.json"
    result = rtcl("-s", str(MESH_SCENE), "-o", str(tmp_path / "o.ppm"), "--size", "24x16",
                  "--flops", str(tmp_path / "flops.npy"), "--work-map", str(tmp_path / "work.npy"), "--stats", str(stats))
    assert result.returncode == 0, result.stderr
    assert (tmp_path / "work.npy").stat().st_size > 24 * 16 * 8
    data = json.loads(stats.read_text())
    flops = [v for k, v in data.items() if "flops" in k and isinstance(v, int)]
    assert flops and max(flops) > 0


def test_missing_mesh_file_leaves_no_output(tmp_path):
    scene = tmp_path / "s.json"
    scene.write_text(json.dumps({
        "format": "rtcl-scene", "version": 2,
        "camera": {"eye": [0, 0, -5], "look_at": [0, 0, 0]},
        "meshes": [{"file": "gone.stl"}]}))
    out = tmp_path / "o.png"
    result = rtcl("-s", str(scene), "-o", str(out))
    assert result.returncode == 1
    assert result.stderr == (f'{scene}: meshes[0].file: cannot read "gone.stl": '
                             "No such file or directory\n")
    assert not out.exists()


def test_shipped_mesh_scene_renders_with_its_models(tmp_path):
    """scenes/glass_mesh.json finds its models relative to itself, from any folder."""
    out = tmp_path / "o.ppm"
    result = subprocess.run([RTCL, "-s", str(ROOT / "scenes" / "glass_mesh.json"), "-o", str(out),
                             "--size", "40x30", "-v"], capture_output=True, text=True,
                            cwd=tmp_path, timeout=300)
    assert result.returncode == 0, result.stderr
    assert "rtcl: 333 triangles; 0 of area 0" in result.stderr
    assert out.stat().st_size > 40 * 30 * 3


def test_mesh_scene_renders_through_the_bvh_by_default(tmp_path):
    """Spheres and triangles in one hierarchy (docs/bvh.md): the default --accel bvh
    builds it over the sphere and the 335 triangles, gives brute force's image, and
    tests fewer triangles than brute force (fewer flops, some node visits)."""
    runs = {}
    for accel in ("none", None):
        name = accel or "default"
        args = ["--accel", accel] if accel else []
        result = rtcl("-s", str(MESH_SCENE), "-o", str(tmp_path / f"{name}.ppm"),
                      "--size", "24x16", "-v", "--stats", str(tmp_path / f"{name}.json"),
                      "--flops", str(tmp_path / f"{name}.npy"), *args)
        assert result.returncode == 0, result.stderr
        runs[name] = (result, json.loads((tmp_path / f"{name}.json").read_text()))
    result, stats = runs["default"]
    assert stats["accel"] == "bvh"
    assert "rtcl: BVH of 1 sphere and 335 triangles: " in result.stderr
    # At most 8 primitives a leaf: at least 336 / 8 leaves, one node fewer.
    assert stats["bvh"]["nodes"] >= 336 // 8 - 1
    assert stats["node_visits"] > 0
    assert stats["total_flops"] < runs["none"][1]["total_flops"]
    assert runs["none"][1]["node_visits"] == 0
    assert (tmp_path / "default.ppm").read_bytes() == (tmp_path / "none.ppm").read_bytes()


def test_a_scene_without_spheres_builds_leaves_of_triangles_only(tmp_path):
    """glass_mesh (meshes and a plane, no sphere) with --accel bvh builds with
    RTCL_LEAF_TRIANGLES_ONLY (traverse.cl: only the leaf triangles' loop) and gives
    the image of bvh-compact and of brute force, which build without it, as does a
    scene with a sphere."""
    runs = {}
    for accel in ("bvh", "bvh-compact", "none"):
        result = rtcl("-s", "scenes/glass_mesh.json", "-o", str(tmp_path / f"{accel}.ppm"),
                      "--size", "24x16", "--accel", accel, "--stats",
                      str(tmp_path / f"{accel}.json"))
        assert result.returncode == 0, result.stderr
        runs[accel] = json.loads((tmp_path / f"{accel}.json").read_text())
    assert "-DRTCL_LEAF_TRIANGLES_ONLY" in runs["bvh"]["build_options"]
    assert "-DRTCL_LEAF_TRIANGLES_ONLY" not in runs["bvh-compact"]["build_options"]
    assert "-DRTCL_LEAF_TRIANGLES_ONLY" not in runs["none"]["build_options"]
    for accel in ("bvh-compact", "none"):
        assert (tmp_path / "bvh.ppm").read_bytes() == (tmp_path / f"{accel}.ppm").read_bytes()
    with_sphere = rtcl("-s", str(MESH_SCENE), "-o", str(tmp_path / "s.ppm"), "--size", "8x8",
                       "--stats", str(tmp_path / "s.json"))
    assert with_sphere.returncode == 0, with_sphere.stderr
    stats = json.loads((tmp_path / "s.json").read_text())
    assert "-DRTCL_LEAF_TRIANGLES_ONLY" not in stats["build_options"]


def many_balls_scene(tmp_path):
    """900 small balls in a grid on a plane, lit: a binary tree of over 128 nodes."""
    scene = tmp_path / "balls.json"
    spheres = [{"center": [x * 0.5 - 6, 0.3 + (x * 7 + z) % 3 * 0.2, z * 0.5],
                "radius": 0.2, "material": ["red", "glass"][(x + z) % 2]}
               for x in range(30) for z in range(30)]
    scene.write_text(json.dumps({
        "format": "rtcl-scene", "version": 1,
        "camera": {"eye": [0, 4, -8], "look_at": [0, 0, 4], "fov": 60},
        "materials": {"red": {"color": [0.8, 0.3, 0.2], "reflect": 0.3},
                      "glass": {"color": [0.2, 0.4, 0.9], "transmit": 0.5, "ior": 1.5}},
        "spheres": spheres,
        "planes": [{"point": [0, 0, 0], "normal": [0, 1, 0], "material": "red"}],
        "lights": [{"position": [2, 8, -4], "color": [1, 1, 1]}]}))
    return scene


@pytest.mark.parametrize("scene", ["scenes/glass_mesh.json", "balls", str(MESH_SCENE)])
def test_a_cpus_four_wide_tree_gives_the_binary_trees_image(tmp_path, scene):
    """On a CPU device the BVH's nodes are four-wide (docs/bvh.md, "A four-wide
    tree on CPUs"; -DRTCL_BVH4) when the binary tree has 128 nodes or more,
    outside the counting build: the image of the binary tree (RTCL_TEST_BVH2=1),
    for meshes, spheres and both at 4 spp."""
    if scene == "balls":
        scene = str(many_balls_scene(tmp_path))
    runs = {}
    for width, env in (("4", {}), ("2", {"RTCL_TEST_BVH2": "1"})):
        result = subprocess.run(
            [RTCL, "-s", scene, "-o", str(tmp_path / f"{width}.ppm"), "--size", "40x30",
             "--spp", "4", "--stats", str(tmp_path / f"{width}.json")],
            capture_output=True, text=True, cwd=ROOT, timeout=300, env={**os.environ, **env})
        assert result.returncode == 0, result.stderr
        runs[width] = json.loads((tmp_path / f"{width}.json").read_text())
    assert runs["4"]["bvh"]["nodes"] >= 128
    assert "-DRTCL_BVH4" in runs["4"]["build_options"]
    assert "-DRTCL_BVH4" not in runs["2"]["build_options"]
    assert (runs["4"]["bvh"]["width"], runs["2"]["bvh"]["width"]) == (4, 2)
    assert runs["4"]["bvh"]["nodes"] == runs["2"]["bvh"]["nodes"]
    assert (tmp_path / "4.ppm").read_bytes() == (tmp_path / "2.ppm").read_bytes()


def test_a_small_tree_stays_binary_on_a_cpu(tmp_path):
    """The default scene's 16 nodes: a four-wide visit would cost more than it
    saves (host/layout/bvh.h, BVH_WIDE_MIN_NODES)."""
    result = rtcl("-o", str(tmp_path / "o.ppm"), "--size", "8x8", "--stats",
                  str(tmp_path / "s.json"))
    assert result.returncode == 0, result.stderr
    stats = json.loads((tmp_path / "s.json").read_text())
    assert stats["bvh"]["nodes"] < 128 and stats["bvh"]["width"] == 2
    assert stats["bvh"]["device_nodes"] == stats["bvh"]["nodes"]
    assert "-DRTCL_BVH4" not in stats["build_options"]


@pytest.mark.parametrize("scene, kernel", [
    (ROOT / "scenes" / "two_balls.json", "dynamic"),
    # The same rule: make test-long.
    pytest.param(ROOT / "scenes" / "two_balls.json", "wavefront", marks=pytest.mark.slow),
    pytest.param(MESH_SCENE, "persistent", marks=pytest.mark.slow)])
def test_a_scene_without_lights_builds_without_shadow_rays(tmp_path, scene, kernel):
    """A scene with no light builds with RTCL_NO_LIGHTS (shade.cl: no light to
    take, so the shadow rays' code is left out) and gives the image of the same
    scene with one black light, which builds without it and traces the shadow
    rays for nothing."""
    data = json.loads(scene.read_text())
    for mesh in data.get("meshes", []):
        mesh["file"] = str((scene.parent / mesh["file"]).resolve())
    runs = {}
    for name, lights in (("none", []), ("black", [{"position": [-6, 9, -7],
                                                     "color": [0, 0, 0]}])):
        path = tmp_path / f"{name}.json"
        path.write_text(json.dumps({**data, "lights": lights}))
        result = rtcl("-s", str(path), "-k", kernel, "--size", "24x16", "--spp", "2", "-o",
                      str(tmp_path / f"{name}.ppm"), "--stats", str(tmp_path / f"{name}.s.json"))
        assert result.returncode == 0, result.stderr
        runs[name] = json.loads((tmp_path / f"{name}.s.json").read_text())
    assert "-DRTCL_NO_LIGHTS" in runs["none"]["build_options"]
    assert "-DRTCL_NO_LIGHTS" not in runs["black"]["build_options"]
    pixels = 24 * 16 * 3  # the header names the scene file
    assert (tmp_path / "none.ppm").read_bytes()[-pixels:] == \
        (tmp_path / "black.ppm").read_bytes()[-pixels:]


def test_bvh_counts_add_up_over_two_devices(tmp_path):
    """One image in row bands over two PoCL devices (--devices) counts the same
    flops and BVH node visits as one device, and --stats has the BVH's figures."""
    runs = {}
    for name, args, env in (("one", [], None),
                            ("two", ["--devices", "0:0,0:1"], {"POCL_DEVICES": "pthread pthread"})):
        result = subprocess.run([RTCL, "-s", str(MESH_SCENE), "--size", "48x32",
                                 "-o", str(tmp_path / f"{name}.ppm"),
                                 "--work-map", str(tmp_path / f"{name}.npy"),
                                 "--stats", str(tmp_path / f"{name}.json"), *args],
                                capture_output=True, text=True, cwd=ROOT, timeout=300,
                                env={**os.environ, **(env or {})})
        assert result.returncode == 0, result.stderr
        runs[name] = json.loads((tmp_path / f"{name}.json").read_text())
    for count in ("node_visits", "leaf_visits", "primitive_tests"):
        assert runs["two"][count] == runs["one"][count] > 0
    assert runs["two"]["total_flops"] == runs["one"]["total_flops"]
    assert runs["two"]["bvh"]["nodes"] == runs["one"]["bvh"]["nodes"] > 0
    assert (tmp_path / "two.ppm").read_bytes() == (tmp_path / "one.ppm").read_bytes()


def grid_mesh_scene(tmp_path, squares=8):
    """A triangle-only scene: a squares x squares grid of 2 triangles each, one light."""
    import sys
    sys.path.insert(0, str(ROOT / "tools"))
    import numpy as np
    from rtcl_tools import ply
    k = squares + 1
    y, x = np.mgrid[0:k, 0:k]
    vertices = np.stack([x.ravel(), y.ravel(), 0 * x.ravel()], -1).astype(float) / squares
    a = (y[:-1, :-1] * k + x[:-1, :-1]).ravel()
    faces = np.concatenate([np.stack([a, a + 1, a + k], -1), np.stack([a + 1, a + k + 1, a + k], -1)])
    ply.write(tmp_path / "grid.ply", vertices, faces)
    scene = tmp_path / "grid.json"
    scene.write_text(json.dumps({
        "format": "rtcl-scene", "version": 2,
        "camera": {"eye": [0.5, 0.5, -3], "look_at": [0.5, 0.5, 0]},
        "lights": [{"position": [0, 0, -5]}],
        "meshes": [{"file": "grid.ply", "smooth": False}]}))
    return scene, 2 * squares * squares


def test_device_bytes_per_triangle_add_up(tmp_path):
    """--stats' scene_bytes is the device block, bytes_per_triangle that over the
    triangles, vertices the distinct ones (the grid's corners, each stored once),
    bvh.bytes its 64-byte nodes and 4-byte references; -v prints the same; --accel
    none's block is the same less the BVH. bvh-compact within issue 11's 64 bytes
    per triangle; bvh (its leaves of triangles smaller and the triangles again in
    leaf order with their vertices inline, 48 bytes each, issue 26) within 128.
    On a CPU (PoCL) a tree of 128 nodes or more is four-wide, 128 bytes a node
    (docs/bvh.md)."""
    scene, n = grid_mesh_scene(tmp_path)
    runs = {}
    for accel in ("bvh", "none", "bvh-compact"):
        result = rtcl("-s", str(scene), "-o", str(tmp_path / f"{accel}.ppm"), "--size", "16x16",
                      "-v", "--accel", accel, "--stats", str(tmp_path / f"{accel}.json"))
        assert result.returncode == 0, result.stderr
        runs[accel] = (result.stderr, json.loads((tmp_path / f"{accel}.json").read_text()))
    stderr, stats = runs["bvh"]
    total, bvh, vertices = stats["scene_bytes"], stats["bvh"], stats["vertices"]
    assert stats["bytes_per_triangle"] == total / n
    assert vertices == 9 * 9  # the 8x8 grid's corners
    node_bytes = {2: 64, 4: 128}  # binary nodes; a CPU's four-wide ones
    assert bvh["bytes"] == node_bytes[bvh["width"]] * bvh["device_nodes"] + (4 + 48) * n
    # 16 bytes a triangle (its vertex indices and material), 32 a vertex (its
    # position and normal), the BVH, and a header, one material and one light
    # of less than 1 KiB
    assert 0 < total - (16 * n + 32 * vertices + bvh["bytes"]) < 1024
    assert stats["bytes_per_triangle"] <= 128
    compact = runs["bvh-compact"][1]
    assert compact["accel"] == "bvh-compact" and compact["bytes_per_triangle"] <= 64
    assert (compact["bvh"]["bytes"] ==
            node_bytes[compact["bvh"]["width"]] * compact["bvh"]["device_nodes"] + 4 * n)
    assert compact["bvh"]["nodes"] < bvh["nodes"]
    assert (tmp_path / "bvh-compact.ppm").read_bytes() == (tmp_path / "bvh.ppm").read_bytes()
    assert runs["none"][1]["scene_bytes"] == total - bvh["bytes"]  # 4 n a multiple of 16
    assert "bvh" not in runs["none"][1]
    assert (f"rtcl: device scene block {total} bytes for {n} triangles: "
            f"{total / n:.1f} bytes per triangle (16 triangle, {32 * vertices / n:.1f} "
            f"vertices ({vertices}), {bvh['bytes'] / n:.1f} BVH)" in stderr)
    assert f"built in {bvh['build_ms']:.3f} ms" in stderr


# ---- the mesh import helper (host/scene/mesh.h): Assimp in a process of its own ----

def quad_scene(tmp_path):
    scene = tmp_path / "s.json"
    scene.write_text(json.dumps({
        "format": "rtcl-scene", "version": 2,
        "camera": {"eye": [0, 0, -5], "look_at": [0, 0, 0]},
        "meshes": [{"file": str(ROOT / "test" / "meshes" / "quad.ply")}]}))
    return scene


def render_with_helper(tmp_path, helper):
    """Renders quad_scene with RTCL_MESHREAD=helper; the output must not appear."""
    scene, out = quad_scene(tmp_path), tmp_path / "o.png"
    result = subprocess.run([RTCL, "-s", str(scene), "-o", str(out), "--size", "8x6"],
                            capture_output=True, text=True, cwd=ROOT, timeout=300,
                            env={**os.environ, "RTCL_MESHREAD": str(helper)})
    assert result.returncode == 1
    assert not out.exists()
    prefix = f'{scene}: meshes[0].file: cannot read "{ROOT}/test/meshes/quad.ply": '
    assert result.stderr.startswith(prefix), result.stderr
    assert result.stderr.count("\n") == 1
    return result.stderr[len(prefix):-1]


def write_helper(tmp_path, body):
    helper = tmp_path / "helper.sh"
    helper.write_text("#!/bin/sh\n" + body + "\n")
    helper.chmod(0o755)
    return helper


def test_the_helper_named_in_the_environment_is_the_one_run(tmp_path):
    """RTCL_MESHREAD names the helper: the quad renders through the built one
    named there, and through none when the name is wrong."""
    built = pathlib.Path(RTCL).resolve().parent
    helper = next(p for p in (built / "rtcl-meshread", built / "build" / "rtcl-meshread")
                  if p.exists())
    scene = quad_scene(tmp_path)
    result = subprocess.run([RTCL, "-s", str(scene), "-o", str(tmp_path / "o.ppm"),
                             "--size", "8x6"], capture_output=True, text=True, timeout=300,
                            env={**os.environ, "RTCL_MESHREAD": str(helper)})
    assert result.returncode == 0, result.stderr
    missing = tmp_path / "no-such-helper"
    assert render_with_helper(tmp_path, missing) == (
        f"the mesh importer failed: cannot run {missing}: No such file or directory")


def test_a_helper_that_fails_is_reported_with_what_it_said(tmp_path):
    helper = write_helper(tmp_path, "echo 'cannot load libassimp.so.5' >&2; exit 127")
    assert render_with_helper(tmp_path, helper) == (
        "the mesh importer failed (exit status 127): cannot load libassimp.so.5")


def test_a_helper_that_answers_nothing_is_reported(tmp_path):
    helper = write_helper(tmp_path, "exit 0")
    assert render_with_helper(tmp_path, helper) == (
        "the mesh importer failed: it ended without an answer")


def test_a_helper_that_answers_nonsense_is_reported(tmp_path):
    helper = write_helper(tmp_path, "head -c 4096 /dev/zero")  # more than a header
    assert render_with_helper(tmp_path, helper) == (
        "the mesh importer failed: its answer makes no sense")


def test_a_helper_of_another_rtcl_is_named_as_such(tmp_path):
    """An answer that starts as a helper's but in another form (an old
    rtcl-meshread left in RTCL_MESHREAD: it was read as "out of memory for
    2097152 triangles") says whose it is and what to do."""
    helper = write_helper(tmp_path, "printf mesh; head -c 4096 /dev/zero")
    assert render_with_helper(tmp_path, helper) == (
        f"the mesh importer {helper} is another rtcl's (its answer has another form): "
        "name the rtcl-meshread built with this rtcl in RTCL_MESHREAD, or reinstall rtcl")


def test_a_helper_killed_by_a_signal_blames_the_file(tmp_path):
    """A crash inside the importer (Assimp's abort() on a malformed file) is the
    file's fault; what the helper printed first says where."""
    helper = write_helper(tmp_path, "echo 'ai_assert failure in X.cpp(1): n > 0' >&2; "
                                    "kill -SEGV $$")
    assert render_with_helper(tmp_path, helper) == (
        "the importer (Assimp) crashed on it (Segmentation fault: ai_assert failure in "
        "X.cpp(1): n > 0); the file is malformed")


def test_a_sanitizer_report_in_the_helper_is_rtcls_failure(tmp_path):
    helper = write_helper(tmp_path, "echo '=================' >&2; "
                                    "echo '==1==ERROR: AddressSanitizer: heap-buffer-overflow' >&2; "
                                    "kill -ABRT $$")
    assert render_with_helper(tmp_path, helper) == (
        "the mesh importer failed: ==1==ERROR: AddressSanitizer: heap-buffer-overflow")


def test_the_helper_refuses_to_write_binary_to_a_terminal_or_without_a_file():
    built = pathlib.Path(RTCL).resolve().parent
    helper = next(p for p in (built / "rtcl-meshread", built / "build" / "rtcl-meshread")
                  if p.exists())
    result = subprocess.run([str(helper)], capture_output=True, text=True, timeout=60)
    assert result.returncode == 2
    assert "rtcl's mesh import helper" in result.stderr


# ---- issue 24: no mesh file hangs rtcl, exhausts memory or is read wrong ----

PLY_FACES = ("ply\nformat {format} 1.0\nelement vertex {vertices}\nproperty float x\n"
             "property float y\nproperty float z\nelement face {faces}\n"
             "property list uchar int vertex_indices\nend_header\n")


def refused(tmp_path, mesh, *options, env=None, timeout=60):
    """Renders a scene placing mesh (a path); returns the reason it was refused,
    checking the one line, the exit status and that no output appeared. The
    timeout bounds what once hung."""
    scene, out = tmp_path / "scene.json", tmp_path / "o.png"
    scene.write_text(json.dumps({
        "format": "rtcl-scene", "version": 2,
        "camera": {"eye": [0, 0, -5], "look_at": [0, 0, 0]},
        "meshes": [{"file": str(mesh)}]}))
    result = subprocess.run([RTCL, "-s", str(scene), "-o", str(out), "--size", "8x6", *options],
                            capture_output=True, text=True, cwd=ROOT, timeout=timeout,
                            env={**os.environ, **(env or {})})
    assert result.returncode == 1, result.stderr
    assert not out.exists()
    assert result.stderr.count("\n") == 1, result.stderr
    prefix = f"{scene}: meshes[0].file: "
    assert result.stderr.startswith(prefix), result.stderr
    return result.stderr[len(prefix):-1]


def test_an_obj_whose_mtllib_is_a_fifo_is_refused_not_waited_on(tmp_path):
    """Finding 4: Assimp opened the FIFO an OBJ's mtllib names and waited for a
    writer for ever. Every file the importer opens must now be a regular one."""
    os.mkfifo(tmp_path / "fifo.mtl")
    mesh = tmp_path / "m.obj"
    mesh.write_text("mtllib fifo.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    assert refused(tmp_path, mesh) == (
        f'cannot read "{mesh}": it names "{tmp_path}/fifo.mtl", which is not a regular file')


def test_a_gltf_whose_buffer_is_a_fifo_is_refused_not_waited_on(tmp_path):
    os.mkfifo(tmp_path / "fifo.bin")
    gltf = json.loads((ROOT / "test" / "meshes" / "nodes.gltf").read_text())
    gltf["buffers"][0]["uri"] = "fifo.bin"
    mesh = tmp_path / "m.gltf"
    mesh.write_text(json.dumps(gltf))
    reason = refused(tmp_path, mesh)
    assert reason.startswith(f'cannot read "{mesh}": ') and "fifo.bin" in reason, reason


@pytest.mark.parametrize("how", ["option", "environment"])
def test_an_import_past_its_time_limit_is_refused_with_the_limit(tmp_path, how):
    """Finding 4: the import has a time limit; a helper that does not answer
    (here one that sleeps) is killed when it passes, with one message."""
    helper = write_helper(tmp_path, "sleep 100")
    options, env = (["--mesh-time-limit", "1"], {}) if how == "option" else \
        ([], {"RTCL_MESH_TIME_LIMIT": "1"})
    started = time.monotonic()
    reason = refused(tmp_path, ROOT / "test" / "meshes" / "quad.ply", *options,
                     env={"RTCL_MESHREAD": str(helper), **env})
    assert time.monotonic() - started < 30
    assert reason.endswith(": the import took longer than its limit of 1 s "
                           "(--mesh-time-limit or RTCL_MESH_TIME_LIMIT)")


def test_a_polygon_of_100000_vertices_is_refused_at_once(tmp_path):
    """Finding 4: a 4.9 MB OBJ with one 100,000-vertex face ran for minutes
    (Assimp triangulates in time quadratic in a polygon's vertices)."""
    n = 100000
    mesh = tmp_path / "disc.obj"
    angles = [2 * math.pi * i / n for i in range(n)]
    mesh.write_text("".join(f"v {math.cos(a):.6f} {math.sin(a):.6f} 0\n" for a in angles)
                    + "f " + " ".join(str(i + 1) for i in range(n)) + "\n")
    assert refused(tmp_path, mesh, timeout=30) == (
        f'cannot read "{mesh}": line {n + 1}: a face of {n} vertices, more than the 4096 a '
        "polygon may have")


def test_a_ply_declaring_two_billion_faces_is_refused_before_any_allocation(tmp_path):
    """Finding 5: a 187-byte ASCII PLY declaring 2,000,000,000 faces made the
    helper take 15.6 GB for 38 s, then "std::bad_alloc"."""
    mesh = tmp_path / "huge.ply"
    mesh.write_text(PLY_FACES.format(format="ascii", vertices=3, faces=2000000000)
                    + "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n")
    started = time.monotonic()
    assert refused(tmp_path, mesh, timeout=30) == (
        f'cannot read "{mesh}": its PLY header declares 3 "vertex" and 2000000000 "face" '
        "records, at least 4000000017 bytes, but the file holds 26 after its header")
    assert time.monotonic() - started < 10


@pytest.mark.skipif(builds.built_with_asan(RTCL),
                    reason="AddressSanitizer cannot run under an address-space limit")
def test_an_import_beyond_its_memory_limit_is_one_message(tmp_path):
    """Finding 5: the helper runs under a memory limit (RLIMIT_AS); a file
    that needs more is refused naming the limit."""
    n = 300000
    mesh = tmp_path / "big.ply"
    vertices = b"".join(struct.pack("<9f", i, 0, 0, i + 1, 0, 0, i, 1, 0) for i in range(n))
    faces = b"".join(struct.pack("<B3i", 3, 3 * i, 3 * i + 1, 3 * i + 2) for i in range(n))
    mesh.write_bytes(PLY_FACES.format(format="binary_little_endian", vertices=3 * n,
                                      faces=n).encode() + vertices + faces)
    assert refused(tmp_path, mesh, "--mesh-memory-limit", "40") == (
        f'cannot read "{mesh}": the import needed more memory than its limit of 40 MiB '
        "(--mesh-memory-limit or RTCL_MESH_MEMORY_LIMIT)")
    assert refused(tmp_path, mesh, env={"RTCL_MESH_MEMORY_LIMIT": "40"}).endswith("40 MiB "
        "(--mesh-memory-limit or RTCL_MESH_MEMORY_LIMIT)")


@pytest.mark.parametrize("bad", ["-1", "1.5", "x", ""])
def test_a_bad_mesh_limit_is_a_usage_error(bad):
    for args, env in ((["--mesh-time-limit", bad], {}), (["--mesh-memory-limit", bad], {}),
                      ([], {"RTCL_MESH_TIME_LIMIT": bad}), ([], {"RTCL_MESH_MEMORY_LIMIT": bad})):
        result = subprocess.run([RTCL, *args, "-o", "/nonexistent/x.png"], capture_output=True,
                                text=True, timeout=60, env={**os.environ, **env})
        assert result.returncode == 2 and result.stderr.count("\n") == 1, result.stderr
        assert "expected a whole number of " in result.stderr


@pytest.mark.parametrize("kind", ["ascii", "binary"])
def test_a_ply_with_fewer_faces_than_declared_is_refused(tmp_path, kind):
    """Finding 11: a header declaring 1000 faces over a body holding 1 gave 1000
    triangles (Assimp pads); the body must hold every declared record. The
    padding makes the file long enough to pass the size check."""
    mesh = tmp_path / "short.ply"
    if kind == "ascii":
        body = b"0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n" + b" " * 10000
        header = PLY_FACES.format(format="ascii", vertices=3, faces=1000)
    else:
        body = (struct.pack("<9f", 0, 0, 0, 1, 0, 0, 0, 1, 0) + struct.pack("<B3i", 3, 0, 1, 2)
                + b"\xff" * 2000)  # faces of 255 vertices, the second one cut off
        header = PLY_FACES.format(format="binary_little_endian", vertices=3, faces=1000)
    mesh.write_bytes(header.encode() + body)
    expected_after = 1 if kind == "ascii" else 2
    assert refused(tmp_path, mesh) == (
        f'cannot read "{mesh}": its PLY header declares 1000 "face" records, but the file '
        f"ends after {expected_after} of them (a truncated file, or a header that does not "
        "match it)")


def test_a_mesh_whose_triangles_all_have_area_0_is_refused(tmp_path):
    """Finding 10: SCENE.md's rule, once only for inline triangles."""
    flat = tmp_path / "flat.obj"
    flat.write_text("v 0 0 0\nv 1 0 0\nv 2 0 0\nv 3 0 0\nf 1 2 3\nf 2 3 4\n")
    assert refused(tmp_path, flat) == (
        f'"{flat}": all of its 2 triangles have area 0 (after placement)')
    regression = ROOT / "test" / "fuzz_mesh_regressions" / "ply-all-area-zero.ply"
    assert "area 0 (after placement)" in refused(tmp_path, regression)


def test_a_gltf_node_of_scale_0_is_refused(tmp_path):
    gltf = json.loads((ROOT / "test" / "meshes" / "nodes.gltf").read_text())
    gltf["nodes"][1]["scale"] = [0, 0, 0]
    for buffer in gltf["buffers"]:
        if not buffer["uri"].startswith("data:"):
            buffer["uri"] = str(ROOT / "test" / "meshes" / buffer["uri"])
    mesh = tmp_path / "m.gltf"
    mesh.write_text(json.dumps(gltf))
    assert refused(tmp_path, mesh) == (
        f'"{mesh}": its one triangle has area 0 (after placement)')


@pytest.mark.parametrize("name", ["x.ase", "x.csm"])
def test_random_bytes_are_not_a_mesh(tmp_path, name):
    """Finding 10: random bytes named x.ase or x.csm were accepted (every triangle
    of area 0, or none)."""
    mesh = tmp_path / name
    mesh.write_bytes(random.Random(24).randbytes(4096))
    reason = refused(tmp_path, mesh)
    assert str(mesh) in reason
