"""Nothing lost, part 3 (issue 39): every file a model reads is an input that no
output may replace (finding 1); the files a mesh file names are confined to its
folder by where they lead (finding 3); texture names are whole (finding 4);
glTF URIs are percent-decoded (finding 9); control bytes in mesh messages are
escaped (finding 19). Each test here failed on a5dea23. Models and images are
generated here, tiny."""
import base64
import json
import os
import pathlib
import shutil
import struct
import subprocess

import pytest

from test_textures import png

ROOT = pathlib.Path(__file__).resolve().parent.parent
RTCL = os.environ.get("RTCL", str(ROOT / "rtcl"))
SMALL = ["--size", "16x16", "-q"]
RED, GREEN = (255, 0, 0, 255), (0, 255, 0, 255)
QUAD_OBJ = ("mtllib q.mtl\nv -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\n"
            "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nusemtl t\nf 1/1 2/2 3/3\nf 1/1 3/3 4/4\n")


def rtcl(*args, cwd, env=None):
    return subprocess.run([RTCL, *map(str, args)], capture_output=True, text=True, cwd=cwd,
                          timeout=120, env={**os.environ, **(env or {})})


def one_line(result, status, words):
    """The run failed with exactly one line on stderr holding words."""
    assert result.returncode == status, (result.returncode, result.stderr)
    assert result.stderr.count("\n") == 1, result.stderr
    assert words in result.stderr, result.stderr


def scene_file(folder, mesh_file, **mesh):
    doc = {"format": "rtcl-scene", "version": 2,
           "camera": {"eye": [0, 0, 3], "look_at": [0, 0, 0]}, "ambient": [1, 1, 1],
           "lights": [{"position": [0, 0, 5]}],
           "meshes": [dict({"file": mesh_file, "smooth": False}, **mesh)]}
    (folder / "s.json").write_text(json.dumps(doc))
    return "s.json"


def obj_model(folder, texture="t.png", write_texture=True):
    """model/q.obj, its MTL library model/q.mtl and its texture."""
    model = folder / "model"
    model.mkdir(exist_ok=True)
    (model / "q.obj").write_text(QUAD_OBJ)
    (model / "q.mtl").write_text(f"newmtl t\nKd 1 1 1\nmap_Kd {texture}\n")
    if write_texture:
        (model / texture).write_bytes(png([[RED, GREEN], [GREEN, RED]]))
    return scene_file(folder, "model/q.obj")


def gltf_quad(images=(), buffers=(), texture=True):
    """A glTF quad with texture coordinates, its geometry in a data: buffer
    (buffer 0); images, and more buffers, as given."""
    blob = struct.pack("<12f", -1, -1, 0, 1, -1, 0, 1, 1, 0, -1, 1, 0)
    blob += struct.pack("<8f", 0, 1, 1, 1, 1, 0, 0, 0) + struct.pack("<6H", 0, 1, 2, 0, 2, 3)
    doc = {"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
           "nodes": [{"mesh": 0}],
           "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1},
                                       "indices": 2, "material": 0}]}],
           "materials": [{"pbrMetallicRoughness": {"metallicFactor": 0}}],
           "buffers": [{"byteLength": len(blob), "uri": "data:application/octet-stream;base64,"
                        + base64.b64encode(blob).decode()}] + list(buffers),
           "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 48},
                           {"buffer": 0, "byteOffset": 48, "byteLength": 32},
                           {"buffer": 0, "byteOffset": 80, "byteLength": 12}],
           "accessors": [{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
                          "min": [-1, -1, 0], "max": [1, 1, 0]},
                         {"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC2"},
                         {"bufferView": 2, "componentType": 5123, "count": 6,
                          "type": "SCALAR"}]}
    if images:
        doc["images"] = list(images)
        doc["textures"] = [{"source": 0}]
        if texture:
            doc["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = {"index": 0}
    return doc


def geometry_in(doc, uri):
    """Moves the quad's geometry (buffer 0) to the file uri names; returns its bytes."""
    geometry = doc["buffers"][0]
    blob = base64.b64decode(geometry["uri"].split(",")[1])
    geometry["uri"] = uri
    return blob


def gltf_model(folder, doc, name="m.gltf"):
    model = folder / "gmodel"
    model.mkdir(exist_ok=True)
    (model / name).write_text(json.dumps(doc))
    return scene_file(folder, f"gmodel/{name}")


def contents(folder):
    """Every file under folder and its bytes (links followed), every link and where it leads."""
    found = {}
    for path in sorted(folder.rglob("*")):
        if path.is_symlink():
            found[path] = ("link", os.readlink(path))
        elif path.is_file():
            found[path] = path.read_bytes()
    return found


# ---- Finding 1: no output replaces a file the model reads --------------------

@pytest.fixture
def models(tmp_path):
    """model/ (OBJ, MTL, texture t.png, and t_0001.png that a second material
    names), gmodel/ (glTF with buffer g.bin and image img.png), links to them."""
    obj_model(tmp_path)
    model = tmp_path / "model"
    (model / "q.mtl").write_text("newmtl t\nKd 1 1 1\nmap_Kd t.png\nmap_d t_0001.png\n")
    (model / "t_0001.png").write_bytes(png([[RED]]))
    doc = gltf_quad(images=[{"uri": "img.png"}])
    blob = geometry_in(doc, "g.bin")
    gltf_model(tmp_path, doc)
    (tmp_path / "gmodel" / "g.bin").write_bytes(blob)
    (tmp_path / "gmodel" / "img.png").write_bytes(png([[GREEN]]))
    doc = json.loads((tmp_path / "s.json").read_text())
    doc["meshes"].append({"file": "model/q.obj", "translate": [0, 0, -1]})
    (tmp_path / "s.json").write_text(json.dumps(doc))
    (tmp_path / "link.png").symlink_to("model/t.png")
    os.link(model / "t.png", tmp_path / "hard.png")
    return tmp_path


INPUT_CLASHES = {
    "the image is the MTL's map_Kd": (["-o", "model/t.png"],
                                      "-o/--output model/t.png names the texture model/t.png"),
    "the image is a link to a texture": (["-o", "link.png"],
                                         "-o/--output link.png names the texture model/t.png"),
    "the image is a hard link to a texture": (["-o", "hard.png"],
                                              "-o/--output hard.png names the texture"),
    "stats is the MTL library": (["--stats", "model/q.mtl"],
                                 "--stats model/q.mtl names the material library model/q.mtl"),
    "stats is a glTF buffer": (["--stats", "gmodel/g.bin"],
                               "--stats gmodel/g.bin names the glTF buffer gmodel/g.bin"),
    "stats is a glTF image": (["--stats", "gmodel/img.png"],
                              "--stats gmodel/img.png names the texture gmodel/img.png"),
    "the work map is a texture": (["--work-map", "model/t.png"],
                                  "--work-map model/t.png names the texture"),
    "the work map's bar is a texture": (["--work-map", "w.png", "--work-map-bar", "model/t.png"],
                                        "--work-map-bar model/t.png names the texture"),
    "the schedule map is a texture": (["--schedule-map", "model/t.png"],
                                      "--schedule-map model/t.png names the texture"),
    "the flops sidecar is a buffer": (["--flops", "gmodel/g"], None),
    "frame 1 is an opacity texture": (["--frames", "1:1", "-o", "model/t.png"],
                                      "frame 1's image model/t_0001.png names the texture "
                                      "model/t_0001.png"),
}


@pytest.mark.parametrize("case", INPUT_CLASHES)
def test_no_output_may_name_a_file_the_model_reads(models, case):
    options, words = INPUT_CLASHES[case]
    if case == "the flops sidecar is a buffer":
        shutil.copy(models / "gmodel" / "g.bin", models / "gmodel" / "g.npy.json")
        (models / "gmodel" / "m.gltf").write_text(
            (models / "gmodel" / "m.gltf").read_text().replace('"g.bin"', '"g.npy.json"'))
        options, words = ["--flops", "gmodel/g.npy"], \
            "--flops (its sidecar) gmodel/g.npy.json names the glTF buffer gmodel/g.npy.json"
    if "-o" not in options:
        options = ["-o", "o.png", *options]
    before = contents(models)
    result = rtcl("-s", "s.json", *SMALL, *options, cwd=models)
    one_line(result, 2, words)
    assert "rtcl does not replace a file the run reads; give the output another name" \
        in result.stderr
    assert contents(models) == before


def test_the_dump_binary_naming_a_texture_is_refused(models):
    before = contents(models)
    result = rtcl("-s", "s.json", *SMALL, "-o", "o.png", cwd=models,
                  env={"RTCL_DUMP_BINARY": "gmodel/img.png"})
    one_line(result, 2, "RTCL_DUMP_BINARY gmodel/img.png names the texture gmodel/img.png")
    assert contents(models) == before


def test_a_texture_the_run_could_not_use_is_still_an_input(models):
    """A texture read but not decoded (missing_textures "warn") was read all the same."""
    (models / "model" / "t.png").write_text("not an image")
    doc = json.loads((models / "s.json").read_text())
    for mesh in doc["meshes"]:
        mesh["missing_textures"] = "warn"
    (models / "s.json").write_text(json.dumps(doc))
    before = contents(models)
    result = rtcl("-s", "s.json", *SMALL, "-o", "model/t.png", cwd=models)
    assert result.returncode == 2, result.stderr
    assert "-o/--output model/t.png names the texture model/t.png" in result.stderr
    assert contents(models) == before


# ---- Finding 3: files a mesh file names stay inside its folder --------------

@pytest.fixture
def outside(tmp_path):
    """tmp/outside/secret.png and secret.bin, tmp/outside/sub/, beside tmp/model."""
    folder = tmp_path / "outside"
    (folder / "sub").mkdir(parents=True)
    (folder / "secret.png").write_bytes(png([[GREEN]]))
    (folder / "secret.bin").write_bytes(b"\0" * 64)
    return folder


@pytest.mark.parametrize("case", ["a link to a file outside", "a linked folder",
                                  "a link, then ..", "an absolute name",
                                  "a name climbing out"])
def test_a_texture_outside_the_model_folder_is_refused_by_where_it_leads(tmp_path, outside,
                                                                         case):
    names = {"a link to a file outside": "lnk.png", "a linked folder": "lnk/secret.png",
             "a link, then ..": "lnk/../secret.png",
             "an absolute name": str(outside / "secret.png"),
             "a name climbing out": "sub/../../outside/secret.png"}
    name = names[case]
    obj_model(tmp_path, texture=name, write_texture=False)
    model = tmp_path / "model"
    (model / "sub").mkdir()
    if case == "a link to a file outside":
        (model / "lnk.png").symlink_to(outside / "secret.png")
    elif case == "a linked folder":
        (model / "lnk").symlink_to(outside)
    elif case == "a link, then ..":
        (model / "lnk").symlink_to(outside / "sub")
    result = rtcl("-s", "s.json", *SMALL, "-o", "o.png", cwd=tmp_path)
    one_line(result, 1, f's.json: meshes[0].file: "model/q.obj": material "t": cannot read '
             f'texture "{name}": it lies outside the folder of "q.obj"')
    assert not (tmp_path / "o.png").exists()


def test_links_and_dots_that_stay_inside_the_folder_are_followed(tmp_path):
    obj_model(tmp_path, texture="sub/../lnk.png", write_texture=False)
    model = tmp_path / "model"
    (model / "sub").mkdir()
    (model / "real.png").write_bytes(png([[RED]]))
    (model / "lnk.png").symlink_to("real.png")
    result = rtcl("-s", "s.json", *SMALL, "-o", "o.png", cwd=tmp_path)
    assert result.returncode == 0, result.stderr


@pytest.mark.parametrize("uri", ["../outside/secret.bin", "lnk.bin",
                                 "%2e%2e%2foutside%2fsecret.bin", "../outside/none.bin"])
def test_a_gltf_buffer_outside_the_model_folder_is_refused(tmp_path, outside, uri):
    doc = gltf_quad()
    (outside / "secret.bin").write_bytes(geometry_in(doc, uri))
    gltf_model(tmp_path, doc)
    (tmp_path / "gmodel" / "lnk.bin").symlink_to(outside / "secret.bin")
    result = rtcl("-s", "s.json", *SMALL, "-o", "o.png", cwd=tmp_path)
    one_line(result, 1, 's.json: meshes[0].file: cannot read "gmodel/m.gltf": it names ')
    assert 'which lies outside the folder of "m.gltf"' in result.stderr
    assert not (tmp_path / "o.png").exists()


def test_an_image_from_a_buffer_outside_the_model_folder_is_refused(tmp_path, outside):
    """A bufferView image whose buffer URI leaves the folder: the buffer is refused."""
    size = len((outside / "secret.png").read_bytes())
    doc = gltf_quad(images=[{"bufferView": 3, "mimeType": "image/png"}],
                    buffers=[{"byteLength": size, "uri": "../outside/secret.png"}])
    doc["bufferViews"].append({"buffer": 1, "byteOffset": 0, "byteLength": size})
    gltf_model(tmp_path, doc)
    result = rtcl("-s", "s.json", *SMALL, "-o", "o.png", cwd=tmp_path)
    one_line(result, 1, 'cannot read "gmodel/m.gltf": it names "gmodel/../outside/secret.png", '
             'which lies outside the folder of "m.gltf"')
    assert not (tmp_path / "o.png").exists()


# ---- Finding 4: texture names are whole --------------------------------------

def long_name(tail, length=272):
    """A relative name of `length` bytes in folders of at most 200 bytes each."""
    head = "d" * 200 + "/"
    return head + "e" * (length - len(head) - len(tail)) + tail


def test_a_texture_name_longer_than_255_bytes_is_read_whole(tmp_path):
    name = long_name("/t.png")
    assert len(name) == 272
    obj_model(tmp_path, texture=name, write_texture=False)
    (tmp_path / "model" / name).parent.mkdir(parents=True)
    (tmp_path / "model" / name).write_bytes(png([[RED]]))
    result = rtcl("-s", "s.json", "--size", "16x16", "-v", "-o", "o.ppm", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert f'texture "{name}": 1x1 8-bit sRGB' in result.stderr


def test_textures_sharing_their_first_255_bytes_stay_apart(tmp_path):
    """Two quads side by side, each a texture of its own whose names differ
    after byte 255: the left red, the right green."""
    red, green = long_name("/red.png", 300), long_name("/grn.png", 300)
    assert red[:255] == green[:255]
    model = tmp_path / "model"
    for name, colour in ((red, RED), (green, GREEN)):
        (model / name).parent.mkdir(parents=True, exist_ok=True)
        (model / name).write_bytes(png([[colour]]))
    (model / "q.obj").write_text(
        "mtllib q.mtl\nv -1 -0.5 0\nv 0 -0.5 0\nv 0 0.5 0\nv -1 0.5 0\n"
        "v 0 -0.5 0\nv 1 -0.5 0\nv 1 0.5 0\nv 0 0.5 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
        "usemtl a\nf 1/1 2/2 3/3\nf 1/1 3/3 4/4\nusemtl b\nf 5/1 6/2 7/3\nf 5/1 7/3 8/4\n")
    (model / "q.mtl").write_text(f"newmtl a\nKd 1 1 1\nmap_Kd {red}\n"
                                 f"newmtl b\nKd 1 1 1\nmap_Kd {green}\n")
    scene_file(tmp_path, "model/q.obj")
    doc = json.loads((tmp_path / "s.json").read_text())
    doc["camera"] = {"eye": [0, 0, 2], "look_at": [0, 0, 0], "fov": 53.13010235415598}
    doc["lights"] = []
    (tmp_path / "s.json").write_text(json.dumps(doc))
    result = rtcl("-s", "s.json", "--size", "32x16", "-v", "-o", "o.ppm", "--encoding",
                  "linear", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert f'texture "{red}"' in result.stderr and f'texture "{green}"' in result.stderr
    data = (tmp_path / "o.ppm").read_bytes()
    pixels = data[-32 * 16 * 3:]

    def pixel(x, y):
        return tuple(pixels[3 * (32 * y + x):3 * (32 * y + x) + 3])
    assert pixel(12, 8) == (255, 0, 0) and pixel(20, 8) == (0, 255, 0)


def test_a_texture_name_of_a_thousand_bytes_is_read(tmp_path):
    """Assimp keeps names of up to 1023 bytes; a path that long (with the
    model's folder longer still) is read."""
    name = "/".join(["f" * 240] * 4) + "/t.png"
    assert len(name) > 960
    obj_model(tmp_path, texture=name, write_texture=False)
    (tmp_path / "model" / name).parent.mkdir(parents=True)
    (tmp_path / "model" / name).write_bytes(png([[RED]]))
    result = rtcl("-s", "s.json", *SMALL, "-o", "o.ppm", cwd=tmp_path)
    assert result.returncode == 0, result.stderr


# ---- Finding 9: glTF URIs are percent-decoded --------------------------------

def test_a_percent_encoded_image_uri_is_decoded(tmp_path):
    gltf_model(tmp_path, gltf_quad(images=[{"uri": "my%20tex.png"}]))
    (tmp_path / "gmodel" / "my tex.png").write_bytes(png([[RED]]))
    result = rtcl("-s", "s.json", "--size", "16x16", "-v", "-o", "o.ppm", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert 'texture "my%20tex.png": 1x1 8-bit sRGB' in result.stderr


def test_a_percent_encoded_buffer_uri_is_decoded(tmp_path):
    doc = gltf_quad()
    blob = geometry_in(doc, "my%20buf.bin")
    gltf_model(tmp_path, doc)
    (tmp_path / "gmodel" / "my buf.bin").write_bytes(blob)
    result = rtcl("-s", "s.json", *SMALL, "-o", "o.ppm", cwd=tmp_path)
    assert result.returncode == 0, result.stderr


@pytest.mark.parametrize("uri, words", [
    ("%2e%2e%2foutside%2fsecret.png", 'it lies outside the folder of "m.gltf"'),
    ("%2E%2E/outside/secret.png", 'it lies outside the folder of "m.gltf"'),
    ("t.png%00.txt", "its URI holds an escaped NUL byte (%00)"),
])
def test_decoding_a_uri_opens_no_way_out_of_the_folder(tmp_path, outside, uri, words):
    gltf_model(tmp_path, gltf_quad(images=[{"uri": uri}]))
    (tmp_path / "gmodel" / "t.png").write_bytes(png([[RED]]))
    result = rtcl("-s", "s.json", *SMALL, "-o", "o.ppm", cwd=tmp_path)
    one_line(result, 1, f'cannot read texture "{uri}": {words}')


# ---- Finding 19: control bytes are escaped, not turned into '?' --------------

def test_control_bytes_in_a_mesh_file_name_are_escaped(tmp_path):
    scene_file(tmp_path, "m\x1b[2J.obj")
    result = rtcl("-s", "s.json", *SMALL, "-o", "o.ppm", cwd=tmp_path)
    one_line(result, 1, 'cannot read "m\\x1b[2J.obj": No such file or directory')
    assert "\x1b" not in result.stderr


def test_control_bytes_the_helper_prints_are_escaped(tmp_path):
    helper = tmp_path / "helper.sh"
    helper.write_text("#!/bin/sh\nprintf 'boom\\033[31m\\ttab\\n' >&2\nexit 3\n")
    helper.chmod(0o755)
    shutil.copy(ROOT / "test" / "meshes" / "cube.obj", tmp_path / "cube.obj")
    scene_file(tmp_path, "cube.obj")
    result = rtcl("-s", "s.json", *SMALL, "-o", "o.ppm", cwd=tmp_path,
                  env={"RTCL_MESHREAD": str(helper)})
    one_line(result, 1, "the mesh importer failed (exit status 3): boom\\x1b[31m\\ttab")
    assert "\x1b" not in result.stderr
