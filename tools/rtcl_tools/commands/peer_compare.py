"""rtcl's traversal against a peer's on the same rays: primary, bounce and shadow rays.

The peer is TinyBVH's OpenCL harness (a folder holding side.cpp, its .cl files,
tiny_bvh.h, tiny_ocl.h and ply2bin.py, given as PEER): its `side` program traces
one primary ray per pixel with rtcl's pinhole camera through each of TinyBVH's
GPU kernels. For every mesh this tool

  1. makes the mesh with rtcl-genbench (--meshes: SPD tetra and mount at a size,
     the lake) or takes a PLY file (--ply), and turns it into the peer's .bin
     with the peer's ply2bin.py, so that both trace the same floats;
  2. writes an rtcl scene of that mesh alone, at identity placement, with
     the scene's camera, max_depth 0 and no lights: primary rays only;
  3. times rtcl's kernels (--kernels, -r N: the median of the OpenCL
     profiling events of N launches) and the peer's kernels (--variants, N
     passes, its median), on the same image size;
  4. writes compare.md (both sides, rays per second and the ratio of rtcl's
     fastest kernel to the peer's fastest: above 1, rtcl is faster) and
     compare.csv, and keeps every raw output under raw/.

It runs where the GPU is (NVIDIA's OpenCL; the peer's kernels do not build on
PoCL) and needs g++ and the OpenCL headers there to build `side`.

--counts counts instead of timing, on any machine and any OpenCL device (PoCL
too): for every mesh, rtcl's counting build (--flops) gives its BVH node
visits, leaf visits and sphere and triangle tests per ray, and peer_counts.cpp,
built here against the peer's tiny_bvh.h, traces the same rays on the host
through the peer's BVH_GPU layout (its fastest GPU kernel's), built HQ and SAH
as `side` builds them, counting its loop iterations (interior nodes and leaves)
and triangle tests per ray. counts.md sets them side by side: where the two
traversals differ in work, before any difference in speed.

--cpu times the peer's CPU traversals instead (its `cside`: TinyBVH's BVH,
BVH4_CPU and BVH8_CPU over the same rays on every hardware thread, built here
with -march=native) against rtcl on a CPU OpenCL device (PoCL): the first CPU of platform -p,
else of the first platform that has one (rtcl's default device is a GPU
wherever there is one); a platform with no CPU is refused. Into cpu.md:
where rtcl stands on a CPU, the device named in its header. It writes to
-o/--out DIR, by default a new folder rtcl-results/peer-<YYYYmmdd-HHMMSS>; a
file tracked by git is replaced only with --update-committed.

--rays traces incoherent rays too (issue 42): for every mesh, peer_rays.cpp
(built here against the peer's tiny_bvh.h) makes three ray files once --
the primary rays (rtcl's camera, one a pixel in 8x4 tiles), one diffuse
bounce from each primary hit (cosine-distributed about the hit triangle's
normal, from an integer hash of the pixel: peer_rays.cpp documents it) and a
shadow ray from each of those hit points to a point light (any hit) -- and
both sides trace the very same rays from those files: rtcl with rtcl-rays
(its traversal, the BVH and program a render builds, one work-item a ray;
built beside rtcl by make) and the peer with its GPU kernels
(peer_rays_gpu.cpp, the --variants; needs g++ and the OpenCL headers), or,
with --cpu, with its CPU traversals (BVH, BVH4_CPU, BVH8_CPU on every
hardware thread) against rtcl on a CPU OpenCL device (PoCL, chosen as
for --cpu). rays.md and
rays.csv give, per mesh and kind of ray, each side's median time and rays
per second, the ratio, the hits of each and how many rays the two sides
agree on (the same hit or miss; for closest hits the same triangle or the
same distance within 1e-4 of it); --rounds N runs the two sides in turn N
times (each side's time the median of its rounds, each round's ratio shown).

    rtcl-peer-compare ../shared/bench/tinybvh --meshes tetra:8,mount:9,lake -r 10
    rtcl-peer-compare PEER --ply bunny.ply --size 1000x1000
    rtcl-peer-compare PEER --counts -o counts      # work per ray, no GPU needed
    rtcl-peer-compare PEER --cpu --meshes tetra:8,mount:8 -o cpu   # on PoCL
    rtcl-peer-compare PEER --rays --meshes tetra:8,mount:9,lake -r 10     # on the GPU
    rtcl-peer-compare PEER --rays --cpu --meshes mount:8 --size 500x500 -r 3
"""
import argparse
import json
import math
import pathlib
import re
import statistics
import subprocess
import sys

from .. import files, locations, ppm
from . import genbench
from ..interrupts import interruptible
from ..report import git_commit, markdown_table, one_line, to_csv, utc_now
from ..usage import (UsageError, add_rtcl_option, add_update_committed, check_positive_int,
                     parse_size, program_name, report_error)

DEFAULT_MESHES = "tetra:8,mount:8,mount:9,lake"
BACKGROUND = (1, 0, 1)
PEER_SOURCES = ("side.cpp", "tiny_bvh.h", "tiny_ocl.h", "ply2bin.py")
COUNTER_SOURCE = pathlib.Path(__file__).resolve().parent.parent / "peer_counts.cpp"
RAYS_SOURCE = COUNTER_SOURCE.with_name("peer_rays.cpp")
RAYS_GPU_SOURCE = COUNTER_SOURCE.with_name("peer_rays_gpu.cpp")
RAYS_KERNELS = COUNTER_SOURCE.with_name("peer_rays.cl")
RAY_KINDS = ("primary", "bounce", "shadow")
RAYS_LINE = re.compile(r"^rtcl-rays: .*?; (\d+) (closest-hit|any-hit) rays, median ([\d.]+) ms, "
                       r"min ([\d.]+) ms .*hits (\d+);")
PEER_RAYS_LINE = re.compile(r"^(.+?)\s+build\s+([\d.]+) ms\s+trace median\s+([\d.]+) ms\s+"
                            r"min\s+([\d.]+) ms.*?(?:hits (\d+))?$")
RAYS_CSV = ("mesh", "triangles", "rays", "count", "round", "side", "traversal", "median_ms",
            "min_ms", "mrays_per_s", "hits")
COUNTS_LINE = re.compile(r"^(BVH_GPU \w+): iterations per ray ([\d.]+), triangle tests per "
                         r"ray ([\d.]+), hits (\d+), nodes (\d+), build ms ([\d.]+)")
CSV_COLUMNS = ("mesh", "triangles", "side", "kernel", "median_ms", "min_ms", "grays_per_s")


class Failure(Exception):
    """A step that failed, in one line."""


def parse_arguments(argv):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter,
                                     epilog=__doc__.split("\n\n", 1)[1])
    parser.add_argument("peer", metavar="PEER", type=pathlib.Path,
                        help="the peer's folder (TinyBVH's harness: side.cpp, *.cl, ply2bin.py)")
    parser.add_argument("--meshes", default=DEFAULT_MESHES,
                        help="genbench meshes, comma-separated: tetra:N, mount:N, lake "
                             f"(default {DEFAULT_MESHES}; '' for none)")
    parser.add_argument("--ply", action="append", default=[], type=pathlib.Path,
                        metavar="FILE", help="a PLY mesh to compare too (repeatable); "
                        "its camera frames its bounding box")
    parser.add_argument("--size", default=(2000, 2000), type=parse_size,
                        help="image size WxH (default 2000x2000)")
    parser.add_argument("-r", "--repeat", default="10",
                        help="timed launches of each kernel (default 10)")
    parser.add_argument("-k", "--kernels", default="persistent,dynamic",
                        help="rtcl kernels (default persistent,dynamic)")
    parser.add_argument("--variants", default="aA",
                        help="the peer's kernels: letters of side.cpp (default aA: "
                             "BVH_GPU built HQ and SAH)")
    add_rtcl_option(parser)
    parser.add_argument("-p", "--platform", help="rtcl's OpenCL platform (default: NVIDIA's; "
                                                 "with --counts, rtcl's default device; with "
                                                 "--cpu, the first with a CPU, its first CPU)")
    parser.add_argument("--rays", action="store_true",
                        help="trace primary rays, one diffuse bounce from each primary hit "
                             "and shadow rays to a point light, the same rays on both "
                             "sides from files made once (rays.md); with --cpu on a CPU")
    parser.add_argument("--rounds", default="1",
                        help="with --rays: rounds of both sides in turn, each side's time "
                             "the median of its rounds (default 1)")
    mode = parser.add_mutually_exclusive_group()
    mode.add_argument("--counts", action="store_true",
                      help="count node visits and triangle tests per ray on both sides "
                           "instead of timing (counts.md); runs on any machine")
    mode.add_argument("--cpu", action="store_true",
                      help="time the peer's CPU traversals (cside) against rtcl on a CPU "
                           "OpenCL device (cpu.md)")
    parser.add_argument("-o", "--out", type=pathlib.Path, metavar="DIR",
                        help="results folder (default: a new rtcl-results/peer-<time>)")
    add_update_committed(parser)
    return parser.parse_args(sys.argv[1:] if argv is None else argv)


def run(command, log, cwd=None):
    """Runs command, keeping its output in log; returns stdout, or Failure."""
    result = subprocess.run([str(part) for part in command], cwd=cwd, capture_output=True,
                            text=True)
    files.write_text(log, f"$ {' '.join(map(str, command))}\n{result.stdout}{result.stderr}")
    if result.returncode != 0:
        last = (result.stderr.strip() or result.stdout.strip() or "no message").splitlines()[-1]
        raise Failure(f"{pathlib.Path(str(command[0])).name} failed ({log}): {last}")
    return result.stdout


def build_peer(peer, out):
    missing = [name for name in PEER_SOURCES if not (peer / name).is_file()]
    if missing:
        raise Failure(f"{peer} is not the peer's folder: no {', '.join(missing)}")
    folder = out / "peer"
    folder.mkdir(parents=True, exist_ok=True)
    for source in peer.glob("*.cl"):
        files.copy_file(source, folder / source.name)
    run(["g++", "-O3", "-march=x86-64-v3", "-std=c++20", "-I/usr/include/CL",
         peer / "side.cpp", "-o", folder / "side", "-lOpenCL", "-lpthread"],
        out / "raw" / "build-side.txt")
    return folder


def nvidia_platform(rtcl, out):
    listing = run([rtcl, "--list-devices"], out / "raw" / "devices.txt")
    for line in listing.splitlines():
        match = re.match(r"Platform #?(\d+):.*NVIDIA", line)
        if match:
            return match.group(1)
    raise Failure("no NVIDIA platform in rtcl --list-devices: give -p N")


LISTED_PLATFORM = re.compile(r"^Platform #(\d+): (.*)$")
LISTED_DEVICE = re.compile(r"^ [|`]-- Device #(\d+): (.*) \((\w+), \d+ compute units")


def cpu_device(listing, platform=None):
    """--cpu's device from rtcl --list-devices' text: the first CPU of the
    platform -p gave, else of the first platform that has one, as
    (platform, device, its name); Failure, saying what to pass, when there
    is none. rtcl's default device is a GPU wherever there is one."""
    platforms, current = {}, None
    for line in listing.splitlines():
        listed, device = LISTED_PLATFORM.match(line), LISTED_DEVICE.match(line)
        if listed:
            current = listed.group(1)
            platforms[current] = (listed.group(2), [])
        elif device and current is not None:
            platforms[current][1].append(device.groups())
    cpus = [(number, index, name) for number, (_, devices) in platforms.items()
            for index, name, kind in devices if kind == "CPU"]
    if platform is None:
        if not cpus:
            raise Failure("--cpu: no CPU OpenCL device in rtcl --list-devices (install PoCL, "
                          "or leave out --cpu to time the GPU)")
        return cpus[0]
    if platform not in platforms:
        raise Failure(f"--cpu: -p {platform}: no such platform in rtcl --list-devices")
    mine = [cpu for cpu in cpus if cpu[0] == platform]
    if mine:
        return mine[0]
    name, devices = platforms[platform]
    kinds = ", ".join(kind for _, _, kind in devices) or "no device"
    hint = f"pass -p {cpus[0][0]} ({platforms[cpus[0][0]][0]})" if cpus else "install PoCL"
    raise Failure(f"--cpu: platform {platform} ({name}) has no CPU device ({kinds}): {hint}")


def rtcl_cpu_device(rtcl, platform, out):
    """cpu_device over rtcl --list-devices: -p and -d for rtcl and rtcl-rays."""
    chosen = cpu_device(run([rtcl, "--list-devices"], out / "raw" / "devices.txt"), platform)
    print(f"--cpu: rtcl on platform {chosen[0]}, device {chosen[1]} ({chosen[2]})", flush=True)
    return ["-p", chosen[0], "-d", chosen[1]]


def genbench_mesh(spec, out):
    """(name, PLY path, scene dict) of a genbench mesh spec: tetra:N, mount:N, lake."""
    kind, _, size = spec.partition(":")
    if kind not in ("tetra", "mount", "lake") or (kind != "lake") != bool(size):
        raise Failure(f"--meshes: {spec!r} is not tetra:N, mount:N or lake")
    folder = out / "meshes" / spec.replace(":", "-")
    # The lake's triangles are always in a PLY; tetra and mount keep small ones inline.
    options = ["--size", size, "--triangles", "ply"] if size else []
    if genbench.main([kind, "-o", str(folder), *options]) != 0:
        raise Failure(f"rtcl-genbench could not make {spec}")
    (scene_path,) = folder.glob("*.json")
    scene = json.loads(scene_path.read_text())
    (mesh,) = scene["meshes"]
    return spec.replace(":", "-"), folder / mesh["file"], scene


def framing_scene(ply, bin_path):
    """A scene that frames the mesh of bin_path (the .bin of ply) from its box."""
    import numpy as np  # only --ply needs it here; genbench and ply2bin need it anyway

    data = np.fromfile(bin_path, dtype="<f4", offset=4).reshape(-1, 4)[:, :3]
    low, high = data.min(axis=0), data.max(axis=0)
    centre, radius = (low + high) / 2, float(np.linalg.norm(high - low)) / 2 or 1.0
    distance = radius / math.tan(math.radians(45) / 2)
    eye = centre + distance * np.array([0.5, 0.4, 1.0]) / np.linalg.norm([0.5, 0.4, 1.0])
    return {"format": "rtcl-scene", "version": 2,
            "camera": {"eye": [float(v) for v in eye], "look_at": [float(v) for v in centre],
                       "fov": 45},
            "meshes": [{"file": str(ply.resolve())}]}


def primary_scene(scene, ply, width, height):
    """The mesh alone at identity placement: primary rays only."""
    mesh = dict(scene["meshes"][0])
    for key in ("scale", "rotate", "translate"):
        if key in mesh:
            raise Failure(f"{ply}: the scene places its mesh with {key!r}: the peer "
                          "would trace other floats")
    mesh["file"] = str(ply.resolve())
    kept = {key: scene[key] for key in ("format", "camera", "materials") if key in scene}
    # Magenta behind the mesh: the pixels of another colour are the hits.
    return {**kept, "version": 2, "image": {"width": width, "height": height},
            "background": list(BACKGROUND),
            "max_depth": 0, "lights": [], "meshes": [mesh]}


def count_hits(image):
    """The pixels of a PPM that are not the background: the rays that hit."""
    _, data = ppm.pixels(image)
    background = bytes(255 * channel for channel in BACKGROUND)
    return sum(data[i:i + 3] != background for i in range(0, len(data), 3))


def device_options(platform):
    """rtcl's -p (and -d) for platform: a platform's number, rtcl_cpu_device's
    options, or None for rtcl's default device."""
    return list(platform) if isinstance(platform, list) else ["-p", platform] if platform else []


def time_rtcl(rtcl, platform, scene_path, kernel, repeat, out, name):
    stats = out / "raw" / f"rtcl-{name}-{kernel}.json"
    image = out / "meshes" / f"rtcl-{name}-{kernel}.ppm"
    device = device_options(platform)
    run([rtcl, "-q", *device, "-k", kernel, "-r", repeat, scene_path,
         "-o", image, "--stats", stats], out / "raw" / f"rtcl-{name}-{kernel}.txt")
    figures = json.loads(stats.read_text())
    times = figures["kernel_ms_all"]
    return statistics.median(times), min(times), figures, count_hits(image)


PEER_LINE = re.compile(r"^(.+?)\s+build\s+([\d.]+) ms\s+trace median ([\d.]+) ms\s+min ([\d.]+) ms")


def time_peer(side_folder, bin_path, scene, width, height, repeat, variants, out, name):
    camera = scene["camera"]
    up = camera.get("up", [0, 1, 0])
    output = run([side_folder / "side", bin_path.resolve(), width, height, *camera["eye"],
                  *camera["look_at"], camera.get("fov", 45), repeat, variants, *up],
                 out / "raw" / f"peer-{name}.txt", cwd=side_folder)
    rows = []
    for line in output.splitlines():
        match = PEER_LINE.match(line)
        hits = re.match(r"\s*hits (\d+)", line)
        if match:
            rows.append([match.group(1).strip(), float(match.group(3)), float(match.group(4)),
                         float(match.group(2)), None])
        elif hits and rows:
            rows[-1][4] = int(hits.group(1))
    if not rows:
        raise Failure(f"the peer printed no timing ({out / 'raw' / f'peer-{name}.txt'})")
    triangles = int(re.search(r"triangles (\d+)", output).group(1))
    return triangles, rows


def build_counter(peer, out):
    """Builds peer_counts against the peer's tiny_bvh.h; returns its path."""
    if not (peer / "tiny_bvh.h").is_file():
        raise Failure(f"{peer} is not the peer's folder: no tiny_bvh.h")
    program = out / "peer" / "peer_counts"
    program.parent.mkdir(parents=True, exist_ok=True)
    run(["g++", "-O3", "-march=native", "-std=c++20", "-I", peer, COUNTER_SOURCE, "-o",
         program, "-lpthread"], out / "raw" / "build-peer-counts.txt")
    return program


def mesh_scenes(args, out, width, height):
    """Yields (name, .bin path, scene dict, primary-ray scene path) for every mesh."""
    meshes = [genbench_mesh(spec, out) for spec in args.meshes.split(",") if spec]
    for ply in args.ply:
        if not ply.is_file():
            raise Failure(f"--ply {ply}: no such file")
    for name, ply, scene in meshes + [(ply.stem, ply, None) for ply in args.ply]:
        bin_path = out / "meshes" / f"{name}.bin"
        run([sys.executable, args.peer / "ply2bin.py", ply, bin_path],
            out / "raw" / f"ply2bin-{name}.txt")
        if scene is None:
            scene = framing_scene(ply, bin_path)
        scene_path = out / "meshes" / f"{name}-primary.json"
        files.write_text(scene_path, json.dumps(primary_scene(scene, ply, width, height),
                                                indent=1))
        yield name, bin_path, scene, scene_path


def count_rtcl(rtcl, platform, scene_path, out, name):
    """rtcl's counting run of the persistent kernel: its --stats."""
    stats = out / "raw" / f"rtcl-counts-{name}.json"
    device = device_options(platform)
    run([rtcl, "-q", *device, "-k", "persistent", scene_path, "-o",
         out / "meshes" / f"rtcl-counts-{name}.ppm", "--flops", out / "meshes" / "f.npy",
         "--stats", stats], out / "raw" / f"rtcl-counts-{name}.txt")
    (out / "meshes" / "f.npy").unlink(missing_ok=True)
    (out / "meshes" / "f.npy.json").unlink(missing_ok=True)
    return json.loads(stats.read_text())


def count_peer(program, bin_path, scene, width, height, out, name):
    """The peer's counts: {build: (iterations, tests, hits, nodes, build ms)}."""
    camera = scene["camera"]
    output = run([program, bin_path.resolve(), width, height, *camera["eye"],
                  *camera["look_at"], camera.get("fov", 45), *camera.get("up", [0, 1, 0])],
                 out / "raw" / f"peer-counts-{name}.txt")
    found = {}
    for line in output.splitlines():
        match = COUNTS_LINE.match(line)
        if match:
            found[match.group(1)] = (float(match.group(2)), float(match.group(3)),
                                     int(match.group(4)), int(match.group(5)),
                                     float(match.group(6)))
    if not found:
        raise Failure(f"peer_counts printed no counts ({out / 'raw' / f'peer-counts-{name}.txt'})")
    found["triangles"] = int(re.search(r"triangles (\d+)", output).group(1))
    return found


CSIDE_LINE = re.compile(r"^(\S+(?: \(HQ\))?)\s+build\s+([\d.]+) ms\s+trace median\s+([\d.]+) ms"
                        r".*\((\d+) threads\), hits (\d+)")


def cpu(args, rtcl, out):
    """--cpu: the peer's CPU traversals against rtcl on a CPU device, into cpu.md."""
    width, height = args.size
    repeat = str(check_positive_int("-r/--repeat", args.repeat))
    if not (args.peer / "cside.cpp").is_file() or not (args.peer / "tiny_bvh.h").is_file():
        raise Failure(f"{args.peer} is not the peer's folder: no cside.cpp or tiny_bvh.h")
    device_chosen = rtcl_cpu_device(rtcl, args.platform, out)
    program = out / "peer" / "cside"
    program.parent.mkdir(parents=True, exist_ok=True)
    run(["g++", "-O3", "-march=native", "-std=c++20", "-I", args.peer, args.peer / "cside.cpp",
         "-o", program, "-lpthread"], out / "raw" / "build-cside.txt")
    rows, device = [], "?"
    for name, bin_path, scene, scene_path in mesh_scenes(args, out, width, height):
        camera = scene["camera"]
        output = run([program, bin_path.resolve(), width, height, *camera["eye"],
                      *camera["look_at"], camera.get("fov", 45),
                      *camera.get("up", [0, 1, 0])], out / "raw" / f"cside-{name}.txt")
        peer = [match.groups() for match in map(CSIDE_LINE.match, output.splitlines())
                if match]
        if not peer:
            raise Failure(f"cside printed no timing ({out / 'raw' / f'cside-{name}.txt'})")
        best_peer = min(peer, key=lambda row: float(row[2]))
        timed = []
        for kernel in args.kernels.split(","):
            median, _, figures, hits = time_rtcl(rtcl, device_chosen, scene_path, kernel,
                                                 repeat, out, name)
            timed.append((median, kernel, hits))
            device = figures["device"]
        best = min(timed)
        # The peer times Intersect over rays made beforehand; rtcl's kernel
        # also makes each ray and writes its pixel. Its fastest kernel on
        # the same camera with nothing to hit is that share.
        empty_path = out / "meshes" / f"{name}-nothing.json"
        nothing = json.loads(scene_path.read_text())
        del nothing["meshes"]
        files.write_text(empty_path, json.dumps(nothing, indent=1))
        outside = time_rtcl(rtcl, device_chosen, empty_path, best[1], repeat, out,
                            f"{name}-nothing")[0]
        traversal = best[0] - outside
        peer_ms = float(best_peer[2])
        rows.append((name, " / ".join(f"{kernel} {ms:.1f}" for ms, kernel, _ in timed),
                     " / ".join(f"{row[0]} {float(row[2]):.1f}" for row in peer),
                     f"{peer_ms / best[0]:.2f}x", f"{outside:.1f}",
                     f"{peer_ms / traversal:.2f}x" if traversal > 0 else "-",
                     f"{best[2]:,} / {int(best_peer[4]):,}", best_peer[3]))
        print(f"{name}: rtcl {best[1]} {best[0]:.1f} ms ({outside:.1f} with nothing to hit), "
              f"peer {best_peer[0]} {peer_ms:.1f} ms: {peer_ms / best[0]:.2f}x", flush=True)
    header = ("mesh", "rtcl ms (median of -r)", "peer ms (median of 5)",
              "rtcl / peer's fastest", "rtcl ms, nothing to hit",
              "the same, rtcl's time less that", "hits rtcl / peer", "peer threads")
    report = (f"# rtcl on a CPU against the peer's CPU traversals, primary rays\n\n"
              f"rtcl on {device}; the peer's cside (TinyBVH) on every hardware thread of "
              f"this machine; {width}x{height}, one primary ray per pixel; rtcl "
              f"{git_commit() or 'commit unknown'}, {utc_now()}. Peer: {args.peer}. "
              "Above 1, rtcl is faster. The peer times its traversal of rays made "
              "beforehand; rtcl's kernel also makes each ray and writes its pixel: "
              "\"nothing to hit\" is rtcl's fastest kernel on the same camera without "
              "the mesh, and the next column the ratio with that taken from rtcl's "
              "time.\n\n" + markdown_table(header, rows) + "\n")
    files.write_text(out / "cpu.md", report)
    print(report)


def counts(args, rtcl, out):
    """--counts: work per ray on both sides, into counts.md."""
    width, height = args.size
    program = build_counter(args.peer, out)
    rows = []
    for name, bin_path, scene, scene_path in mesh_scenes(args, out, width, height):
        stats = count_rtcl(rtcl, args.platform, scene_path, out, name)
        peer = count_peer(program, bin_path, scene, width, height, out, name)
        nodes, leaves = stats["node_visits_per_ray"], stats["leaf_visits_per_ray"]
        hq = peer["BVH_GPU HQ"]
        sah = peer.get("BVH_GPU SAH", (None,) * 5)
        rows.append((name, f"{peer['triangles']:,}", f"{nodes:.2f}", f"{leaves:.2f}", f"{nodes + leaves:.2f}",
                     f"{stats['primitive_tests_per_ray']:.2f}",
                     f"{hq[0]:.2f}", f"{hq[1]:.2f}",
                     f"{sah[0]:.2f}" if sah[0] is not None else "–",
                     f"{sah[1]:.2f}" if sah[1] is not None else "–",
                     f"{(nodes + leaves) / hq[0]:.2f}", f"{stats['primitive_tests_per_ray'] / hq[1]:.2f}"
                     if hq[1] else "–",
                     f"{stats['bvh']['nodes']:,} / {hq[3]:,}",
                     f"{stats['bvh']['build_ms']:.0f} / {hq[4]:.0f}"))
        print(f"{name}: rtcl {nodes + leaves:.2f} iterations, "
              f"{stats['primitive_tests_per_ray']:.2f} tests per ray; peer HQ {hq[0]:.2f}, "
              f"{hq[1]:.2f}", flush=True)
    header = ("mesh", "triangles", "rtcl node visits / ray", "rtcl leaf visits / ray",
              "rtcl iterations / ray", "rtcl triangle tests / ray",
              "peer HQ iterations / ray", "peer HQ triangle tests / ray",
              "peer SAH iterations / ray", "peer SAH triangle tests / ray",
              "iterations rtcl / peer HQ", "tests rtcl / peer HQ",
              "nodes: rtcl (2 boxes each) / peer HQ (1 box each)", "build ms rtcl / peer HQ")
    report = (f"# Work per primary ray: rtcl's BVH against the peer's BVH_GPU\n\n"
              f"{width}x{height}, one primary ray per pixel (rtcl's camera), every ray "
              f"counted, hits and misses; rtcl {git_commit() or 'commit unknown'} "
              f"(its persistent kernel's counting run), {utc_now()}. An iteration is one "
              "step of the traversal loop: an interior node (both children's boxes "
              "tested) or a leaf (its triangles tested). Peer: "
              f"{args.peer}, BVH_GPU::Intersect on the host.\n\n"
              + markdown_table(header, rows) + "\n")
    files.write_text(out / "counts.md", report)
    print(report)


def compare(args, rtcl, out):
    width, height = args.size
    repeat = str(check_positive_int("-r/--repeat", args.repeat))
    side_folder = build_peer(args.peer, out)
    platform = args.platform or nvidia_platform(rtcl, out)
    table, csv_rows = [], []
    for name, bin_path, scene, scene_path in mesh_scenes(args, out, width, height):
        triangles, peer_rows = time_peer(side_folder, bin_path, scene, width, height, repeat,
                                         args.variants, out, name)
        rtcl_rows = []
        for kernel in args.kernels.split(","):
            rtcl_rows.append((kernel, *time_rtcl(rtcl, platform, scene_path, kernel, repeat,
                                                 out, name)))
        rays = width * height
        best_rtcl = min(rtcl_rows, key=lambda row: row[1])
        best_peer = min(peer_rows, key=lambda row: row[1])
        for kernel, median, low, _, _ in rtcl_rows:
            csv_rows.append(dict(zip(CSV_COLUMNS, (name, triangles, "rtcl", kernel, median, low,
                                                   rays / median * 1e-6))))
        for variant, median, low, _, _ in peer_rows:
            csv_rows.append(dict(zip(CSV_COLUMNS, (name, triangles, "peer", variant, median, low,
                                                   rays / median * 1e-6))))
        figures = best_rtcl[3]
        table.append((name, f"{triangles:,}", f"{best_rtcl[0]} {best_rtcl[1]:.3f}",
                      f"{rays / best_rtcl[1] * 1e-6:.2f}",
                      f"{best_peer[0]} {best_peer[1]:.3f}", f"{rays / best_peer[1] * 1e-6:.2f}",
                      f"{best_peer[1] / best_rtcl[1]:.2f}x",
                      f"{figures.get('bytes_per_triangle', 0):.1f}",
                      f"{figures['bvh']['build_ms']:.0f}", f"{best_peer[3]:.0f}",
                      f"{best_rtcl[4]:,} / {best_peer[4]:,}" if best_peer[4] is not None
                      else f"{best_rtcl[4]:,} / ?",
                      # A program from rtcl's cache ran 7-16 % slower on NVIDIA
                      # before f3ae66c: say which this was.
                      "from the cache" if figures.get("build_cached") else "built"))
        print(f"{name}: rtcl {best_rtcl[0]} {best_rtcl[1]:.3f} ms, peer {best_peer[0]} "
              f"{best_peer[1]:.3f} ms: {best_peer[1] / best_rtcl[1]:.2f}x", flush=True)
    device = json.loads(next((out / "raw").glob("rtcl-*.json")).read_text())["device"]
    header = ("mesh", "triangles", "rtcl fastest (ms)", "rtcl G rays/s", "peer fastest (ms)",
              "peer G rays/s", "rtcl / peer", "rtcl bytes/tri", "rtcl build ms",
              "peer build ms", "hits rtcl / peer", "rtcl program")
    report = (f"# rtcl against the peer on primary rays\n\n{device}, {width}x{height}, one "
              f"primary ray per pixel, median of {repeat} launches (OpenCL profiling "
              f"events) on each side; rtcl {git_commit() or 'commit unknown'}, {utc_now()}.\n"
              f"Peer: {args.peer}. rtcl / peer above 1: rtcl is faster.\n\n"
              + markdown_table(header, table) + "\n")
    files.write_text(out / "compare.md", report)
    files.write_text(out / "compare.csv", to_csv(CSV_COLUMNS, csv_rows))
    print(report)


def find_rtcl_rays(rtcl):
    """rtcl-rays beside rtcl: PREFIX/lib/rtcl of an installed rtcl
    (PREFIX/bin/rtcl), or build/ of the source tree."""
    here = pathlib.Path(rtcl).resolve().parent
    for candidate in (here.parent / "lib" / "rtcl" / "rtcl-rays", here / "rtcl-rays",
                      here / "build" / "rtcl-rays",
                      locations.SOURCE_ROOT / "build" / "rtcl-rays"):
        if locations.is_program(candidate):
            return candidate
    raise Failure(f"no rtcl-rays beside {rtcl} or in build/: build it with make")


def hits_agreeing(rtcl_hits, peer_hits, any_hit):
    """(rtcl's hits, the peer's, the rays on which both agree): the same hit or
    miss and, for closest hits, the same triangle or the same distance within
    1e-4 of it (bounce rays meet triangles next to their origin, where both
    sides' distances differ by float rounding in their last bits)."""
    import numpy as np

    ours = np.fromfile(rtcl_hits, dtype="<f4").reshape(-1, 2)
    theirs = np.fromfile(peer_hits, dtype="<f4").reshape(-1, 2)
    if ours.shape != theirs.shape:
        raise Failure(f"{rtcl_hits} and {peer_hits} hold different numbers of rays")
    hit, peer_hit = ours[:, 0] > 0, theirs[:, 0] > 0
    same = hit == peer_hit
    if not any_hit:
        same_triangle = ours[:, 1].view("<i4") == theirs[:, 1].view("<i4")
        near = np.abs(ours[:, 0] - theirs[:, 0]) <= 1e-4 * np.abs(theirs[:, 0])
        same &= ~hit | same_triangle | near
    return int(hit.sum()), int(peer_hit.sum()), int(same.sum())


def build_ray_programs(args, out):
    """peer_rays (the rays' maker and the peer's CPU traversals) and, for the
    GPU, peer_rays_gpu in a folder with the peer's kernels: (maker, gpu, its folder)."""
    folder = out / "peer"
    folder.mkdir(parents=True, exist_ok=True)
    maker = folder / "peer_rays"
    run(["g++", "-O3", "-march=native", "-std=c++20", "-I", args.peer, RAYS_SOURCE, "-o", maker,
         "-lpthread"], out / "raw" / "build-peer-rays.txt")
    if args.cpu:
        return maker, None, None
    for source in list(args.peer.glob("*.cl")) + [RAYS_KERNELS]:
        files.copy_file(source, folder / source.name)
    gpu = folder / "peer_rays_gpu"
    run(["g++", "-O3", "-march=x86-64-v3", "-std=c++20", "-I", args.peer, "-I/usr/include/CL",
         RAYS_GPU_SOURCE, "-o", gpu, "-lOpenCL", "-lpthread"],
        out / "raw" / "build-peer-rays-gpu.txt")
    return maker, gpu, folder


def time_rtcl_rays(args, rtcl_rays, platform, name, scene_path, rays_file, out, tag=""):
    """rtcl-rays over one ray file: (count, any hit, median ms, min ms)."""
    kind = rays_file.stem
    log = out / "raw" / f"rtcl-rays-{name}-{kind}{tag}.txt"
    device = device_options(platform)
    line = run([rtcl_rays, *device, "-r", args.repeat, scene_path, rays_file,
                rays_file.with_suffix(".rtcl-hits")], log)
    match = RAYS_LINE.search(line)
    if not match:
        raise Failure(f"rtcl-rays printed no timing ({log})")
    return int(match.group(1)), match.group(2) == "any-hit", float(match.group(3)), \
        float(match.group(4))


def time_peer_rays(args, programs, name, bin_path, folder, out, tag=""):
    """The peer over every ray file of folder, each layout built once:
    {kind: [(traversal, median ms, min ms)]}."""
    maker, gpu, gpu_folder = programs
    pairs = [str(path.resolve()) for kind in RAY_KINDS
             for path in (folder / f"{kind}.rays", folder / f"{kind}.peer-hits")]
    log = out / "raw" / f"peer-rays-{name}{tag}.txt"
    if gpu:
        output = run([gpu, bin_path.resolve(), args.repeat, args.variants, *pairs], log,
                     cwd=gpu_folder)
    else:
        output = run([maker, "trace", bin_path.resolve(), args.repeat, *pairs], log)
    found, kind = {}, None
    for line in output.splitlines():
        section = re.match(r"^(.*)\.rays: \d+ ", line)
        match = PEER_RAYS_LINE.match(line)
        if section:
            kind = pathlib.Path(section.group(1)).name
        elif match and kind:
            found.setdefault(kind, []).append((match.group(1).strip(), float(match.group(3)),
                                               float(match.group(4))))
    if set(found) != set(RAY_KINDS):
        raise Failure(f"the peer printed no timing for some rays ({log})")
    return found


def rays(args, rtcl, out):
    """--rays: primary, bounce and shadow rays from one file each, both sides."""
    width, height = args.size
    args.repeat = str(check_positive_int("-r/--repeat", args.repeat))
    args.rounds = check_positive_int("--rounds", args.rounds)
    needed = ("tiny_bvh.h", "ply2bin.py") + (() if args.cpu else ("tiny_ocl.h", "traverse.cl"))
    missing = [name for name in needed if not (args.peer / name).is_file()]
    if missing:
        raise Failure(f"{args.peer} is not the peer's folder: no {', '.join(missing)}")
    rtcl_rays = find_rtcl_rays(rtcl)
    platform = (rtcl_cpu_device(rtcl, args.platform, out) if args.cpu
                else args.platform or nvidia_platform(rtcl, out))
    programs = build_ray_programs(args, out)
    table, csv_rows, device = [], [], None
    for name, bin_path, scene, scene_path in mesh_scenes(args, out, width, height):
        camera = scene["camera"]
        folder = out / "rays" / name
        folder.mkdir(parents=True, exist_ok=True)
        made = run([programs[0], "make", bin_path, width, height, *camera["eye"],
                    *camera["look_at"], camera.get("fov", 45), *camera.get("up", [0, 1, 0]),
                    folder], out / "raw" / f"peer-rays-make-{name}.txt")
        triangles = int(re.search(r"triangles (\d+)", made).group(1))
        # Rounds interleave the two sides, so that a machine busy with other
        # work slows both alike; each side's time is the median of its rounds.
        rounds = []
        for number in range(1, args.rounds + 1):
            tag = f"-round{number}" if args.rounds > 1 else ""
            rtcl_times = {kind: time_rtcl_rays(args, rtcl_rays, platform, name, scene_path,
                                               folder / f"{kind}.rays", out, tag)
                          for kind in RAY_KINDS}
            rounds.append((rtcl_times, time_peer_rays(args, programs, name, bin_path, folder,
                                                      out, tag)))
        for kind in RAY_KINDS:
            count, any_hit = rounds[0][0][kind][:2]
            median = statistics.median(r[0][kind][2] for r in rounds)
            low = min(r[0][kind][3] for r in rounds)
            names = [row[0] for row in rounds[0][1][kind]]
            peer = [(traversal, statistics.median(r[1][kind][i][1] for r in rounds),
                     min(r[1][kind][i][2] for r in rounds)) for i, traversal in enumerate(names)]
            per_round = [min(row[1] for row in r[1][kind]) / r[0][kind][2] for r in rounds]
            agree = hits_agreeing(folder / f"{kind}.rtcl-hits", folder / f"{kind}.peer-hits",
                                  any_hit)
            if device is None:
                device = re.search(r"^rtcl-rays: (.*?); ", next((out / "raw").glob(
                    f"rtcl-rays-{name}-{kind}*.txt")).read_text(), re.M).group(1)
            best = min(peer, key=lambda row: row[1])
            for number, (rtcl_times, peer_times) in enumerate(rounds, 1):
                csv_rows.append(dict(zip(RAYS_CSV, (
                    name, triangles, kind, count, number, "rtcl", "rtcl-rays",
                    rtcl_times[kind][2], rtcl_times[kind][3],
                    count / rtcl_times[kind][2] * 1e-3, agree[0]))))
                for traversal, peer_median, peer_low in peer_times[kind]:
                    csv_rows.append(dict(zip(RAYS_CSV, (
                        name, triangles, kind, count, number, "peer", traversal, peer_median,
                        peer_low, count / peer_median * 1e-3, agree[1]))))
            table.append((name, f"{triangles:,}", kind + (" (any hit)" if any_hit else ""),
                          f"{count:,}", f"{median:.3f}", f"{count / median * 1e-3:.1f}",
                          f"{best[0]} {best[1]:.3f}", f"{count / best[1] * 1e-3:.1f}",
                          f"{best[1] / median:.2f}x",
                          " / ".join(f"{ratio:.2f}" for ratio in per_round),
                          " / ".join(f"{row[0]} {row[1]:.3f}" for row in peer),
                          f"{agree[0]:,} / {agree[1]:,}", f"{agree[2]:,} of {count:,}"))
            print(f"{name} {kind}: rtcl {median:.3f} ms, peer {best[0]} {best[1]:.3f} ms: "
                  f"{best[1] / median:.2f}x (rounds: "
                  f"{', '.join(f'{ratio:.2f}' for ratio in per_round)}); "
                  f"agreeing {agree[2]:,} of {count:,}", flush=True)
    header = ("mesh", "triangles", "rays", "count", "rtcl ms", "rtcl M rays/s",
              "peer fastest (ms)", "peer M rays/s", "rtcl / peer", "each round",
              "every peer traversal (ms)", "hits rtcl / peer", "rays agreeing")
    where = ("the peer's CPU traversals on every hardware thread of this machine (median of "
             f"{args.repeat} passes)" if args.cpu else
             f"the peer's GPU kernels ({args.variants}), median of {args.repeat} launches")
    report = (f"# rtcl against the peer on primary, diffuse bounce and shadow rays\n\n"
              f"rtcl-rays on {device} (median of {args.repeat} launches, OpenCL profiling "
              f"events) against {where}; {args.rounds} round{'s' if args.rounds > 1 else ''}, "
              "the two sides in turn, each side's time the median of its rounds; "
              f"rays from a {width}x{height} image: the same rays on "
              f"both sides, read from the files peer_rays.cpp made (docs/bvh.md, \"Incoherent "
              f"rays against TinyBVH\"); rtcl {git_commit() or 'commit unknown'}, {utc_now()}. "
              f"Peer: {args.peer}. rtcl / peer above 1: rtcl is faster. Agreeing: the same hit "
              "or miss and, for closest hits, the same triangle or the same distance within "
              "1e-4 of it.\n\n"
              + markdown_table(header, table) + "\n")
    files.write_text(out / "rays.md", report)
    files.write_text(out / "rays.csv", to_csv(RAYS_CSV, csv_rows))
    print(report)


@interruptible
def main(argv=None):
    args = parse_arguments(argv)
    program = program_name()
    try:
        with files.committed_files_allowed(args.update_committed):
            out = args.out or locations.new_results_folder("peer")
            if args.rays and args.counts:
                raise UsageError("--rays and --counts do not go together: --rays times")
            outputs = ([out / "rays.md", out / "rays.csv"] if args.rays
                       else [out / "counts.md"] if args.counts else [out / "cpu.md"] if args.cpu
                       else [out / "compare.md", out / "compare.csv"])
            files.reading(args.ply)
            files.check_output_folder(out, [path.name for path in outputs])
            rtcl = locations.find_rtcl(args.rtcl)
            (out / "raw").mkdir(parents=True, exist_ok=True)
            (rays if args.rays else counts if args.counts else cpu if args.cpu
             else compare)(args, rtcl, out)
    except (Failure, locations.NotFound, UsageError, OSError) as error:
        return report_error(program, one_line(error))
    print(f"{program}: results in {out}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
