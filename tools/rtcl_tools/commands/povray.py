"""Convert an rtcl scene (docs/SCENE.md) into POV-Ray 3.7 SDL, and time POV-Ray on it.

This is the baseline of rtcl's CPU performance target (issue 4): PoCL on a 2-core
machine must need at most half the time that POV-Ray 3.7 (Debian's `povray`,
+WT2, no antialiasing, adc_bailout 0, max_trace_level = depth + 1) needs for an
equivalent scene at the same size.  The SDL written here is as close to
docs/RENDERING.md as POV-Ray allows; what differs is listed below.

    rtcl-povray                                   # the paper's 60 balls as SDL, on stdout
    rtcl-povray -s scenes/two_balls.json --size 64x48 -o balls.pov
    rtcl-povray --time 3 --size 2000x2000         # median/min/max of 3 POV-Ray renders
    rtcl-povray -s scenes/tir.json --image tir.png  # render once, keep the image
    rtcl-povray --time 3 --transparent-shadows    # POV-Ray's own filtered shadows
(tools/povray.py in a checkout is the same command.)  Without -s, the scene is
the paper's 60 balls, rtcl's built-in paper60 (scenes/paper60.json), made here as
tools/genscene.py makes it, so that an installed copy needs no scene file.
Neither -o nor --image replaces a file tracked by git, or the scene or a mesh it
reads (by path, link or inode).

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
9. Version 2 (rtcl_tools/povray_mesh.py): a mesh becomes a mesh2, placed and
   with its smooth normals computed here as rtcl does; an inline triangle a
   triangle.  Only the binary PLY meshes tools/genbench.py writes are read (any
   other mesh file is refused).  A transparent mesh gets inside_vector (rtcl
   takes every mesh as closed) and no shadow clone: its shadow is POV-Ray's
   filtered one, where rtcl's is opaque.
"""

import argparse
import os
import shutil
import sys

from ..requirements import require

require("numpy")  # the meshes

from .. import files, genscene  # noqa: E402
from ..interrupts import interruptible  # noqa: E402
from ..locations import SOURCE_ROOT  # noqa: E402
from ..povray_mesh import MeshError  # noqa: E402
from ..povray_run import RunError, povray_version, render, summary  # noqa: E402
from ..povray_sdl import opaque_warnings, to_sdl  # noqa: E402
from ..scene import SceneError, load_scene, read_scene  # noqa: E402
from ..usage import os_error_message, parse_size, program_name  # noqa: E402

ROOT = str(SOURCE_ROOT)
# Without -s: rtcl's built-in paper60, which tools/genscene.py's defaults make
# byte for byte (scenes/paper60.json; test/test_povray.py checks it).
DEFAULT_SCENE_NAME = "paper60 (built in)"


def default_scene():
    """Returns the paper's 60-ball scene, made as tools/genscene.py makes it."""
    return read_scene(genscene.build_scene(genscene.REFERENCE_BALLS, genscene.DEFAULT_SEED,
                                           (2000, 2000), 5))


def parse_arguments(argv):
    parser = argparse.ArgumentParser(
        description="Convert an rtcl scene to POV-Ray 3.7 SDL; optionally time POV-Ray on it.",
        epilog="The module docstring lists how the scene maps and what differs.")
    parser.add_argument("-s", "--scene", metavar="FILE",
                        help="rtcl scene (default: the paper's 60 balls, rtcl's built-in "
                             "paper60)")
    parser.add_argument("--size", type=parse_size, metavar="WxH",
                        help="image size (default the scene's)")
    parser.add_argument("--depth", type=int, metavar="N",
                        help="max_depth 0 ... 64 (default the scene's); max_trace_level is N+1")
    parser.add_argument("-o", "--output", "--out", metavar="FILE.pov",
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
    return args


def print_report(args, scene, size, depth, version, exe, cmd, load, results):
    """Prints what ran and every run's times (the output of --time and --image)."""
    n_clones = 0 if args.transparent_shadows else sum(
        1 for o in scene["spheres"] + scene["planes"] if o["material"]["transmit"] > 0)
    print("povray: %s (%s)" % (version, exe))
    print("scene: %s, %dx%d, max_depth %d -> max_trace_level %d; %d spheres, %d planes, "
          "%d lights, %d shadow clones" % (args.scene or DEFAULT_SCENE_NAME, size[0], size[1],
                                          depth, depth + 1,
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


def scene_label(path):
    """Returns how the SDL's header names the scene: relative to the source tree
    when it lies in it."""
    if path is None:
        return DEFAULT_SCENE_NAME
    if os.path.abspath(path).startswith(ROOT + os.sep):
        return os.path.relpath(path, ROOT)
    return path


@interruptible
def main(argv=None):
    args = parse_arguments(argv)
    prog = program_name()
    try:
        scene = load_scene(args.scene) if args.scene else default_scene()
    except (SceneError, OSError) as e:
        message = e.strerror if isinstance(e, OSError) else e
        print("%s: %s: %s" % (prog, args.scene, message), file=sys.stderr)
        return 1
    files.reading([args.scene, *(mesh["file"] for mesh in scene.get("meshes", []))])
    try:   # refused before the conversion and the renders, not after
        files.check_outputs([path for path in (args.output, args.image) if path])
    except OSError as e:
        print("%s: %s" % (prog, os_error_message(e)), file=sys.stderr)
        return 1
    size = args.size or scene["size"]
    depth = scene["max_depth"] if args.depth is None else args.depth
    try:
        text = to_sdl(scene, size, depth, scene_label(args.scene),
                      shadow_clones=not args.transparent_shadows)
    except MeshError as e:
        print("%s: %s: %s" % (prog, args.scene, e), file=sys.stderr)
        return 1
    dropped = opaque_warnings(scene)
    if dropped:
        print("%s: warning: %d object(s) with transmit 1: POV-Ray shows no ambient or diffuse"
              " on them" % (prog, dropped), file=sys.stderr)

    try:
        if args.output:
            files.write_text(args.output, text)
        elif args.time is None and not args.image:
            sys.stdout.write(text)
        if args.time is None and not args.image:
            return 0

        exe = shutil.which(args.povray)
        if exe is None:
            raise RunError("%s not found on PATH (apt-get install povray)" % args.povray)
        version = povray_version(exe)
        load = os.getloadavg()
        cmd, results = render(exe, text, size, args.threads, args.time or 1, args.image)
    except RunError as e:
        print("%s: %s" % (prog, e), file=sys.stderr)
        return 1
    except OSError as e:
        print("%s: %s" % (prog, os_error_message(e)), file=sys.stderr)
        return 1
    print_report(args, scene, size, depth, version, exe, cmd, load, results)
    return 0

