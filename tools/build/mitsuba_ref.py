#!/usr/bin/env python3
"""Renders an rtcl path-tracing scene with Mitsuba 3, the independent oracle of
issue 40, and writes the reference image as data (docs/oracle.md).

    python3 tools/build/mitsuba_ref.py SCENE.json -o test/oracle/refs/NAME.npz \\
        [--spp N] [--batches K] [--size WxH] [--threads T] [--aov albedo] [--approximate]

The scene is read by this script's own reading of docs/SCENE.md, not by rtcl,
and turned into a Mitsuba scene by the rules of docs/oracle.md ("Mappings"):
the same triangles (OBJ files parsed here, placed by scale, rotate, translate)
and spheres, the same pinhole camera (fov_axis "y", a box pixel filter), the
same BSDFs (GGX alpha = roughness^2; the Schlick conductor as Mitsuba's
`principled` with metallic 1; rtcl's principled as Mitsuba blendbsdf
mixtures of that, `roughdielectric` and the BSDF `gltf` below), emission on
the front side, `background` as a uniform environment, the environment map
sampled finely enough to keep its integral, the thin lens as Mitsuba's
thinlens, glTF 2.0 triangles read here. What it cannot map exactly is
refused with a message, never approximated silently; --approximate
(Scene(approximate=True), for issue 41's speed comparison only, never for a
reference) maps planes as 1000-unit squares and glTF textures and cut-outs
approximately (docs/oracle.md, "Approximations").

The N samples a pixel are rendered as K batches of N/K, each with its own seed
of Mitsuba's independent sampler. The output (.npz) holds
  image            float32 H x W x 3, linear radiance, rows from the top: the mean
  block_sample_std float32 H/8 x W/8 x 3: the standard deviation of ONE sample's
                   contribution to the mean of an 8 x 8 block, estimated from the
                   spread of the K batches' block means (std x sqrt(64 N/K)); a
                   renderer's block mean at n samples a pixel then has the Monte
                   Carlo error block_sample_std / sqrt(64 n)
  meta             a JSON string: the scene, its SHA-256, spp, batches, Mitsuba's
                   version and variant, the command, seconds taken
Needs `pip install mitsuba` (tools/requirements-oracle.txt); rtcl's tests do
not: they read the committed .npz files.
"""
import argparse
import hashlib
import json
import math
import os
import pathlib
import sys
import tempfile
import time

import numpy as np

BLOCK = 8


class SceneError(Exception):
    """A scene this script cannot turn into the same Mitsuba scene."""


# ---------------------------------------------------------------- the scene

def vec(value, where):
    if not (isinstance(value, list) and len(value) == 3
            and all(isinstance(c, (int, float)) for c in value)):
        raise SceneError(f"{where}: expected three numbers, got {value!r}")
    return [float(c) for c in value]


def rotation(degrees):
    """SCENE.md's meshes[i].rotate: degrees about x, then y, then z (world axes)."""
    ax, ay, az = (math.radians(d) for d in degrees)
    rx = np.array([[1, 0, 0], [0, math.cos(ax), -math.sin(ax)], [0, math.sin(ax), math.cos(ax)]])
    ry = np.array([[math.cos(ay), 0, math.sin(ay)], [0, 1, 0], [-math.sin(ay), 0, math.cos(ay)]])
    rz = np.array([[math.cos(az), -math.sin(az), 0], [math.sin(az), math.cos(az), 0], [0, 0, 1]])
    return rz @ ry @ rx


def read_obj(path, uvs=None):
    """The triangles of an OBJ file by material name: {name: [[v0, v1, v2], ...]}.
    Polygons are fanned from their first vertex, as Assimp triangulates a convex
    polygon; faces before the first `usemtl` have the material None. With a
    dict `uvs`, each material's texture coordinates go there too ({name:
    [[uv0, uv1, uv2], ...]}, (0, 0) where a face vertex has none, as rtcl
    reads them); without, a file with texture coordinates is refused."""
    vertices, texcoords, groups, material = [], [], {}, None
    for number, line in enumerate(path.read_text().splitlines(), 1):
        fields = line.split()
        if not fields or fields[0].startswith("#"):
            continue
        if fields[0] == "v":
            vertices.append([float(c) for c in fields[1:4]])
        elif fields[0] == "vt":
            if uvs is None:
                raise SceneError(f"{path}:{number}: texture coordinates are not mapped "
                                 "(give untextured meshes)")
            texcoords.append([float(c) for c in fields[1:3]])
        elif fields[0] == "usemtl":
            material = fields[1]
        elif fields[0] == "f":
            index, uv = [], []
            for field in fields[1:]:
                parts = field.split("/")
                i = int(parts[0])
                index.append(i - 1 if i > 0 else len(vertices) + i)
                if len(parts) > 1 and parts[1]:
                    t = int(parts[1])
                    uv.append(texcoords[t - 1 if t > 0 else len(texcoords) + t])
                else:
                    uv.append([0.0, 0.0])
            for k in range(1, len(index) - 1):
                groups.setdefault(material, []).append(
                    [vertices[index[0]], vertices[index[k]], vertices[index[k + 1]]])
                if uvs is not None:
                    uvs.setdefault(material, []).append([uv[0], uv[k], uv[k + 1]])
        elif fields[0] == "vn":
            raise SceneError(f"{path}:{number}: vertex normals are not mapped "
                             "(give flat meshes)")
        elif fields[0] not in ("o", "g", "s", "mtllib"):
            raise SceneError(f"{path}:{number}: unknown OBJ statement {fields[0]!r}")
    return groups


def read_mtl(obj_path):
    """The materials of an OBJ's `mtllib` files: {name: {statement: fields}}."""
    materials, current = {}, None
    for line in obj_path.read_text().splitlines():
        fields = line.split()
        if not fields or fields[0] != "mtllib":
            continue
        for library in fields[1:]:
            for row in (obj_path.parent / library).read_text().splitlines():
                words = row.split()
                if not words or words[0].startswith("#"):
                    continue
                if words[0] == "newmtl":
                    current = materials.setdefault(words[1], {})
                elif current is not None:
                    current[words[0]] = words[1:]
    return materials


def mtl_material(obj_path, name, fields, where):
    """An OBJ material that the file gives (not replaced by the scene) as an
    rtcl material of the oracle's own kind "mtl_diffuse": RENDERING.md's
    mapped BSDF for an opaque material without reflection (d 1, illum 0, 1
    or 2) is the diffuse lobe rho = min(1, Kd (x) map_Kd's texture); anything
    else (dissolve, reflection, emission, options of map_Kd) is refused."""
    known = {"Kd", "Ka", "Ks", "Ns", "map_Kd", "illum", "d", "Tr", "Ni"}
    extra = set(fields) - known
    if extra:
        raise SceneError(f"{where}: MTL statements the oracle does not map: {sorted(extra)}")
    d = float(fields.get("d", ["1"])[0])
    if "Tr" in fields:
        d = 1 - float(fields["Tr"][0])
    illum = int(fields.get("illum", ["2"])[0])
    if d != 1 or illum > 2:
        raise SceneError(f"{where}: only opaque MTL materials without reflection (d 1, "
                         "illum 0 ... 2) are mapped")
    kd = [float(c) for c in fields.get("Kd", ["0.6", "0.6", "0.6"])]
    texture = None
    if "map_Kd" in fields:
        if len(fields["map_Kd"]) != 1:
            raise SceneError(f"{where}: map_Kd options are not mapped")
        texture = obj_path.parent / fields["map_Kd"][0]
    return {"mtl_diffuse": {"kd": kd, "texture": texture}}


def read_ply(path):
    """The triangles of a binary little-endian PLY file of float x, y, z vertices
    and uchar-counted int faces (tools/rtcl_tools/ply.py's layout, which
    rtcl-genbench and blob.py write) as an N x 3 x 3 array; other PLY files
    are refused."""
    data = path.read_bytes()
    end = data.find(b"end_header\n")
    if not data.startswith(b"ply\n") or end < 0:
        raise SceneError(f"{path}: not a PLY file")
    lines = [line for line in data[:end].decode("ascii").splitlines()
             if not line.startswith("comment")]
    expected_props = ["property float x", "property float y", "property float z"]
    if (lines[1] != "format binary_little_endian 1.0" or not lines[2].startswith("element vertex")
            or lines[3:6] != expected_props or not lines[6].startswith("element face")
            or lines[7] not in ("property list uchar int vertex_indices",
                                "property list uchar int vertex_index")
            or len(lines) != 8):
        raise SceneError(f"{path}: the oracle reads binary little-endian PLY files of float "
                         "x, y, z vertices and triangles only")
    vertex_count, face_count = int(lines[2].split()[2]), int(lines[6].split()[2])
    start = end + len(b"end_header\n")
    vertices = np.frombuffer(data, "<f4", 3 * vertex_count, start).reshape(-1, 3)
    faces = np.frombuffer(data, np.dtype([("n", "u1"), ("i", "<i4", 3)]), face_count,
                          start + 12 * vertex_count)
    if face_count and (faces["n"] != 3).any():
        raise SceneError(f"{path}: the oracle reads triangles only")
    return vertices.astype(np.float64)[faces["i"]]


PLANE_SIZE = 1000.0   # the side of an approximate plane's square, world units


def read_gltf(path, uvs, materials):
    """The triangles of a glTF 2.0 .gltf file by material name, as read_obj
    gives them: every primitive (mode 4, triangles) of every mesh of the
    default scene's nodes, which must carry no transform; POSITION, indices
    and TEXCOORD_0 read from the buffers (data: URIs or files beside it); v
    given as rtcl reads it, 1 - v (Assimp turns glTF's downward v). The
    materials go into `materials` ({name: the glTF material, with the folder
    and the document for its textures}); a primitive without one is refused."""
    import base64
    doc = json.loads(path.read_text())
    if not doc.get("asset", {}).get("version", "").startswith("2."):
        raise SceneError(f"{path}: the oracle reads glTF 2.0 files only")

    def load(uri):
        if uri.startswith("data:"):
            return base64.b64decode(uri.split(",", 1)[1])
        return (path.parent / uri).read_bytes()
    buffers = [load(b["uri"]) for b in doc["buffers"]]

    def accessor(index):
        acc = doc["accessors"][index]
        view = doc["bufferViews"][acc["bufferView"]]
        kinds = {5126: "<f4", 5125: "<u4", 5123: "<u2", 5121: "u1"}
        if acc["componentType"] not in kinds or acc.get("sparse") or acc.get("normalized"):
            raise SceneError(f"{path}: accessor {index}: not read by the oracle")
        width = {"SCALAR": 1, "VEC2": 2, "VEC3": 3}[acc["type"]]
        dtype = np.dtype(kinds[acc["componentType"]])
        stride = view.get("byteStride", 0) or width * dtype.itemsize
        if stride != width * dtype.itemsize:
            raise SceneError(f"{path}: accessor {index}: interleaved buffers are not read")
        start = view.get("byteOffset", 0) + acc.get("byteOffset", 0)
        data = np.frombuffer(buffers[view["buffer"]], dtype, width * acc["count"], start)
        return data.reshape(acc["count"], width).astype(np.float64 if width > 1 else np.int64)

    groups = {}
    scene = doc["scenes"][doc.get("scene", 0)]
    for n in scene["nodes"]:
        node = doc["nodes"][n]
        if set(node) & {"matrix", "translation", "rotation", "scale", "children"}:
            raise SceneError(f"{path}: node {n}: transforms and children are not mapped")
        for prim in doc["meshes"][node["mesh"]]["primitives"]:
            if prim.get("mode", 4) != 4 or "material" not in prim:
                raise SceneError(f"{path}: the oracle reads triangle primitives with a "
                                 "material only")
            positions = accessor(prim["attributes"]["POSITION"])
            index = (accessor(prim["indices"])[:, 0] if "indices" in prim
                     else np.arange(len(positions)))
            index = index.reshape(-1, 3)
            material = doc["materials"][prim["material"]]
            name = material.get("name", "#")
            materials[name] = dict(material, folder=path.parent, document=doc, file=path,
                                   load=load)
            groups.setdefault(name, []).extend(positions[index].tolist())
            if "TEXCOORD_0" in prim.get("attributes", {}):
                uv = accessor(prim["attributes"]["TEXCOORD_0"])
                uv[:, 1] = 1.0 - uv[:, 1]
                uvs.setdefault(name, []).extend(uv[index].tolist())
            else:
                uvs.setdefault(name, []).extend(np.zeros((len(index), 3, 2)).tolist())
    return groups


class Scene:
    """An rtcl scene (docs/SCENE.md) as far as the oracle maps it."""

    KNOWN = {"format", "version", "image", "camera", "background", "max_depth", "materials",
             "spheres", "meshes", "triangles", "integrator", "environment", "epsilon",
             "lights", "planes", "ambient"}

    def __init__(self, path, approximate=False, plane_size=PLANE_SIZE):
        """approximate: False refuses what has no exact mapping (the oracle);
        True maps it approximately (pt_mitsuba.py's speed comparison only):
        each plane as a plane_size x plane_size square about its point, which
        differs from rtcl's infinite plane near the horizon, and a glTF
        material's base colour texture and cut-out as gltf_material says."""
        self.path = pathlib.Path(path)
        self.doc = json.loads(self.path.read_text())
        self.approximate = approximate
        self.approximate_planes = plane_size if approximate else None
        unknown = set(self.doc) - self.KNOWN
        if unknown:
            raise SceneError(f"{path}: keys the oracle does not map: {sorted(unknown)}")
        if self.doc.get("planes") and not approximate:
            raise SceneError(f"{path}: planes: not mapped (infinite; give triangles)")
        if self.doc.get("integrator", "whitted") != "path":
            raise SceneError(f'{path}: integrator: the oracle renders "path" scenes only')
        self.materials = self.doc.get("materials", {})

    def material(self, ref, where):
        if isinstance(ref, str):
            if ref not in self.materials:
                raise SceneError(f"{where}: unknown material {ref!r}")
            return ref, self.materials[ref]
        if isinstance(ref, dict):
            return None, ref
        raise SceneError(f"{where}: a material must be named or given, got {ref!r}")

    def shapes(self):
        """Yields (kind, geometry, (name, material), where): kind "sphere" with
        (center, radius) or "triangles" with an N x 3 x 3 float64 array."""
        for i, sphere in enumerate(self.doc.get("spheres", [])):
            where = f"spheres[{i}]"
            if "material" not in sphere:
                raise SceneError(f"{where}: give a material with a bsdf")
            yield ("sphere", (vec(sphere["center"], where), float(sphere["radius"])),
                   self.material(sphere["material"], where), where)
        for i, tri in enumerate(self.doc.get("triangles", [])):
            where = f"triangles[{i}]"
            geometry = np.array([vec(v, where) for v in tri["vertices"]])[None]
            yield "triangles", geometry, self.material(tri["material"], where), where
        for i, mesh in enumerate(self.doc.get("meshes", [])):
            yield from self.mesh_shapes(i, mesh)
        for i, plane in enumerate(self.doc.get("planes", [])):
            yield self.plane_square(i, plane)

    def plane_square(self, i, plane):
        """An approximation: plane i as a square of side approximate_planes about
        its point, two triangles facing its normal, with texture coordinates
        laid for Mitsuba's checkerboard (mitsuba_checker): RENDERING.md's (s,
        t), the world coordinates without the axis of the normal's largest
        |component|, over twice the checker's size, so that Mitsuba's squares
        (u mod 1 < 0.5 against v mod 1 < 0.5) are rtcl's floor(s/size) +
        floor(t/size) parity."""
        where = f"planes[{i}]"
        extra = set(plane) - {"point", "normal", "material", "checker"}
        if extra:
            raise SceneError(f"{where}: keys the oracle does not map: {sorted(extra)}")
        if "material" not in plane:
            raise SceneError(f"{where}: give a material with a bsdf")
        point = np.array(vec(plane["point"], where + ".point"))
        normal = np.array(vec(plane["normal"], where + ".normal"))
        normal /= np.linalg.norm(normal)
        helper = np.array([1.0, 0, 0]) if abs(normal[0]) < 0.9 else np.array([0, 1.0, 0])
        a = np.cross(normal, helper)
        a /= np.linalg.norm(a)
        b = np.cross(normal, a)           # (a, b, normal) right-handed
        h = 0.5 * float(self.approximate_planes)
        corners = [point + h * (x * a + y * b) for x, y in ((-1, -1), (1, -1), (1, 1), (-1, 1))]
        tri = np.array([[corners[0], corners[1], corners[2]],
                        [corners[0], corners[2], corners[3]]])
        name, material = self.material(plane["material"], where + ".material")
        material = dict(material)
        if "checker" in plane:
            checker = plane["checker"]
            size = float(checker["size"])
            if size <= 0:
                raise SceneError(f"{where}.checker.size: must be > 0")
            drop = int(np.argmax(np.abs(normal)))   # ties: x before y before z
            keep = [k for k in range(3) if k != drop]
            uv = tri[..., keep] / (2 * size)
            uv[..., 1] = 1.0 - uv[..., 1]           # write_ply writes 1 - v
            material["checker"] = vec(checker["color"], where + ".checker.color")
            return "triangles", (tri, uv), (None, material), where
        return "triangles", tri, (name, material), where

    def mesh_shapes(self, i, mesh):
        where = f"meshes[{i}]"
        extra = set(mesh) - {"file", "material", "materials", "scale", "rotate", "translate",
                             "smooth"}
        if extra:
            raise SceneError(f"{where}: keys the oracle does not map: {sorted(extra)}")
        if mesh.get("smooth", True):
            raise SceneError(f'{where}: give "smooth": false (the oracle maps flat meshes)')
        file = self.path.parent / mesh["file"]
        if file.suffix.lower() not in (".obj", ".ply", ".gltf"):
            raise SceneError(f"{where}.file: the oracle reads OBJ, PLY and .gltf files only")
        scale = mesh.get("scale", 1)
        scale = np.array([float(scale)] * 3 if isinstance(scale, (int, float))
                         else vec(scale, where + ".scale"))
        turn = rotation(vec(mesh.get("rotate", [0, 0, 0]), where + ".rotate"))
        shift = np.array(vec(mesh.get("translate", [0, 0, 0]), where + ".translate"))
        mirror = np.prod(np.sign(scale)) < 0
        uvs, file_materials = {}, {}
        if file.suffix.lower() == ".ply":
            if "material" not in mesh:
                raise SceneError(f"{where}: a PLY file has no materials: give \"material\"")
            groups = {None: read_ply(file)}
        elif file.suffix.lower() == ".gltf":
            groups = read_gltf(file, uvs, file_materials)
            file_materials = {name: {"gltf_material": m, "approximate": self.approximate}
                              for name, m in file_materials.items()}
        else:
            groups = read_obj(file, uvs)
            file_materials = read_mtl(file)
        for name, triangles in groups.items():
            if "material" in mesh:
                ref = self.material(mesh["material"], f"{where}.material")
            elif name in mesh.get("materials", {}):
                ref = self.material(mesh["materials"][name], f"{where}.materials.{name}")
            elif name in file_materials and "gltf_material" in file_materials[name]:
                ref = (f"{file}#{name}", file_materials[name])
            elif name in file_materials:
                # The file's own material: its texture coordinates are used.
                ref = (f"{file}#{name}", mtl_material(file, name, file_materials[name],
                                                      f"{file}: material {name!r}"))
            else:
                raise SceneError(f"{where}: the file's material {name!r} needs a scene "
                                 "material with a bsdf (meshes[i].materials)")
            tri = np.array(triangles, dtype=np.float64) * scale
            tri = tri @ turn.T + shift
            uv = np.array(uvs[name], dtype=np.float64) if name in uvs else None
            if mirror:
                tri = tri[:, ::-1]
                uv = uv[:, ::-1] if uv is not None else None
            if "mtl_diffuse" in ref[1] or "gltf_material" in ref[1]:
                yield "triangles", (tri, uv), ref, where
            else:
                yield "triangles", tri, ref, where


# ---------------------------------------------------------------- the mapping

def rgb(value, where):
    return {"type": "rgb", "value": vec(value, where)}


def number_in(material, key, default, where, low=0.0, high=1.0):
    value = float(material.get(key, default))
    if not low <= value <= high:
        raise SceneError(f"{where}.{key}: must be in [{low}, {high}], got {value}")
    return value


def mitsuba_checker(material, where):
    """A plane's checker on its diffuse material (RENDERING.md, trace step 3:
    odd squares take min(1, checker.color) for the reflectance) as Mitsuba's
    checkerboard over the square's texture coordinates (Scene.plane_square)."""
    bsdf = material.get("bsdf", {})
    if bsdf.get("type") != "diffuse":
        raise SceneError(f"{where}: the oracle maps checkers on diffuse materials only")
    return {"type": "twosided", "bsdf": {"type": "diffuse", "reflectance": {
        "type": "checkerboard",
        "color0": rgb(bsdf.get("reflectance", [0.5] * 3), where + ".bsdf.reflectance"),
        "color1": rgb(list(np.minimum(material["checker"], 1.0)), where + ".checker.color")}}}


def gltf_image(material, texture_info):
    """The RGBA texels of a glTF texture as floats 0 ... 1 (rows from the top)."""
    import mitsuba as mi
    doc = material["document"]
    texture = doc["textures"][texture_info["index"]]
    sampler = doc["samplers"][texture["sampler"]] if "sampler" in texture else {}
    if sampler.get("wrapS", 10497) != 10497 or sampler.get("wrapT", 10497) != 10497 \
            or texture_info.get("texCoord", 0) or texture_info.get("extensions"):
        raise SceneError(f"{material['file']}: textures other than repeated TEXCOORD_0 "
                         "ones are not mapped")
    image = doc["images"][texture["source"]]
    data = material["load"](image["uri"])
    path = pathlib.Path(tempfile.mkdtemp(prefix="mitsuba_ref.")) / "texture.png"
    path.write_bytes(data)
    bitmap = mi.Bitmap(str(path)).convert(mi.Bitmap.PixelFormat.RGBA, mi.Struct.Type.UInt8,
                                          srgb_gamma=True)
    return np.array(bitmap, dtype=np.float64) / 255.0


def gltf_material(material, where):
    """A glTF metallic-roughness material (RENDERING.md, "Metallic-roughness
    materials") as rtcl's principled BSDF. Exact without textures; with a base
    colour texture or a MASK cut-out only when approximations are allowed
    (Scene(approximate=True)): the texture as its mean linear colour over the
    texels not cut out (a constant base colour), and the cut-out as Mitsuba's
    `mask` of a binary opacity: the texture's alpha filtered bilinearly
    (repeated, texel centres at half-integers) at 8 times its resolution and
    compared with the cutoff, looked up without filtering (rtcl filters the
    alpha at the hit itself: the edges differ within 1/16 of a texel)."""
    import mitsuba as mi
    pbr = material.get("pbrMetallicRoughness")
    if pbr is None or set(material) & {"normalTexture", "emissiveTexture", "occlusionTexture",
                                       "extensions", "emissiveFactor"}:
        raise SceneError(f"{where}: the oracle maps plain glTF metallic-roughness materials")
    factor = np.array(pbr.get("baseColorFactor", [1, 1, 1, 1]), dtype=np.float64)
    mode = material.get("alphaMode", "OPAQUE")
    if mode == "BLEND" or "metallicRoughnessTexture" in pbr:
        raise SceneError(f"{where}: alphaMode BLEND and metallic-roughness textures "
                         "are not mapped")
    cutoff = float(material.get("alphaCutoff", 0.5)) if mode == "MASK" else 0.0
    texels = None
    if "baseColorTexture" in pbr or cutoff > 0:
        if not material["approximate"]:
            raise SceneError(f"{where}: glTF base colour textures and cut-outs are mapped "
                             "approximately only (docs/oracle.md)")
    if "baseColorTexture" in pbr:
        texels = gltf_image(material, pbr["baseColorTexture"])
    base = factor[:3]
    if texels is not None:
        code = texels[..., :3]
        linear = np.where(code <= 0.04045, code / 12.92, ((code + 0.055) / 1.055) ** 2.4)
        kept = texels[..., 3] * factor[3] >= cutoff if cutoff > 0 else np.ones(code.shape[:2], bool)
        base = base * linear[kept].mean(axis=0)
    bsdf = principled({"base_color": list(np.minimum(base, 1.0)),
                       "metallic": float(pbr.get("metallicFactor", 1.0)),
                       "roughness": float(pbr.get("roughnessFactor", 1.0))}, where)
    if cutoff <= 0:
        return bsdf
    alpha = (texels[..., 3] if texels is not None else np.ones((1, 1))) * factor[3]
    h, w = alpha.shape
    up = 8
    y = (np.arange(up * h) + 0.5) / up - 0.5          # fine sample in texel units
    x = (np.arange(up * w) + 0.5) / up - 0.5
    y0, x0 = np.floor(y).astype(int), np.floor(x).astype(int)
    fy, fx = (y - y0)[:, None], (x - x0)[None, :]
    a = lambda j, i: alpha[np.ix_(j % h, i % w)]
    filtered = ((1 - fy) * ((1 - fx) * a(y0, x0) + fx * a(y0, x0 + 1))
                + fy * ((1 - fx) * a(y0 + 1, x0) + fx * a(y0 + 1, x0 + 1)))
    opacity = (filtered >= cutoff).astype(np.float32)[..., None]
    return {"type": "mask", "bsdf": bsdf,
            "opacity": {"type": "bitmap", "bitmap": mi.Bitmap(opacity), "raw": True,
                        "filter_type": "nearest", "wrap_mode": "repeat"}}


def mitsuba_bsdf(material, where):
    """The Mitsuba BSDF of an rtcl material's "bsdf" (docs/oracle.md, "Mappings")."""
    if "checker" in material:
        return mitsuba_checker(material, where)
    if "gltf_material" in material:
        return gltf_material(dict(material["gltf_material"],
                                  approximate=material["approximate"]), where)
    if "mtl_diffuse" in material:
        return {"type": "twosided", "bsdf": mtl_diffuse(material["mtl_diffuse"])}
    if "bsdf" not in material:
        raise SceneError(f"{where}: the oracle maps materials with a \"bsdf\" only")
    bsdf = material["bsdf"]
    kind = bsdf.get("type")
    where = where + ".bsdf"
    if kind == "diffuse":
        inner = {"type": "diffuse",
                 "reflectance": rgb(bsdf.get("reflectance", [0.5] * 3), where)}
    elif kind == "conductor":
        # Schlick's Fresnel with F0 = reflectance, GGX alpha = roughness^2: exactly
        # Mitsuba's principled with metallic 1 (its calc_schlick(base_color, wi.m)),
        # whose alpha is max(0.001, roughness^2).
        inner = {"type": "principled",
                 "base_color": rgb(bsdf.get("reflectance", [1.0] * 3), where),
                 "metallic": 1.0,
                 "roughness": number_in(bsdf, "roughness", 0, where)}
    elif kind == "dielectric":
        ior = float(bsdf.get("ior", 1.5))
        roughness = number_in(bsdf, "roughness", 0, where)
        if roughness == 0:
            return {"type": "dielectric", "int_ior": ior, "ext_ior": 1.0}
        return {"type": "roughdielectric", "distribution": "ggx", "alpha": roughness ** 2,
                "int_ior": ior, "ext_ior": 1.0, "sample_visible": True}
    elif kind == "principled":
        return principled(bsdf, where)
    else:
        raise SceneError(f"{where}.type: unknown BSDF {kind!r}")
    # rtcl's opaque BSDFs reflect on both sides of a surface; Mitsuba's on the
    # front only unless wrapped.
    return {"type": "twosided", "bsdf": inner}


def mtl_diffuse(mtl):
    """The diffuse lobe of an MTL material (mtl_material): rho = min(1, Kd (x) T).
    The texture is decoded here as rtcl decodes it (RENDERING.md, "Textures":
    8-bit sRGB through the inverse sRGB curve, rows from the top) and scaled
    by Kd, then given to Mitsuba as a linear float bitmap filtered bilinearly
    with texel centres at half-integers and repeated, as rtcl filters it; its
    v = 0 is the top row, so the meshes' v is written as 1 - v (write_ply)."""
    import mitsuba as mi
    kd = np.array(mtl["kd"], dtype=np.float64)
    if mtl["texture"] is None:
        return {"type": "diffuse", "reflectance": rgb(list(np.minimum(kd, 1.0)), "Kd")}
    bitmap = mi.Bitmap(str(mtl["texture"])).convert(
        mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.UInt8, srgb_gamma=True)
    code = np.array(bitmap, dtype=np.float64) / 255.0
    linear = np.where(code <= 0.04045, code / 12.92, ((code + 0.055) / 1.055) ** 2.4)
    texels = np.minimum(linear.astype(np.float32) * kd, 1.0).astype(np.float32)
    return {"type": "diffuse",
            "reflectance": {"type": "bitmap", "bitmap": mi.Bitmap(texels), "raw": True,
                            "filter_type": "bilinear", "wrap_mode": "repeat"}}


def principled(bsdf, where):
    """RENDERING.md's principled BSDF, f = m f_metal + (1 - m) t f_glass +
    (1 - m)(1 - t) f_plastic, as Mitsuba blendbsdf mixtures (whose sample
    weight and pdf are the mixture's): f_metal the Schlick conductor above,
    f_glass Mitsuba's roughdielectric with its transmission tinted by the base
    colour, f_plastic the BSDF "gltf" (glTF's fresnel_mix, below). alpha =
    max(roughness^2, 0.001) for all three, as rtcl clamps it."""
    base = vec(bsdf.get("base_color", [1, 1, 1]), where + ".base_color")
    metallic = number_in(bsdf, "metallic", 0, where)
    roughness = number_in(bsdf, "roughness", 0.5, where)
    transmission = number_in(bsdf, "transmission", 0, where)
    ior = float(bsdf.get("ior", 1.5))
    alpha = max(roughness ** 2, 0.001)
    register_gltf()
    plastic = {"type": "twosided", "bsdf": {"type": "gltf", "base_color": base,
                                            "alpha": alpha, "ior": ior}}
    glass = {"type": "roughdielectric", "distribution": "ggx", "alpha": alpha,
             "int_ior": ior, "ext_ior": 1.0, "sample_visible": True,
             "specular_transmittance": rgb(base, where + ".base_color")}
    metal = {"type": "twosided", "bsdf": {
        "type": "principled", "base_color": rgb(base, where + ".base_color"),
        "metallic": 1.0, "roughness": math.sqrt(alpha)}}
    dielectric = plastic
    if transmission > 0:
        dielectric = {"type": "blendbsdf", "weight": transmission,
                      "bsdf_0": plastic, "bsdf_1": glass}
    if metallic == 0:
        return dielectric
    if metallic == 1:
        return metal
    return {"type": "blendbsdf", "weight": metallic, "bsdf_0": dielectric, "bsdf_1": metal}


def mitsuba_light(light, where):
    """SCENE.md's lights under "path": a point light's color is its intensity
    (Mitsuba's `point`), a directional light's its irradiance (`directional`,
    `direction` the way the light travels in both). Sphere lights and
    directional lights with an angle are refused: rtcl's are not seen by rays
    and block nothing, which no Mitsuba emitter of a finite size matches."""
    extra = set(light) - {"position", "direction", "color", "radius", "angle"}
    if extra:
        raise SceneError(f"{where}: keys the oracle does not map: {sorted(extra)}")
    color = rgb(light.get("color", [1, 1, 1]), where + ".color")
    if light.get("radius", 0) or light.get("angle", 0):
        raise SceneError(f"{where}: sphere lights and directional lights with an angle "
                         "are not mapped (docs/oracle.md)")
    if "position" in light:
        return {"type": "point", "position": vec(light["position"], where + ".position"),
                "intensity": color}
    return {"type": "directional", "direction": vec(light["direction"], where + ".direction"),
            "irradiance": color}


def mitsuba_scene(scene, spp, width=None, height=None, aov=None):
    import mitsuba as mi
    doc = scene.doc
    image = doc.get("image", {})
    width = width or image.get("width", 640)
    height = height or image.get("height", 480)
    camera = doc["camera"]
    eye = vec(camera["eye"], "camera.eye")
    look_at = vec(camera["look_at"], "camera.look_at")
    up = vec(camera.get("up", [0, 1, 0]), "camera.up")
    aperture = float(camera.get("aperture", 0))
    if aperture < 0:
        raise SceneError(f"camera.aperture: must be >= 0, got {aperture}")
    # rtcl's max_depth counts the bounces after the first hit (0: direct light);
    # Mitsuba's counts path segments (1: emitters seen, 2: direct light).
    max_depth = int(doc.get("max_depth", 5)) + 2
    out = {
        "type": "scene",
        "integrator": ({"type": "aov", "aovs": "albedo:albedo"} if aov else
                       {"type": "path", "max_depth": max_depth, "hide_emitters": False}),
        "sensor": {
            "type": "perspective",
            "fov_axis": "y",
            "fov": float(camera.get("fov", 45)),
            "near_clip": 1e-4,
            "far_clip": 1e6,
            "to_world": mi.ScalarTransform4f().look_at(origin=eye, target=look_at, up=up),
            "sampler": {"type": "independent", "sample_count": spp},
            "film": {"type": "hdrfilm", "width": width, "height": height,
                     "rfilter": {"type": "box"}, "pixel_format": "rgb",
                     "component_format": "float32"},
        },
    }
    if aperture > 0:
        # RENDERING.md's thin lens: rays from a disk of radius A about the eye,
        # through the pinhole ray's point on the plane at F along the view
        # direction; Mitsuba's thinlens (concentric disk sampling too) is that.
        focus = float(camera.get("focus_distance",
                                 np.linalg.norm(np.subtract(look_at, eye))))
        if focus <= 0:
            raise SceneError(f"camera.focus_distance: must be > 0, got {focus}")
        out["sensor"].update(type="thinlens", aperture_radius=aperture, focus_distance=focus)
    background = vec(doc.get("background", [0, 0, 0]), "background")
    if "environment" in doc:
        out["background"] = environment(doc["environment"], scene.path.parent)
    elif any(background):
        out["background"] = {"type": "constant", "radiance": rgb(background, "background")}
    for i, light in enumerate(doc.get("lights", [])):
        out[f"light{i}"] = mitsuba_light(light, f"lights[{i}]")
    tmp = tempfile.mkdtemp(prefix="mitsuba_ref.")
    bsdfs = {}
    for k, (kind, geometry, (name, material), where) in enumerate(scene.shapes()):
        if name is None:                       # an inline material: its own BSDF
            bsdf = mitsuba_bsdf(material, where)
        else:
            if name not in bsdfs:
                bsdfs[name] = mitsuba_bsdf(material, f"materials.{name}")
            bsdf = bsdfs[name]
        shape = {"bsdf": bsdf}
        if any(material.get("emission", [0, 0, 0])):
            shape["emitter"] = {"type": "area", "radiance": rgb(material["emission"], where)}
        if kind == "sphere":
            shape.update(type="sphere", center=geometry[0], radius=geometry[1])
        else:
            ply = pathlib.Path(tmp) / f"shape{k}.ply"
            if isinstance(geometry, tuple):         # an MTL material's, with its uv
                write_ply(ply, *geometry)
            else:
                write_ply(ply, geometry)
            shape.update(type="ply", filename=str(ply), face_normals=True)
        out[f"shape{k}"] = shape
    return out


ENV_UPSAMPLE = 8


def environment(env, folder):
    """RENDERING.md's environment map as Mitsuba's `envmap`. rtcl's map is
    constant over each texel (j, k), u in [j/W, (j+1)/W), v in [k/H, (k+1)/H),
    and its u = 0.5 looks along -z; Mitsuba's interpolates bilinearly between
    samples at u = (c + 0.5)/W' (its u = 0 along -z: rtcl's u is Mitsuba's u -
    0.5) and v = r/(H' - 1). Mitsuba gets a grid ENV_UPSAMPLE times finer, W' =
    U W columns and H' = U H + 1 rows, so that each of rtcl's texel edges lies
    midway between two columns or exactly on a row; a row on an edge holds the
    mean of the texels on either side. Mitsuba's map then differs from rtcl's
    only within 1/(2U) of a texel of its edges, where it ramps linearly from one
    texel to the next, and has the same integral over each texel's rows and
    columns (up to the change of sin(theta) across 1/U of a texel). `rotate`
    is the same right-handed turn about +y in both."""
    import mitsuba as mi
    extra = set(env) - {"file", "scale", "rotate"}
    if extra:
        raise SceneError(f"environment: keys the oracle does not map: {sorted(extra)}")
    texels = read_hdr(folder / env["file"])
    height, width, _ = texels.shape
    u = ((np.arange(ENV_UPSAMPLE * width) + 0.5) / (ENV_UPSAMPLE * width) - 0.5) % 1.0
    columns = texels[:, np.minimum(width - 1, np.floor(width * u).astype(int))]
    rows = []
    for r in range(ENV_UPSAMPLE * height + 1):
        k, on_edge = divmod(r, ENV_UPSAMPLE)
        if on_edge:                                    # inside texel row k
            rows.append(columns[k])
        else:                                          # on the edge above row k
            rows.append(0.5 * (columns[max(k - 1, 0)] + columns[min(k, height - 1)]))
    image = np.array(rows, dtype=np.float32)
    return {"type": "envmap", "bitmap": mi.Bitmap(image),
            "scale": float(env.get("scale", 1.0)),
            "to_world": mi.ScalarTransform4f().rotate([0, 1, 0], float(env.get("rotate", 0)))}


def read_hdr(path):
    """A Radiance RGBE file (flat or run-length encoded scanlines, -Y H +X W) as
    an H x W x 3 float64 array, row 0 at the top; a texel is m * 2^(e - 136)
    (e > 0), as stb_image and rtcl decode it, without Radiance's own + 0.5."""
    data = pathlib.Path(path).read_bytes()
    if not data.startswith(b"#?"):
        raise SceneError(f"{path}: not a Radiance HDR file")
    end = data.index(b"\n\n") + 2
    line_end = data.index(b"\n", end)
    fields = data[end:line_end].split()
    if fields[0] != b"-Y" or fields[2] != b"+X":
        raise SceneError(f"{path}: only -Y H +X W files are read")
    height, width = int(fields[1]), int(fields[3])
    pos, rows = line_end + 1, []
    for _ in range(height):
        if data[pos] == 2 and data[pos + 1] == 2 and not data[pos + 2] & 0x80:
            pos += 4
            row = np.zeros((4, width), np.uint8)
            for channel in range(4):
                x = 0
                while x < width:
                    count = data[pos]
                    if count > 128:
                        row[channel, x:x + count - 128] = data[pos + 1]
                        x, pos = x + count - 128, pos + 2
                    else:
                        row[channel, x:x + count] = list(data[pos + 1:pos + 1 + count])
                        x, pos = x + count, pos + 1 + count
            rows.append(row.T)
        else:
            rows.append(np.frombuffer(data[pos:pos + 4 * width], np.uint8).reshape(width, 4))
            pos += 4 * width
    rgbe = np.array(rows).astype(np.float64)
    scale = np.where(rgbe[..., 3] > 0, np.ldexp(1.0, rgbe[..., 3].astype(int) - 136), 0.0)
    return rgbe[..., :3] * scale[..., None]


def write_ply(path, triangles, uv=None):
    """N triangles (N x 3 x 3) as a binary PLY, float32 vertices, unshared;
    with uv (N x 3 x 2, rtcl's: v up), Mitsuba's texture coordinates (u, 1 - v:
    its bitmaps' v = 0 is the top row, rtcl's the bottom)."""
    count = len(triangles)
    tri = np.asarray(triangles, dtype="<f4").reshape(-1, 3)
    props = "property float x\nproperty float y\nproperty float z\n"
    if uv is not None:
        uv = np.asarray(uv, dtype=np.float64).reshape(-1, 2)
        uv = np.stack([uv[:, 0], 1.0 - uv[:, 1]], axis=1)
        tri = np.concatenate([tri, uv.astype("<f4")], axis=1)
        props += "property float u\nproperty float v\n"
    header = ("ply\nformat binary_little_endian 1.0\n"
              f"element vertex {3 * count}\n{props}element face {count}\n"
              "property list uchar int vertex_indices\nend_header\n").encode()
    faces = np.empty(count, dtype=np.dtype([("n", "u1"), ("i", "<i4", 3)]))
    faces["n"] = 3
    faces["i"] = np.arange(3 * count, dtype=np.int64).reshape(-1, 3)
    path.write_bytes(header + np.ascontiguousarray(tri).tobytes() + faces.tobytes())


# ---------------------------------------------------------------- glTF's BSDF

_GLTF_REGISTERED = False


def register_gltf():
    """Registers the Mitsuba BSDF "gltf": the dielectric part of glTF 2.0's
    metallic-roughness BRDF (the glTF specification, Appendix B), transcribed
    term by term, which Mitsuba has no plugin for:

        f = mix(C / pi, specular_brdf, F)              (glTF's fresnel_mix)
          = F specular_brdf + (1 - F) C / pi,  F = F0 + (1 - F0) (1 - |V.H|)^5
        specular_brdf = D(H) G1(V, H) G1(L, H) / (4 |N.L| |N.V|)   (GGX, separable Smith)
        F0 = ((ior - 1) / (ior + 1))^2, C the base colour, alpha given

    sampled by Mitsuba's GGX visible normals or the cosine, chosen with a fixed
    probability (the pdf is their mixture, so the choice is free). Reflection
    only, on the side of the normal (wrapped in "twosided")."""
    global _GLTF_REGISTERED
    if _GLTF_REGISTERED:
        return
    import drjit as dr
    import mitsuba as mi

    class GltfBSDF(mi.BSDF):
        def __init__(self, props):
            mi.BSDF.__init__(self, props)
            self.base = mi.Color3f(props["base_color"])
            self.dist = mi.MicrofacetDistribution(mi.MicrofacetType.GGX,
                                                  mi.Float(props["alpha"]), True)
            ior = mi.Float(props["ior"])
            self.f0 = dr.square((ior - 1) / (ior + 1))
            self.p_spec = mi.Float(0.25)  # how often the specular lobe is sampled
            reflection = mi.BSDFFlags.GlossyReflection | mi.BSDFFlags.DiffuseReflection
            self.m_components = [reflection]
            self.m_flags = reflection

        # In scalar variants a cosine is a Python float, whose division by 0
        # raises: both cosines are checked first (0 outside the hemisphere).
        def f(self, wi, wo):
            cos_i, cos_o = mi.Frame3f.cos_theta(wi), mi.Frame3f.cos_theta(wo)
            active = (cos_i > 0) & (cos_o > 0)
            h = dr.normalize(wi + wo)
            fresnel = self.f0 + (1 - self.f0) * dr.power(1 - dr.abs(dr.dot(wi, h)), 5)
            spec = self.dist.eval(h) * self.dist.G(wi, wo, h) / dr.select(
                active, 4 * cos_i * cos_o, 1)
            value = spec * fresnel + self.base * dr.inv_pi * (1 - fresnel)
            return dr.select(active, value * cos_o, 0)

        def pdf_of(self, wi, wo):
            cos_i, cos_o = mi.Frame3f.cos_theta(wi), mi.Frame3f.cos_theta(wo)
            active = (cos_i > 0) & (cos_o > 0)
            h = dr.normalize(wi + wo)
            spec = self.dist.eval(h) * self.dist.smith_g1(wi, h) / dr.select(
                active, 4 * cos_i, 1)
            pdf = self.p_spec * spec + (1 - self.p_spec) * cos_o * dr.inv_pi
            return dr.select(active, pdf, 0)

        def sample(self, ctx, si, sample1, sample2, active=True):
            wi = si.wi
            m, _ = self.dist.sample(wi, sample2)
            wo = dr.select(sample1 < self.p_spec, mi.reflect(wi, m),
                           mi.warp.square_to_cosine_hemisphere(sample2))
            bs = mi.BSDFSample3f()
            bs.wo = wo
            bs.pdf = self.pdf_of(wi, wo)
            bs.eta = 1.0
            bs.sampled_type = mi.UInt32(+mi.BSDFFlags.GlossyReflection)
            bs.sampled_component = 0
            ok = active & (bs.pdf > 0)
            return bs, dr.select(ok, self.f(wi, wo) / dr.select(ok, bs.pdf, 1), 0)

        def eval(self, ctx, si, wo, active=True):
            return self.f(si.wi, wo)

        def pdf(self, ctx, si, wo, active=True):
            return self.pdf_of(si.wi, wo)

        def eval_pdf(self, ctx, si, wo, active=True):
            return self.f(si.wi, wo), self.pdf_of(si.wi, wo)

        def to_string(self):
            return "GltfBSDF[]"

    mi.register_bsdf("gltf", lambda props: GltfBSDF(props))
    _GLTF_REGISTERED = True


# ---------------------------------------------------------------- rendering

def block_means(image):
    h, w, c = image.shape
    return image.reshape(h // BLOCK, BLOCK, w // BLOCK, BLOCK, c).mean(axis=(1, 3))


def render(scene_path, spp, batches, size=None, threads=1, aov=None, seed=0,
           approximate=False):
    import drjit as dr
    import mitsuba as mi
    mi.set_variant("scalar_rgb")
    dr.set_thread_count(threads)
    scene = Scene(scene_path, approximate)
    width, height = size or (None, None)
    if spp % batches:
        raise SceneError(f"--spp {spp} is not a multiple of --batches {batches}")
    per_batch = spp // batches
    loaded = mi.load_dict(mitsuba_scene(scene, per_batch, width, height, aov))
    total, blocks = None, []
    start = time.time()
    for batch in range(batches):
        image = np.array(mi.render(loaded, spp=per_batch, seed=seed + batch),
                         dtype=np.float64)
        image = image[..., :3]
        total = image if total is None else total + image
        if image.shape[0] % BLOCK == 0 and image.shape[1] % BLOCK == 0:
            blocks.append(block_means(image))
    seconds = time.time() - start
    mean = (total / batches).astype(np.float32)
    if blocks and batches > 1:
        spread = np.std(np.array(blocks), axis=0, ddof=1)
        sample_std = (spread * math.sqrt(BLOCK * BLOCK * per_batch)).astype(np.float32)
    else:
        sample_std = np.zeros((0,), np.float32)
    return mean, sample_std, seconds, mi.__version__


def input_digests(scene_path, folder):
    """The SHA-256 of every file the render read: the scene, its mesh files,
    their MTL files and textures, and its environment map, by their paths
    relative to folder."""
    scene_path = pathlib.Path(scene_path)
    doc = json.loads(scene_path.read_text())
    files = [scene_path] + [scene_path.parent / m["file"] for m in doc.get("meshes", [])]
    for mesh in doc.get("meshes", []):                 # an OBJ's MTL files and textures
        obj = scene_path.parent / mesh["file"]
        if obj.suffix.lower() != ".obj":
            continue
        for line in obj.read_text().splitlines():
            if line.split()[:1] == ["mtllib"]:
                files += [obj.parent / name for name in line.split()[1:]]
        files += [m["mtl_diffuse"]["texture"] for m in
                  (mtl_material(obj, name, fields, str(obj))
                   for name, fields in read_mtl(obj).items() if "map_Kd" in fields)]
    if "environment" in doc:
        files.append(scene_path.parent / doc["environment"]["file"])
    return {os.path.relpath(f, folder): hashlib.sha256(f.read_bytes()).hexdigest()
            for f in files}


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("scene")
    parser.add_argument("-o", "--output", required=True, help="the .npz to write")
    parser.add_argument("--spp", type=int, default=4096)
    parser.add_argument("--batches", type=int, default=16)
    parser.add_argument("--size", help="WxH (default: the scene's image)")
    parser.add_argument("--threads", type=int, default=1,
                        help="rendering threads (default 1: the machine is shared)")
    parser.add_argument("--seed", type=int, default=0,
                        help="the first batch's seed (batch k: seed + k)")
    parser.add_argument("--aov", choices=["albedo"],
                        help="render the surfaces' albedo instead (the camera and geometry check)")
    parser.add_argument("--approximate", action="store_true",
                        help=f"map planes as {PLANE_SIZE:g}-unit squares and glTF textures "
                        "approximately (docs/oracle.md; never for the oracle's references)")
    args = parser.parse_args(argv)
    size = None
    if args.size:
        width, _, height = args.size.partition("x")
        size = (int(width), int(height))
    try:
        mean, sample_std, seconds, version = render(args.scene, args.spp, args.batches, size,
                                                    args.threads, args.aov, args.seed,
                                                    args.approximate)
    except SceneError as error:
        sys.exit(f"mitsuba_ref.py: {error}")
    scene_bytes = pathlib.Path(args.scene).read_bytes()
    meta = {
        "scene": os.path.relpath(args.scene, pathlib.Path(args.output).parent),
        "scene_sha256": hashlib.sha256(scene_bytes).hexdigest(),
        "inputs": input_digests(args.scene, pathlib.Path(args.output).parent),
        "spp": args.spp, "batches": args.batches, "seed": args.seed, "aov": args.aov,
        "width": int(mean.shape[1]), "height": int(mean.shape[0]),
        "mitsuba": version, "variant": "scalar_rgb", "threads": args.threads,
        "seconds": round(seconds, 1), "approximate": args.approximate,
        "command": "python3 tools/build/mitsuba_ref.py " + " ".join(argv or sys.argv[1:]),
    }
    tmp = pathlib.Path(args.output).with_suffix(".tmp.npz")
    np.savez_compressed(tmp, image=mean, block_sample_std=sample_std,
                        meta=np.array(json.dumps(meta, sort_keys=True)))
    os.replace(tmp, args.output)
    print(json.dumps(meta, sort_keys=True))


if __name__ == "__main__":
    main()
