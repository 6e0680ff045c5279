"""Mitsuba 3 timings for issue 41's study on paths: each scene given as
NAME=PATH through tools/build/mitsuba_ref.py's own mapping (docs/oracle.md),
rendered as a megakernel and as a wavefront at the same size and samples as
rtcl's; the median of 3 timed renders after one that compiles. One JSON object
a line is appended to OUT (rtcl-path-study's mitsuba.jsonl). A scene the
oracle's exact mapping refuses is mapped again with its approximations
(mitsuba_ref.Scene(approximate=True): studio_path's plane as a 1000-unit
square, its glTF trellis's texture as a mean colour and a mask), and its
records say so ("approximate", "approximate_label"); one that still fails is
reported and skipped. Should a form fail with the mapping's Python BSDF
"gltf" (the principled materials' plastic lobe, untried on a GPU), it is
tried again with Mitsuba's own `principled` of metallic 0 in its place, a
BSDF of like cost but not the same (its record says "approximate").

    python3 pt_mitsuba.py OUT.jsonl WxH SPP NAME=SCENE[:SPP] ...
"""
import json
import os
import pathlib
import statistics
import sys
import time
import traceback

sys.path.insert(0, "tools/build")
import drjit as dr  # noqa: E402
import mitsuba as mi  # noqa: E402

mi.set_variant(os.environ.get("MI_VARIANT", "cuda_ad_rgb"))  # scalar_rgb: a check on a CPU
import mitsuba_ref as mr  # noqa: E402

out = pathlib.Path(sys.argv[1])
W, H = (int(v) for v in sys.argv[2].split("x"))
SPP = int(sys.argv[3])


def without_gltf(d):
    """d with every "gltf" BSDF replaced by Mitsuba's principled of metallic 0
    (specular: F0 = 0.08 specular), and whether there was one."""
    found = False

    def walk(value):
        nonlocal found
        if isinstance(value, dict):
            if value.get("type") == "gltf":
                found = True
                f0 = ((value["ior"] - 1) / (value["ior"] + 1)) ** 2
                return {"type": "principled", "base_color": {"type": "rgb", "value": value["base_color"]},
                        "metallic": 0.0, "roughness": value["alpha"] ** 0.5, "specular": f0 / 0.08}
            return {k: walk(v) for k, v in value.items()}
        return value
    return walk(d), found


def mapping_approximations(scene):
    """What mitsuba_ref.py's approximate mapping changes in the scene (docs/oracle.md)."""
    found = []
    if scene.doc.get("planes"):
        found.append(f"plane as a {mr.PLANE_SIZE:g}-unit square")
    for _, _, (_, material), _ in scene.shapes():
        gltf = material.get("gltf_material", {})
        if gltf.get("pbrMetallicRoughness", {}).get("baseColorTexture") \
                or gltf.get("alphaMode") == "MASK":
            found.append("glTF base colour texture as its mean colour, cut-out as a mask")
            break
    return found


def time_it(name, d, spp, approximations=None):
    for wavefront in (False, True):
        form = "wavefront" if wavefront else "megakernel"
        record = render(name, form, wavefront, d, spp)
        if record is None:
            approximate, found = without_gltf(d)
            if found:
                print(f"mitsuba {name} {form}: again with Mitsuba's principled for the plastic lobe",
                      flush=True)
                record = render(name, form, wavefront, approximate, spp)
                if record:
                    record["approximate"] = "Mitsuba's principled (metallic 0) for the gltf plastic lobe"
        if record and approximations:
            record["approximate"] = "; ".join(
                ["the mapping's approximations: " + "; ".join(approximations)]
                + ([record["approximate"]] if "approximate" in record else []))
            record["approximate_label"] = "approximate: " + approximations[0]
        if record:
            with out.open("a") as f:
                f.write(json.dumps(record) + "\n")


def render(name, form, wavefront, d, spp):
    """Times the scene in one form: its record, or None when it failed."""
    try:
        dr.set_flag(dr.JitFlag.SymbolicLoops, not wavefront)
        s = mi.load_dict(d)
        t0 = time.perf_counter()
        img = mi.render(s, spp=spp)
        dr.eval(img)
        dr.sync_thread()
        first = time.perf_counter() - t0
        times = []
        for r in range(3):
            t0 = time.perf_counter()
            img = mi.render(s, spp=spp, seed=r + 1)
            dr.eval(img)
            dr.sync_thread()
            times.append(time.perf_counter() - t0)
    except Exception as error:  # report, go on with the next
        print(f"mitsuba {name} {form}: FAILED: {error}", flush=True)
        traceback.print_exc(limit=3)
        return None
    ms = statistics.median(times) * 1e3
    print(f"mitsuba {name} {form}: {ms:.1f} ms (all {', '.join('%.1f' % (t * 1e3) for t in times)}; "
          f"first with its compilation {first:.1f} s), {W * H * spp / ms / 1e3:.1f} M paths/s",
          flush=True)
    return {"scene": name, "form": form, "ms": ms, "all_ms": [t * 1e3 for t in times],
            "first_s": first, "width": W, "height": H, "spp": spp, "mitsuba": mi.__version__}


for item in sys.argv[4:]:
    name, path = item.split("=", 1)
    spp = SPP
    if ":" in path:
        path, spp = path.rsplit(":", 1)
        spp = int(spp)
    try:
        t0 = time.perf_counter()
        approximations = None
        try:
            d = mr.mitsuba_scene(mr.Scene(pathlib.Path(path)), spp, W, H)
        except mr.SceneError as error:   # the oracle's exact mapping refuses it
            scene = mr.Scene(pathlib.Path(path), approximate=True)
            d = mr.mitsuba_scene(scene, spp, W, H)
            approximations = mapping_approximations(scene)
            print(f"mitsuba {name}: not exact ({error}): mapped with "
                  f"{'; '.join(approximations)}", flush=True)
        print(f"mitsuba {name}: mapped in {time.perf_counter() - t0:.1f} s", flush=True)
    except mr.SceneError as error:
        print(f"mitsuba {name}: skipped, the mapping refuses it: {error}", flush=True)
        continue
    time_it(name, d, spp, approximations)
