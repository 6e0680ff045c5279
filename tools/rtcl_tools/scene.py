"""The tools' scene validator: docs/SCENE.md (format versions 1 and 2) in Python.

host/scene/scene.c is the authority; this module (with scene_check.py for the messages
and the checks of values, as host/scene/scene_check.c) mirrors it for the tools (povray.py
reads scenes through it) and for the tests, rule for rule and in the same
order, with the same "PATH: what is wrong" messages, so that every file rtcl
refuses is refused here too, with rtcl's message (test/test_rtcl_tools.py
checks that against test/bad_scenes/).  Two deliberate differences: JSON
syntax errors are "LINE:COLUMN: what" as in rtcl, in Python's wording; and a
mesh file is only checked to exist and be readable (after the mesh's other
fields, where rtcl reads it): parsing it is the importer's job, so a file
without triangles or with a non-finite vertex passes here (RTCL_ONLY in
test/test_rtcl_tools.py lists those bad scenes).

load_scene(path) and read_scene(document, base_dir) return the scene with every
default filled in (colours and vectors as tuples, plane normals normalised);
both raise SceneError.  base_dir is the folder that mesh files are relative to
(load_scene passes the scene file's); None skips the check that they exist.
"""

import errno
import json
import os
import stat

from .files import open_input
from .scene_check import (SceneError, Written, _escaped, check_keys, child, did_you_mean, fail,
                          format_number, format_vector, integer, length, number, optional,
                          required, scale_to_unit_max, type_name, vec3)
from .vector import normalize

PARALLEL_SINE = 1e-9                         # camera.up "parallel" below this sine
MAX_IMAGE_SIDE = 32768
MAX_DEPTH = 64
MAX_SAMPLES = 65536
VERSIONS = (1, 2)

TOP_KEYS = ("format", "version", "image", "camera", "background", "ambient", "max_depth",
            "epsilon", "materials", "lights", "spheres", "planes")
VERSION_2_KEYS = ("meshes", "triangles")
PATH_KEYS = ("integrator", "environment")    # SCENE.md, "Path tracing"
INTEGRATORS = ("whitted", "path")
BSDF_KEYS = {"diffuse": ("type", "reflectance"),
             "conductor": ("type", "reflectance", "roughness"),
             "dielectric": ("type", "ior", "roughness"),
             "principled": ("type", "base_color", "metallic", "roughness", "transmission",
                            "ior")}
MESH_KEYS = ("file", "material", "materials", "scale", "rotate", "translate", "smooth",
             "missing_textures", "camera")
MATERIAL_DEFAULTS = {"color": (1.0, 1.0, 1.0), "ambient": 1.0, "diffuse": 0.7,
                     "specular": 0.3, "shininess": 32.0, "reflect": 0.0,
                     "transmit": 0.0, "ior": 1.5, "fresnel": False, "bsdf": None,
                     "emission": (0.0, 0.0, 0.0)}
# Material fields in rtcl's order, each with its range.
MATERIAL_RANGES = (("ambient", "non-negative"), ("diffuse", "non-negative"),
                   ("specular", "non-negative"), ("shininess", "non-negative"),
                   ("reflect", "unit"), ("transmit", "unit"), ("ior", "positive"))


# ---- the scene -------------------------------------------------------------------------

def read_header(doc):
    """Returns the version of the document after checking its header and top-level keys."""
    if not isinstance(doc, dict):
        fail("", f"must be an object, got {type_name(doc)}")
    fmt = required(doc, "format", "")
    if not isinstance(fmt, str):
        fail("format", f'must be the string "rtcl-scene", got {type_name(fmt)}')
    if fmt != "rtcl-scene":
        fail("format", f'must be "rtcl-scene", got "{_escaped(fmt)}"')
    version = integer(required(doc, "version", ""), "version", -2**63, 2**63 - 1)
    if version > max(VERSIONS):
        fail("version", f"version {version} is not supported (this rtcl reads versions 1 and 2)")
    if version < min(VERSIONS):
        fail("version", f"must be 1 or 2, got {version}")
    for key in VERSION_2_KEYS:
        if key in doc and version < 2:
            fail(key, f'needs "version": 2 (the file says "version": {version})')
    check_keys(doc, "", TOP_KEYS + VERSION_2_KEYS + PATH_KEYS)
    return version


def camera_mesh(doc):
    """The index of the first mesh entry that takes its file's camera, or None."""
    meshes = doc.get("meshes")
    for i, value in enumerate(meshes if isinstance(meshes, list) else []):
        if isinstance(value, dict) and value.get("camera", False) is not False:
            return i
    return None


def read_lens_only(doc, mesh):
    """The scene's camera where the view comes from a mesh file's camera (SCENE.md,
    "The camera from a mesh file"): only the lens, the view left to rtcl (None)."""
    cam = check_keys(doc.get("camera", {}), "camera",
                     ("eye", "look_at", "up", "fov", "aperture", "focus_distance"))
    for key in ("eye", "look_at", "up", "fov"):
        if key in cam:
            fail(f"camera.{key}", f"the view comes from the camera of meshes[{mesh}]'s file; "
                 'the scene\'s "camera" may give only "aperture" and "focus_distance" then')
    return {"eye": None, "look_at": None, "up": None, "fov": None, "from_mesh": mesh,
            "aperture": optional(cam, "aperture", "camera", number, 0.0, "non-negative"),
            "focus_distance": optional(cam, "focus_distance", "camera", number, None,
                                       "positive")}


def read_camera(doc):
    mesh = camera_mesh(doc)
    if mesh is not None:
        return read_lens_only(doc, mesh)
    cam = check_keys(required(doc, "camera", ""), "camera",
                     ("eye", "look_at", "up", "fov", "aperture", "focus_distance"))
    camera = {"eye": vec3(required(cam, "eye", "camera"), "camera.eye"),
              "look_at": vec3(required(cam, "look_at", "camera"), "camera.look_at"),
              "up": optional(cam, "up", "camera", vec3, (0.0, 1.0, 0.0)),
              "fov": optional(cam, "fov", "camera", number, 45.0, "fov"),
              "aperture": optional(cam, "aperture", "camera", number, 0.0, "non-negative"),
              "focus_distance": optional(cam, "focus_distance", "camera", number, None,
                                         "positive")}
    # Halved first so that the difference cannot overflow.
    d = scale_to_unit_max([b / 2 - a / 2 for a, b in zip(camera["eye"], camera["look_at"])])
    if d is None:
        fail("camera.look_at", f"must differ from camera.eye, both are "
                               f"{format_vector(camera['eye'])}")
    u = scale_to_unit_max(camera["up"])
    if u is None:
        fail("camera.up", "must be non-zero")
    cross = (u[1] * d[2] - u[2] * d[1], u[2] * d[0] - u[0] * d[2], u[0] * d[1] - u[1] * d[0])
    if length(cross) <= PARALLEL_SINE * length(u) * length(d):
        fail("camera.up", f"must not be parallel to look_at - eye, got "
                          f"{format_vector(camera['up'])}")
    if camera["focus_distance"] is None:
        camera["focus_distance"] = 2 * length([b / 2 - a / 2 for a, b in
                                               zip(camera["eye"], camera["look_at"])])
    return camera


def choice(obj, key, path, names, default):
    """One of names (rtcl's loader_read_choice): 'must be "a", "b" or "c", got ...'."""
    if key not in obj:
        return default
    value, where = obj[key], child(path, key)
    rule = "must be " + ", ".join(f'"{n}"' for n in names[:-1]) + f' or "{names[-1]}", got '
    if not isinstance(value, str):
        fail(where, rule + type_name(value))
    if value not in names:
        fail(where, rule + f'"{_escaped(value)}"' + did_you_mean(value, names))
    return value


def read_environment(doc):
    """SCENE.md's "environment" (path only): the map's file, scale and rotation."""
    if "environment" not in doc:
        return None
    env = check_keys(doc["environment"], "environment", ("file", "scale", "rotate"))
    scale = optional(env, "scale", "environment", number, 1.0, "non-negative")
    rotate = optional(env, "rotate", "environment", number, 0.0)
    if "file" not in env:
        fail("environment", 'needs "file"')
    file = env["file"]
    if not isinstance(file, str) or not file:
        fail("environment.file", "must be a file name, got " +
             ('""' if isinstance(file, str) else type_name(file)))
    return {"file": file, "scale": scale, "rotate": rotate}


def read_globals(doc):
    """Returns the image size, camera and the global settings, in rtcl's order."""
    size, samples = (640, 480), 1
    if "image" in doc:
        image = check_keys(doc["image"], "image", ("width", "height", "samples"))
        size = tuple(optional(image, key, "image", integer, default, 1, MAX_IMAGE_SIDE)
                     for key, default in (("width", 640), ("height", 480)))
        samples = optional(image, "samples", "image", integer, 1, 1, MAX_SAMPLES)
    integrator = choice(doc, "integrator", "", INTEGRATORS, "whitted")
    environment = read_environment(doc)
    return {"size": size, "samples": samples, "integrator": integrator,
            "environment": environment, "camera": read_camera(doc),
            "background": optional(doc, "background", "", vec3, (0.0, 0.0, 0.0),
                                   "non-negative"),
            "ambient": optional(doc, "ambient", "", vec3, (0.1, 0.1, 0.1), "non-negative"),
            "max_depth": optional(doc, "max_depth", "", integer, 5, 0, MAX_DEPTH),
            "epsilon": optional(doc, "epsilon", "", number, 1e-4, "positive")}


def read_material(value, path):
    check_keys(value, path, tuple(MATERIAL_DEFAULTS))
    material = dict(MATERIAL_DEFAULTS)
    material["color"] = optional(value, "color", path, vec3, material["color"], "non-negative")
    for key, kind in MATERIAL_RANGES:
        material[key] = optional(value, key, path, number, material[key], kind)
    fresnel = value.get("fresnel", False)
    if fresnel is not False and fresnel not in ("dielectric", "conductor"):
        got = f'"{_escaped(fresnel)}"' if isinstance(fresnel, str) else \
            "true" if fresnel is True else type_name(fresnel)
        fail(child(path, "fresnel"), f'must be "dielectric", "conductor" or false, got {got}')
    material["fresnel"] = fresnel
    material["bsdf"] = read_bsdf(value, path)
    material["emission"] = optional(value, "emission", path, vec3, material["emission"],
                                    "non-negative")
    return material


def reflectance(bsdf, key, path, default):
    """A bsdf's colour: a color whose parts are at most 1."""
    colour = optional(bsdf, key, path, vec3, default, "non-negative")
    if max(colour) > 1:
        fail(child(path, key), "must be a color with parts between 0 and 1, got "
                               f"{format_vector(colour)}")
    return colour


def read_bsdf(value, path):
    """SCENE.md's "A material's bsdf": its type, then that type's fields."""
    if "bsdf" not in value:
        return None
    bsdf, where = value["bsdf"], child(path, "bsdf")
    if not isinstance(bsdf, dict):
        fail(where, f"must be an object, got {type_name(bsdf)}")
    kind = choice(bsdf, "type", where, tuple(BSDF_KEYS), None)
    if kind is None:
        fail(child(where, "type"), "required field is missing")
    check_keys(bsdf, where, BSDF_KEYS[kind])
    out = {"type": kind}
    if kind in ("diffuse", "conductor"):
        out["reflectance"] = reflectance(bsdf, "reflectance", where,
                                         (0.5,) * 3 if kind == "diffuse" else (1.0,) * 3)
    if kind == "principled":
        out["base_color"] = reflectance(bsdf, "base_color", where, (1.0,) * 3)
        out["metallic"] = optional(bsdf, "metallic", where, number, 0.0, "unit")
    if kind == "dielectric":
        out["ior"] = optional(bsdf, "ior", where, number, 1.5, "positive")
    if kind != "diffuse":
        out["roughness"] = optional(bsdf, "roughness", where, number,
                                    0.5 if kind == "principled" else 0.0, "unit")
    if kind == "principled":
        out["transmission"] = optional(bsdf, "transmission", where, number, 0.0, "unit")
        out["ior"] = optional(bsdf, "ior", where, number, 1.5, "positive")
    return out


def material_of(obj, path, materials):
    """Returns the material of a sphere or plane: named, inline or the default."""
    if "material" not in obj:
        return dict(MATERIAL_DEFAULTS)
    value, where = obj["material"], child(path, "material")
    if isinstance(value, str):
        if value not in materials:
            fail(where, f'unknown material "{_escaped(value)}"' + did_you_mean(value, materials))
        return materials[value]
    if not isinstance(value, dict):
        fail(where, f"must be a material name or an object, got {type_name(value)}")
    return read_material(value, where)


def read_light_kind(value, path):
    """Returns the position and radius of a point or sphere light, or the direction
    (normalised: the way its light travels) and angle of a directional one."""
    has_position, has_direction = "position" in value, "direction" in value
    if has_position == has_direction:
        fail(path, 'has both "position" and "direction": give one' if has_position else
             'needs "position" (a point or sphere light) or "direction" (a directional light)')
    if has_position:
        if "angle" in value:
            fail(child(path, "angle"), 'a point or sphere light has no angle; give its "radius"')
        return {"directional": False,
                "position": vec3(value["position"], child(path, "position")),
                "radius": optional(value, "radius", path, number, 0.0, "non-negative")}
    if "radius" in value:
        fail(child(path, "radius"), 'a directional light has no radius; give its "angle"')
    direction = vec3(value["direction"], child(path, "direction"), "direction")
    angle = optional(value, "angle", path, number, 0.0, "non-negative")
    if scale_to_unit_max(direction) is None:
        fail(child(path, "direction"), "must be non-zero")
    if angle >= 90:
        fail(child(path, "angle"), f"must be >= 0 and < 90, got {format_number(angle)}")
    return {"directional": True, "direction": normalize(direction), "angle": angle}


def read_lights(items):
    lights = []
    for i, value in enumerate(items):
        path = child("lights", i)
        check_keys(value, path, ("position", "direction", "color", "radius", "angle"))
        light = read_light_kind(value, path)
        light["color"] = optional(value, "color", path, vec3, (1.0, 1.0, 1.0), "non-negative")
        lights.append(light)
    return lights


def read_spheres(items, materials):
    spheres = []
    for i, value in enumerate(items):
        path = child("spheres", i)
        check_keys(value, path, ("center", "radius", "material"))
        spheres.append({"center": vec3(required(value, "center", path), child(path, "center")),
                        "radius": number(required(value, "radius", path),
                                         child(path, "radius"), "positive"),
                        "material": material_of(value, path, materials)})
    return spheres


def read_planes(items, materials):
    planes = []
    for i, value in enumerate(items):
        path = child("planes", i)
        check_keys(value, path, ("point", "normal", "material", "checker"))
        point = vec3(required(value, "point", path), child(path, "point"))
        normal = vec3(required(value, "normal", path), child(path, "normal"), "direction")
        if scale_to_unit_max(normal) is None:
            fail(child(path, "normal"), "must be non-zero")
        material = material_of(value, path, materials)
        checker = None
        if "checker" in value:
            where = child(path, "checker")
            raw = check_keys(value["checker"], where, ("size", "color"))
            checker = {"size": number(required(raw, "size", where), child(where, "size"),
                                      "positive"),
                       "color": vec3(required(raw, "color", where), child(where, "color"),
                                     "non-negative")}
        planes.append({"point": point, "normal": normalize(normal), "material": material,
                       "checker": checker})
    return planes


def non_zero(value, path):
    """Returns value as a float if it is a number other than 0 (a mesh's scale)."""
    x = number(value, path)
    if x == 0:
        fail(path, "must not be 0")
    return x


def read_scale(value, path):
    """Returns a mesh's scale, a number or a vec3 with no part 0, as a tuple."""
    if isinstance(value, list):
        vec3(value, path)
        return tuple(non_zero(part, child(path, i)) for i, part in enumerate(value))
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        fail(path, f"must be a number or an array of 3 numbers, got {type_name(value)}")
    return (non_zero(value, path),) * 3


def boolean(value, path):
    if not isinstance(value, bool):
        fail(path, f"must be true or false, got {type_name(value)}")
    return value


def one_line(text):
    """Returns a file name as rtcl quotes it (host/scene/scene_mesh.c): control characters
    become '?', cut after 299 bytes, without trailing '?' and spaces."""
    raw = bytes(b if b >= 0x20 and b != 0x7f else 0x3f for b in text.encode("utf-8"))
    return raw[:299].rstrip(b"? ").decode("utf-8", errors="replace")


def mesh_name(value, path):
    """Returns the file name of a mesh, a non-empty string."""
    if not isinstance(value, str):
        fail(path, f"must be a string, got {type_name(value)}")
    if not value:
        fail(path, 'must name a file, got ""')
    return value


def mesh_file(name, path, base_dir):
    """Returns the path of a mesh file, after checking that it is a regular file
    that can be opened for reading, as rtcl does; relative to base_dir unless
    absolute (None: not looked up)."""
    if base_dir is None:
        return name
    # An absolute path stays as it is (os.path.join drops base_dir).
    resolved = os.path.join(base_dir, name)
    try:
        # O_NONBLOCK: a FIFO must not hang the open (rtcl refuses it too).
        fd = os.open(resolved, os.O_RDONLY | os.O_NONBLOCK)
        try:
            mode = os.fstat(fd).st_mode
        finally:
            os.close(fd)
    except OSError as error:
        fail(path, f'cannot read "{one_line(name)}": {error.strerror}')
    if stat.S_ISDIR(mode):
        fail(path, f'cannot read "{one_line(name)}": {os.strerror(errno.EISDIR)}')
    if not stat.S_ISREG(mode):
        fail(path, f'cannot read "{one_line(name)}": not a regular file')
    return resolved


def read_meshes(items, materials, base_dir):
    """The meshes in rtcl's order: the file's name, the material and placement, and
    only then the file itself."""
    meshes, camera_from = [], None
    for i, value in enumerate(items):
        path = child("meshes", i)
        check_keys(value, path, MESH_KEYS)
        where = child(path, "file")
        name = mesh_name(required(value, "file", path), where)
        # The file's own materials (SCENE.md, "Materials from mesh files") are
        # rtcl's to read; the tools convert only the PLY meshes tools/genbench.py
        # writes, which have none: a mesh without "material" is the default one.
        if "material" in value and "materials" in value:
            fail(path, '"material" (one for the whole mesh) and "materials" (by the '
                 "file's names) exclude each other")
        overrides = value.get("materials", {})
        if not isinstance(overrides, dict):
            fail(child(path, "materials"), f"must be an object, got {type_name(overrides)}")
        for key, material in overrides.items():
            where = child(child(path, "materials"), key)
            if isinstance(material, str):
                if material not in materials:
                    fail(where, f'unknown material "{_escaped(material)}"'
                         + did_you_mean(material, materials))
            elif isinstance(material, dict):
                read_material(material, where)
            else:
                fail(where, f"must be a material name or an object, got {type_name(material)}")
        missing = value.get("missing_textures", "error")
        if missing not in ("error", "warn"):
            fail(child(path, "missing_textures"), 'must be "error" or "warn", got '
                 + (f'"{_escaped(missing)}"' if isinstance(missing, str) else type_name(missing)))
        camera = value.get("camera", False)
        if camera is not False:
            if camera is not True and not isinstance(camera, str):
                fail(child(path, "camera"), "must be true, false or the name of a camera of "
                     f"the file, got {type_name(camera)}")
            if camera == "":
                fail(child(path, "camera"), 'must name a camera of the file, got ""')
            if camera_from is not None:
                fail(child(path, "camera"), f"meshes[{camera_from}] gives the camera already; "
                     "one mesh at most may")
        mesh = {"material": material_of(value, path, materials),
                "scale": optional(value, "scale", path, read_scale, (1.0, 1.0, 1.0)),
                "rotate": optional(value, "rotate", path, vec3, (0.0, 0.0, 0.0)),
                "translate": optional(value, "translate", path, vec3, (0.0, 0.0, 0.0)),
                "smooth": optional(value, "smooth", path, boolean, True)}
        mesh["file"] = mesh_file(name, where, base_dir)
        if camera is not False:
            mesh["camera"] = camera
            camera_from = i
        meshes.append(mesh)
    return meshes


def read_vertices(value, path):
    """Returns the three vertices of an inline triangle, which must span an area."""
    if not isinstance(value, list):
        fail(path, f"must be an array of 3 vertices, got {type_name(value)}")
    if len(value) != 3:
        fail(path, f"must be an array of 3 vertices, got {len(value)} "
                   f"element{'' if len(value) == 1 else 's'}")
    a, b, c = (vec3(point, child(path, i)) for i, point in enumerate(value))
    # Halved so that no difference overflows; only "exactly 0" matters here.
    u = [y / 2 - x / 2 for x, y in zip(a, b)]
    v = [y / 2 - x / 2 for x, y in zip(a, c)]
    if not any((u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2],
                u[0] * v[1] - u[1] * v[0])):
        fail(path, "must span a triangle of non-zero area, got "
                   + ", ".join(format_vector(p) for p in (a, b, c)))
    return a, b, c


def read_triangles(items, materials):
    triangles = []
    for i, value in enumerate(items):
        path = child("triangles", i)
        check_keys(value, path, ("vertices", "material"))
        triangles.append({"vertices": read_vertices(required(value, "vertices", path),
                                                    child(path, "vertices")),
                          "material": material_of(value, path, materials)})
    return triangles


def read_scene(doc, base_dir=None):
    """Returns the parsed document doc as a scene with its defaults; SceneError if bad.
    Mesh files are looked up relative to base_dir (None: not looked up)."""
    version = read_header(doc)
    scene = read_globals(doc)
    scene["version"] = version
    arrays = {}
    for key in ("lights", "spheres", "planes") + VERSION_2_KEYS:
        arrays[key] = doc.get(key, [])
        if not isinstance(arrays[key], list):
            fail(key, f"must be an array, got {type_name(arrays[key])}")
    named = doc.get("materials", {})
    if not isinstance(named, dict):
        fail("materials", f"must be an object, got {type_name(named)}")
    materials = {name: read_material(value, child("materials", name))
                 for name, value in named.items()}
    scene.update(lights=read_lights(arrays["lights"]),
                 spheres=read_spheres(arrays["spheres"], materials),
                 planes=read_planes(arrays["planes"], materials),
                 meshes=read_meshes(arrays["meshes"], materials, base_dir),
                 triangles=read_triangles(arrays["triangles"], materials))
    return scene


# ---- the file ----------------------------------------------------------------------------

def _no_duplicates(pairs):
    seen = set()
    for key, _ in pairs:
        if key in seen:
            raise SceneError(f'duplicate object key "{_escaped(key)}"')
        seen.add(key)
    return dict(pairs)


def parse(data):
    """Returns the JSON document of data (bytes or str), strict about duplicate keys.
    A byte-order mark at the very start is skipped, as rtcl does."""
    if isinstance(data, bytes) and data.startswith(b"\xef\xbb\xbf"):
        data = data[3:]
    if isinstance(data, bytes):
        try:
            data = data.decode("utf-8")
        except UnicodeDecodeError as error:
            line = data.count(b"\n", 0, error.start) + 1
            column = error.start - (data.rfind(b"\n", 0, error.start) + 1)
            raise SceneError(f"{line}:{column}: unable to decode byte "
                             f"0x{data[error.start]:02x}") from None
    try:
        return json.loads(data, object_pairs_hook=_no_duplicates, parse_float=Written)
    except json.JSONDecodeError as error:
        raise SceneError(f"{error.lineno}:{error.colno}: {error.msg}") from None


def load_scene(path):
    """Returns the scene in the file at path; SceneError (or OSError) if it cannot
    (a folder or FIFO too: files.open_input)."""
    with open_input(path) as stream:
        data = stream.read()
    return read_scene(parse(data), os.path.dirname(os.path.abspath(path)))


def validate(doc, base_dir=None):
    """Raises SceneError unless the parsed document doc follows SCENE.md; mesh files
    are looked up relative to base_dir when it is given."""
    read_scene(doc, base_dir)
