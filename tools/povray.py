#!/usr/bin/env python3
"""Convert an rtcl scene (docs/SCENE.md) into POV-Ray 3.7 SDL, and time POV-Ray on it.

This is the baseline of rtcl's CPU performance target (issue 4): PoCL on a 2-core
machine must need at most half the time that POV-Ray 3.7 (Debian's `povray`,
+WT2, no antialiasing, adc_bailout 0, max_trace_level = depth + 1) needs for an
equivalent scene at the same size.  The SDL written here is as close to
docs/RENDERING.md as POV-Ray allows; what differs is listed below.

    tools/povray.py                                   # scenes/paper60.json as SDL, on stdout
    tools/povray.py -s scenes/two_balls.json --size 64x48 -o balls.pov
    tools/povray.py --time 3 --size 2000x2000         # median/min/max of 3 POV-Ray renders
    tools/povray.py -s scenes/tir.json --image tir.png  # render once, keep the image
    tools/povray.py --time 3 --transparent-shadows    # POV-Ray's own filtered shadows

With --time N (and --image FILE, which implies one run), the SDL is written to a
temporary directory and rendered N times with

    povray +Iscene.pov +Orender.png +WW +HH -A +WT2 -D +FN File_Gamma=1.0

run in that directory (Debian's povray.conf restricts writes to it and /tmp);
the tool prints POV-Ray's version, the command, the load average, every run's
wall time and POV-Ray's own "Trace Time" (and CPU seconds), then the median,
min and max of both.  The wall time includes POV-Ray's start, parsing and
bounding (about 0.6 s here even for a tiny image); the trace time does not.
-GA is not passed: with it POV-Ray 3.7 prints no statistics, so its own trace
time could not be read; its console output goes to a pipe.  File_Gamma=1.0 makes
POV-Ray write linear values, round(255 * clamp(c, 0, 1)) as rtcl does (POV-Ray's
default is gamma-encoded output); .ppm for --image gives +FP instead of +FN.

How the scene maps (POV-Ray is left-handed; rtcl's world is right-handed):

* Every point and direction is mirrored in x (POV-Ray x = -rtcl x), so the
  scene, seen through the mirrored camera, gives the same picture.
* Camera: perspective, location = eye, direction = f, right = 2*a*h*r,
  up = 2*h*u (f, r, u, h = tan(fov/2), a = width/height as in RENDERING.md, all
  mirrored), with no look_at or angle, so POV-Ray uses them as given.  POV-Ray
  3.7's perspective camera shoots pixel (x, y) along
  direction + ((x+0.5)/W - 0.5)*right + (0.5 - (y+0.5)/H)*up, which is exactly
  RENDERING.md's primary ray.
* #version 3.7; global_settings { assumed_gamma 1.0  max_trace_level depth+1
  adc_bailout 0  ambient_light <scene ambient> }; background { rgb <background> }.
  POV-Ray's primary ray has trace level 1 and a ray at level max_trace_level
  returns black, so depth+1 levels are traced, as rtcl's depths 0 .. max_depth.
* Point lights: light_source { <position> color rgb <color> } (no fading).
* Spheres: sphere { <center>, radius }; planes: plane { <n>, n.point }.
* Material (C, ka, kd, ks, shininess, kr, kt, ior):
  pigment rgbt <C, kt>; finish { ambient ka/(1-kt) diffuse kd/(1-kt)
  specular ks roughness 1/shininess reflection { kr } }; interior { ior } when
  kt > 0.  POV-Ray scales ambient and diffuse by the pigment's opacity 1 - kt,
  which the division undoes; it adds ka*C*ambient_light + sum over lights of
  kd*|n.L|*C*Lc + ks*(n.H)^(1/roughness)*Lc (H the normalised half vector of L and
  -d: Blinn-Phong), reflection kr*trace(R) with a constant kr (no Fresnel, no
  falloff, no metallic) and kt*trace(T) through a non-filtering transmit, T by
  Heckbert's formula, which is RENDERING.md's.
* Checker: POV-Ray's checker pattern is three-dimensional (parity of
  floor(x)+floor(y)+floor(z) after adding 1e-10).  The pattern is mirrored back
  into rtcl's axes, the two kept axes scaled by checker.size, and the dropped
  axis (largest |normal| component, x before y before z) scaled by 1e9 with the
  plane's point at the middle of a cell, so that only floor(s/size) +
  floor(t/size) decides the colour: checker { <material colour>, <checker colour> }.
* Shadows: rtcl's transparent objects block light completely; POV-Ray lets
  light through them, filtered by their transmit at every surface.  So each
  object with kt > 0 gets a shadow clone: opaque, with `no_image
  no_reflection`, which POV-Ray hides from camera, reflected and refracted rays
  (only shadow rays see it).  A sphere's clone has radius r*(1 - 1e-6): a clone
  of the very same size is missed, because POV-Ray's shadow ray, resolving the
  tie in favour of the glass, restarts on its surface and ignores hits closer
  than 1e-3; the smaller clone blocks through its far side.  A plane gets two
  clones, 1e-6 on each side.  --transparent-shadows leaves the clones out:
  POV-Ray's own filtered shadows, brighter shadows of glass and direct light on
  the inside of glass balls, and a different amount of work.
* Nested transparent spheres: POV-Ray refracts by the ratio of the iors on both
  sides (it keeps a stack of the objects a ray is in); rtcl by ior against 1 at
  every surface.  A transparent sphere wholly inside transparent spheres or
  wholly beneath a transparent plane gets POV-Ray ior = its ior times theirs,
  which gives the same ratios at every surface (scenes/tir.json's bubbles).
* -A: one ray per pixel through its centre, no jitter; the output is
  round(255 * clamp(c, 0, 1)) per channel, no dithering, as rtcl's.

With all this, rtcl and POV-Ray agree on every pixel within 1/255 at depth 0
(paper60 at 64x48: byte-identical at depths 0 and 1), and within PSNR > 50 dB
for paper60 and two_balls at full depth (test/test_povray.py checks a render).
What still differs:

1. Total internal reflection: rtcl traces the reflected ray with weight kr + kt;
   POV-Ray with weight 1 (it replaces the kr reflection by the whole TIR ray).
2. Ray offsets: rtcl starts secondary rays at p +- epsilon*n (the scene's
   epsilon); POV-Ray starts them at p and ignores hits closer than 1e-6
   (spheres, planes), shadow blockers closer than 1e-3 (SMALL_TOLERANCE) to p
   or to the light, and a light whose n.L is below 1e-10.  Shadow rays that
   graze a glass ball's clone along a chord shorter than 1e-3 pass, filtered.
3. Precision: rtcl computes in float on the device, POV-Ray in double (colours in
   float); edges and highlights differ by a pixel or a level here and there.
4. Bounding: POV-Ray builds a bounding-box hierarchy over the finite objects
   (spheres, clones included; planes are unbounded) before tracing (its
   "Bounding Time", outside "Trace Time") and keeps a shadow cache (the last
   opaque blocker per light, tested first); rtcl tests every object for every
   ray.  That is POV-Ray's algorithmic advantage, and part of the baseline.
5. kt = 1: POV-Ray's opacity is 0, so no ambient or diffuse can be given back;
   both are dropped (a warning says so).
6. shininess 0: rtcl adds ks*Lc even where n.H <= 0 (pow(0, 0) = 1); POV-Ray
   (roughness 1e30) only where n.H > 0.
7. ior 1: POV-Ray passes the ray straight through without counting a trace
   level; rtcl counts the depth.  Overlapping (not nested) transparent objects,
   or a sphere straddling a transparent plane, refract differently.
8. POV-Ray ignores objects farther than 1e7 (MAX_DISTANCE); rtcl allows 1e18.
"""

import argparse
import json
import math
import os
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from genscene import cross, dot, parse_size, sub  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DEFAULT_SCENE = os.path.join(ROOT, "scenes", "paper60.json")
PROG = "povray.py"

TOP_KEYS = {"format", "version", "image", "camera", "background", "ambient",
            "max_depth", "epsilon", "materials", "lights", "spheres", "planes"}
MATERIAL_DEFAULTS = {"color": [1.0, 1.0, 1.0], "ambient": 1.0, "diffuse": 0.7,
                     "specular": 0.3, "shininess": 32.0, "reflect": 0.0,
                     "transmit": 0.0, "ior": 1.5}
CHECKER_BIG = 1e9            # scale of the checker's dropped axis
CLONE_SHRINK = 1e-6          # a sphere's shadow clone has radius r * (1 - this)
CLONE_SHIFT = 1e-6           # a plane's two shadow clones lie this far on each side
CLONE = (" pigment { rgb 0 } finish { ambient 0 diffuse 0 specular 0 }"
         " no_image no_reflection }  // shadow clone")
ZERO_SHININESS_ROUGHNESS = 1e30


class SceneError(Exception):
    """A scene that cannot be converted; the message names the place."""


# parse_size and the vector helpers are genscene's (same folder).


def scale(a, s):
    return tuple(x * s for x in a)


def normalize(a):
    n = math.sqrt(dot(a, a))
    return tuple(x / n for x in a)


def mirror(v):
    """rtcl's right-handed world to POV-Ray's left-handed one: negate x."""
    return (-v[0], v[1], v[2])


# ---- scene reading ----------------------------------------------------------------

def expect(ok, where, what):
    if not ok:
        raise SceneError("%s: %s" % (where, what))


def number(value, where, low=None, high=None, low_open=False):
    expect(isinstance(value, (int, float)) and not isinstance(value, bool)
           and math.isfinite(value), where, "must be a number")
    if low is not None:
        if low_open:
            expect(value > low, where, "must be > %g, got %g" % (low, value))
        else:
            expect(value >= low, where, "must be >= %g, got %g" % (low, value))
    if high is not None:
        expect(value <= high, where, "must be <= %g, got %g" % (high, value))
    return float(value)


def vec3(value, where, color=False):
    expect(isinstance(value, list) and len(value) == 3, where,
           "must be an array of three numbers")
    return tuple(number(v, "%s[%d]" % (where, i), 0 if color else None)
                 for i, v in enumerate(value))


def obj(value, where, keys):
    expect(isinstance(value, dict), where, "must be an object")
    for key in value:
        expect(key in keys, where, 'unknown key "%s"' % key)
    return value


def read_material(value, where):
    obj(value, where, set(MATERIAL_DEFAULTS))
    m = dict(MATERIAL_DEFAULTS)
    for key, v in value.items():
        if key == "color":
            m[key] = vec3(v, where + ".color", color=True)
        elif key in ("reflect", "transmit"):
            m[key] = number(v, "%s.%s" % (where, key), 0, 1)
        elif key == "ior":
            m[key] = number(v, where + ".ior", 0, low_open=True)
        else:
            m[key] = number(v, "%s.%s" % (where, key), 0)
    m["color"] = tuple(m["color"])
    return m


def load_scene(path):
    """Return the scene as a dict with every default filled in (SCENE.md)."""
    try:
        with open(path, encoding="utf-8") as f:
            text = f.read()
    except OSError as e:
        raise SceneError(e.strerror or str(e))
    except UnicodeDecodeError:
        raise SceneError("not UTF-8 text")

    def no_duplicates(pairs):
        keys = [k for k, _ in pairs]
        for k in keys:
            if keys.count(k) > 1:
                raise SceneError('duplicate key "%s"' % k)
        return dict(pairs)

    try:
        raw = json.loads(text, object_pairs_hook=no_duplicates)
    except json.JSONDecodeError as e:
        raise SceneError("%d:%d: %s" % (e.lineno, e.colno, e.msg))
    obj(raw, "scene", TOP_KEYS)
    expect(raw.get("format") == "rtcl-scene", "format", 'must be "rtcl-scene"')
    expect(raw.get("version") == 1, "version", "must be 1, got %r" % (raw.get("version"),))

    image = obj(raw.get("image", {}), "image", {"width", "height"})
    size = []
    for key, default in (("width", 640), ("height", 480)):
        v = image.get(key, default)
        expect(isinstance(v, int) and not isinstance(v, bool) and 1 <= v <= 32768,
               "image." + key, "must be an integer 1 ... 32768")
        size.append(v)

    expect("camera" in raw, "camera", "missing")
    cam = obj(raw["camera"], "camera", {"eye", "look_at", "up", "fov"})
    for key in ("eye", "look_at"):
        expect(key in cam, "camera." + key, "missing")
    camera = {"eye": vec3(cam["eye"], "camera.eye"),
              "look_at": vec3(cam["look_at"], "camera.look_at"),
              "up": vec3(cam.get("up", [0, 1, 0]), "camera.up"),
              "fov": number(cam.get("fov", 45), "camera.fov", 0, 180, low_open=True)}
    expect(camera["fov"] < 180, "camera.fov", "must be < 180")
    f = sub(camera["look_at"], camera["eye"])
    expect(dot(f, f) > 0, "camera", "eye and look_at must differ")
    c = cross(f, camera["up"])
    expect(dot(c, c) > 0, "camera.up", "must not be parallel to look_at - eye")

    depth = raw.get("max_depth", 5)
    expect(isinstance(depth, int) and not isinstance(depth, bool) and 0 <= depth <= 64,
           "max_depth", "must be an integer 0 ... 64")

    materials = {}
    for name, value in _items(raw.get("materials", {}), "materials"):
        materials[name] = read_material(value, "materials." + name)

    def material_of(value, where):
        if value is None:
            return dict(MATERIAL_DEFAULTS, color=tuple(MATERIAL_DEFAULTS["color"]))
        if isinstance(value, str):
            expect(value in materials, where, 'unknown material "%s"' % value)
            return materials[value]
        return read_material(value, where)

    lights = []
    for i, v in enumerate(_list(raw.get("lights", []), "lights")):
        where = "lights[%d]" % i
        obj(v, where, {"position", "color"})
        expect("position" in v, where + ".position", "missing")
        lights.append({"position": vec3(v["position"], where + ".position"),
                       "color": vec3(v.get("color", [1, 1, 1]), where + ".color", color=True)})

    spheres = []
    for i, v in enumerate(_list(raw.get("spheres", []), "spheres")):
        where = "spheres[%d]" % i
        obj(v, where, {"center", "radius", "material"})
        for key in ("center", "radius"):
            expect(key in v, "%s.%s" % (where, key), "missing")
        spheres.append({"center": vec3(v["center"], where + ".center"),
                        "radius": number(v["radius"], where + ".radius", 0, low_open=True),
                        "material": material_of(v.get("material"), where + ".material")})

    planes = []
    for i, v in enumerate(_list(raw.get("planes", []), "planes")):
        where = "planes[%d]" % i
        obj(v, where, {"point", "normal", "material", "checker"})
        for key in ("point", "normal"):
            expect(key in v, "%s.%s" % (where, key), "missing")
        normal = vec3(v["normal"], where + ".normal")
        expect(dot(normal, normal) > 0, where + ".normal", "must not be zero")
        checker = None
        if "checker" in v:
            ch = obj(v["checker"], where + ".checker", {"size", "color"})
            for key in ("size", "color"):
                expect(key in ch, "%s.checker.%s" % (where, key), "missing")
            checker = {"size": number(ch["size"], where + ".checker.size", 0, low_open=True),
                       "color": vec3(ch["color"], where + ".checker.color", color=True)}
        planes.append({"point": vec3(v["point"], where + ".point"),
                       "normal": normalize(normal),
                       "material": material_of(v.get("material"), where + ".material"),
                       "checker": checker})

    return {"size": tuple(size), "camera": camera,
            "background": vec3(raw.get("background", [0, 0, 0]), "background", color=True),
            "ambient": vec3(raw.get("ambient", [0.1, 0.1, 0.1]), "ambient", color=True),
            "max_depth": depth,
            "epsilon": number(raw.get("epsilon", 1e-4), "epsilon", 0, low_open=True),
            "lights": lights, "spheres": spheres, "planes": planes}


def _items(value, where):
    expect(isinstance(value, dict), where, "must be an object")
    return value.items()


def _list(value, where):
    expect(isinstance(value, list), where, "must be an array")
    return value


# ---- SDL writing ------------------------------------------------------------------

def num(x):
    """Shortest text that reads back as the same double; never -0."""
    x = float(x)
    if x == 0:
        return "0"
    text = repr(x)
    return text[:-2] if text.endswith(".0") else text


def vec(v):
    return "<%s>" % ", ".join(num(x) for x in v)


def camera_vectors(camera, width, height):
    """Return (location, direction, right, up) in POV-Ray's (mirrored) world."""
    f = normalize(sub(camera["look_at"], camera["eye"]))
    r = normalize(cross(f, camera["up"]))
    u = cross(r, f)
    h = math.tan(math.radians(camera["fov"]) / 2)
    a = width / height
    return (mirror(camera["eye"]), mirror(f), mirror(scale(r, 2 * a * h)),
            mirror(scale(u, 2 * h)))


def dropped_axis(normal):
    """The axis along which the normal has its largest |component| (x, y, z first)."""
    mags = [abs(c) for c in normal]
    return mags.index(max(mags))


def pigment(m, checker, point, normal):
    kt = m["transmit"]
    first = "rgbt <%s, %s>" % (", ".join(num(c) for c in m["color"]), num(kt))
    if checker is None:
        return "pigment { color %s }" % first
    second = "rgbt <%s, %s>" % (", ".join(num(c) for c in checker["color"]), num(kt))
    k = dropped_axis(normal)
    size = checker["size"]
    scales = [size, size, size]
    offsets = [0.0, 0.0, 0.0]
    scales[k] = CHECKER_BIG
    offsets[k] = point[k] - 0.5 * CHECKER_BIG
    # Pattern space -> rtcl world (scale, translate) -> POV-Ray world (mirror x).
    return ("pigment { checker color %s, color %s\n"
            "      scale %s translate %s scale <-1, 1, 1> }"
            % (first, second, vec(scales), vec(offsets)))


def finish(m):
    opacity = 1.0 - m["transmit"]
    ka = m["ambient"] / opacity if opacity > 0 else 0.0
    kd = m["diffuse"] / opacity if opacity > 0 else 0.0
    parts = ["ambient %s" % num(ka), "diffuse %s" % num(kd)]
    if m["specular"] > 0:
        rough = 1.0 / m["shininess"] if m["shininess"] > 0 else ZERO_SHININESS_ROUGHNESS
        parts.append("specular %s roughness %s" % (num(m["specular"]), num(rough)))
    else:
        parts.append("specular 0")
    if m["reflect"] > 0:
        parts.append("reflection { %s }" % num(m["reflect"]))
    return "finish { %s }" % " ".join(parts)


def sphere_inside_sphere(inner, outer):
    d = math.sqrt(dot(sub(inner["center"], outer["center"]), sub(inner["center"], outer["center"])))
    return d + inner["radius"] < outer["radius"]


def sphere_below_plane(sphere, plane):
    return dot(sub(sphere["center"], plane["point"]), plane["normal"]) < -sphere["radius"]


def pov_iors(scene):
    """POV-Ray ior of each transparent sphere: its own times those of the
    transparent spheres and planes wholly containing it (see the docstring)."""
    result = []
    for s in scene["spheres"]:
        ior = s["material"]["ior"]
        for o in scene["spheres"]:
            if o is not s and o["material"]["transmit"] > 0 and sphere_inside_sphere(s, o):
                ior *= o["material"]["ior"]
        for p in scene["planes"]:
            if p["material"]["transmit"] > 0 and sphere_below_plane(s, p):
                ior *= p["material"]["ior"]
        result.append(ior)
    return result


def to_sdl(scene, size, depth, source="", shadow_clones=True):
    """Return the POV-Ray 3.7 SDL text of the scene at size (w, h) and max_depth depth."""
    width, height = size
    loc, direction, right, up = camera_vectors(scene["camera"], width, height)
    out = []
    w = out.append
    w("// Generated by tools/povray.py%s: %dx%d, max_depth %d."
      % (" from " + source if source else "", width, height, depth))
    w("// rtcl's right-handed world mirrored in x (POV-Ray x = -rtcl x); render with")
    w("// povray +W%d +H%d -A File_Gamma=1.0 (see the tool's docstring)." % (width, height))
    w("#version 3.7;")
    w("global_settings {")
    w("  assumed_gamma 1.0")
    w("  max_trace_level %d" % (depth + 1))
    w("  adc_bailout 0")
    w("  ambient_light rgb %s" % vec(scene["ambient"]))
    w("}")
    w("background { color rgb %s }" % vec(scene["background"]))
    w("camera {")
    w("  perspective")
    w("  location %s" % vec(loc))
    w("  right %s" % vec(right))
    w("  up %s" % vec(up))
    w("  direction %s" % vec(direction))
    w("}")
    for light in scene["lights"]:
        w("light_source { %s color rgb %s }" % (vec(mirror(light["position"])),
                                                 vec(light["color"])))
    iors = pov_iors(scene)
    for s, ior in zip(scene["spheres"], iors):
        m = s["material"]
        shape = "sphere { %s, %s" % (vec(mirror(s["center"])), num(s["radius"]))
        w(shape)
        w("  texture { %s\n    %s }" % (pigment(m, None, None, None), finish(m)))
        if m["transmit"] > 0:
            w("  interior { ior %s }" % num(ior))
        w("}")
        if m["transmit"] > 0 and shadow_clones:
            w("sphere { %s, %s%s" % (vec(mirror(s["center"])),
                                     num(s["radius"] * (1 - CLONE_SHRINK)), CLONE))
    for p in scene["planes"]:
        m = p["material"]
        n = mirror(p["normal"])
        d = dot(p["normal"], p["point"])
        w("plane { %s, %s" % (vec(n), num(d)))
        w("  texture { %s\n    %s }" % (pigment(m, p["checker"], p["point"], p["normal"]),
                                       finish(m)))
        if m["transmit"] > 0:
            w("  interior { ior %s }" % num(m["ior"]))
        w("}")
        if m["transmit"] > 0 and shadow_clones:
            for offset in (CLONE_SHIFT, -CLONE_SHIFT):
                w("plane { %s, %s%s" % (vec(n), num(d + offset), CLONE))
    return "\n".join(out) + "\n"


def opaque_warnings(scene):
    """Materials whose ambient/diffuse POV-Ray cannot show (kt = 1)."""
    count = sum(1 for o in scene["spheres"] + scene["planes"]
                if o["material"]["transmit"] >= 1
                and (o["material"]["ambient"] > 0 or o["material"]["diffuse"] > 0))
    return count


# ---- running POV-Ray --------------------------------------------------------------

class RunError(Exception):
    pass


def povray_version(exe):
    try:
        done = subprocess.run([exe, "--version"], capture_output=True, text=True, timeout=60)
    except OSError as e:
        raise RunError("cannot run %s: %s" % (exe, e.strerror or e))
    for line in (done.stdout + "\n" + done.stderr).splitlines():
        if line.startswith("POV-Ray "):
            return line.strip()
    raise RunError("%s --version printed no POV-Ray version" % exe)


TRACE_TIME = re.compile(r"Trace Time:.*?\(([0-9.]+) seconds\)\s*\n\s*using (\d+) thread\(s\) "
                        r"with ([0-9.]+) CPU-seconds")


def povray_error(text):
    """The most telling line of POV-Ray's output after a failure."""
    lines = [l.strip() for l in text.splitlines() if l.strip()]
    for line in lines:
        if "error" in line.lower() and "configuration file" not in line:
            return line
    return lines[-1] if lines else "no output"


def render(exe, pov_text, size, threads, runs, image):
    """Render pov_text runs times; return (command, [(wall, trace, threads, cpu)])."""
    ext = ".ppm" if image and image.lower().endswith(".ppm") else ".png"
    results = []
    with tempfile.TemporaryDirectory(prefix="rtcl-povray-") as tmp:
        with open(os.path.join(tmp, "scene.pov"), "w", encoding="utf-8") as f:
            f.write(pov_text)
        out_name = "render" + ext
        cmd = [exe, "+Iscene.pov", "+O" + out_name, "+W%d" % size[0], "+H%d" % size[1],
               "-A", "+WT%d" % threads, "-D", "+FP" if ext == ".ppm" else "+FN",
               "File_Gamma=1.0"]
        for _ in range(runs):
            out_path = os.path.join(tmp, out_name)
            if os.path.exists(out_path):
                os.remove(out_path)
            start = time.perf_counter()
            done = subprocess.run(cmd, cwd=tmp, capture_output=True, text=True,
                                  errors="replace")
            wall = time.perf_counter() - start
            text = done.stdout + "\n" + done.stderr
            if done.returncode != 0 or not os.path.exists(out_path):
                raise RunError("povray failed (exit %d): %s" % (done.returncode, povray_error(text)))
            m = TRACE_TIME.search(text)
            if m:
                results.append((wall, float(m.group(1)), int(m.group(2)), float(m.group(3))))
            else:
                results.append((wall, None, None, None))
        if image:
            write_atomically(image, os.path.join(tmp, out_name))
    return cmd, results


def write_atomically(target, source=None, text=None):
    """Write text (or copy file source) to target through a temporary file beside it."""
    directory = os.path.dirname(os.path.abspath(target))
    try:
        fd, tmp = tempfile.mkstemp(prefix=".povray-", dir=directory)
    except OSError as e:
        raise OSError(e.errno, e.strerror, target)
    try:
        with os.fdopen(fd, "wb") as out:
            if text is not None:
                out.write(text.encode("utf-8"))
            else:
                with open(source, "rb") as src:
                    shutil.copyfileobj(src, out)
        os.chmod(tmp, 0o644)
        os.replace(tmp, target)
    except BaseException:
        if os.path.exists(tmp):
            os.remove(tmp)
        raise


def summary(values):
    return "median %.3f s, min %.3f s, max %.3f s" % (statistics.median(values), min(values),
                                                       max(values))


def main(argv=None):
    parser = argparse.ArgumentParser(
        description="Convert an rtcl scene to POV-Ray 3.7 SDL; optionally time POV-Ray on it.",
        epilog="The module docstring lists how the scene maps and what differs.")
    parser.add_argument("-s", "--scene", default=DEFAULT_SCENE, metavar="FILE",
                        help="rtcl scene (default scenes/paper60.json)")
    parser.add_argument("--size", type=parse_size, metavar="WxH",
                        help="image size (default the scene's)")
    parser.add_argument("--depth", type=int, metavar="N",
                        help="max_depth 0 ... 64 (default the scene's); max_trace_level is N+1")
    parser.add_argument("-o", "--output", metavar="FILE.pov",
                        help="write the SDL here (default stdout, unless --time or --image)")
    parser.add_argument("--time", type=int, metavar="N",
                        help="render N times with povray and print the wall and trace times")
    parser.add_argument("--image", metavar="FILE",
                        help="keep the rendered image (.png, or .ppm); renders once without --time")
    parser.add_argument("--threads", type=int, default=2, metavar="N",
                        help="POV-Ray render threads, +WT (default %(default)s)")
    parser.add_argument("--transparent-shadows", action="store_true",
                        help="no opaque shadow clones: POV-Ray's filtered shadows")
    parser.add_argument("--povray", default="povray", metavar="EXE",
                        help="POV-Ray executable (default %(default)s)")
    args = parser.parse_args(argv)
    if args.depth is not None and not 0 <= args.depth <= 64:
        parser.error("--depth must be 0 ... 64, got %d" % args.depth)
    if args.time is not None and args.time < 1:
        parser.error("--time must be >= 1, got %d" % args.time)
    if args.threads < 1:
        parser.error("--threads must be >= 1, got %d" % args.threads)
    if args.image and not args.image.lower().endswith((".png", ".ppm")):
        parser.error("--image must end in .png or .ppm, got %r" % args.image)

    try:
        scene = load_scene(args.scene)
    except SceneError as e:
        print("%s: %s: %s" % (PROG, args.scene, e), file=sys.stderr)
        return 1
    size = args.size or scene["size"]
    depth = scene["max_depth"] if args.depth is None else args.depth
    text = to_sdl(scene, size, depth, os.path.relpath(args.scene, ROOT)
                  if os.path.abspath(args.scene).startswith(ROOT + os.sep) else args.scene,
                  shadow_clones=not args.transparent_shadows)
    dropped = opaque_warnings(scene)
    if dropped:
        print("%s: warning: %d object(s) with transmit 1: POV-Ray shows no ambient or diffuse"
              " on them" % (PROG, dropped), file=sys.stderr)

    try:
        if args.output:
            write_atomically(args.output, text=text)
        elif args.time is None and not args.image:
            sys.stdout.write(text)
        if args.time is None and not args.image:
            return 0

        exe = shutil.which(args.povray)
        if exe is None:
            raise RunError("%s not found on PATH (apt-get install povray)" % args.povray)
        version = povray_version(exe)
        load = os.getloadavg()
        runs = args.time or 1
        cmd, results = render(exe, text, size, args.threads, runs, args.image)
    except RunError as e:
        print("%s: %s" % (PROG, e), file=sys.stderr)
        return 1
    except OSError as e:
        print("%s: %s: %s" % (PROG, e.filename or "", e.strerror or e), file=sys.stderr)
        return 1

    n_clones = 0 if args.transparent_shadows else sum(
        1 for o in scene["spheres"] + scene["planes"] if o["material"]["transmit"] > 0)
    print("povray: %s (%s)" % (version, exe))
    print("scene: %s, %dx%d, max_depth %d -> max_trace_level %d; %d spheres, %d planes, "
          "%d lights, %d shadow clones" % (args.scene, size[0], size[1], depth, depth + 1,
                                          len(scene["spheres"]), len(scene["planes"]),
                                          len(scene["lights"]), n_clones))
    print("command (in a temporary directory holding scene.pov): %s" % " ".join(cmd))
    print("load average before: %.2f %.2f %.2f (%d CPUs)" % (load + (os.cpu_count() or 0,)))
    for i, (wall, trace, threads, cpu) in enumerate(results, 1):
        if trace is None:
            print("run %d: wall %.3f s (POV-Ray printed no trace time)" % (i, wall))
        else:
            print("run %d: wall %.3f s, POV-Ray trace time %.3f s (%d threads, %.3f CPU-s)"
                  % (i, wall, trace, threads, cpu))
    print("wall time over %d run(s): %s" % (len(results), summary([r[0] for r in results])))
    traces = [r[1] for r in results if r[1] is not None]
    if traces:
        print("POV-Ray trace time over %d run(s): %s" % (len(traces), summary(traces)))
    if args.image:
        print("image: %s" % args.image)
    return 0


if __name__ == "__main__":
    sys.exit(main())
