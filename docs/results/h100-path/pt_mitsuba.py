"""Mitsuba 3 (cuda_ad_rgb) timings for issue 40's speed table: the same
scenes as rtcl's (scenes/cornell.json; cornell_blob.json: the room and a
1.3 M-triangle rough gold blob) through tools/build/mitsuba_ref.py's own
mapping, and mi.cornell_box() as the shared README's reference, each as a
megakernel and as a wavefront; 1024x1024, 64 spp; the median of 3 timed
renders after one that compiles."""
import json, pathlib, statistics, sys, time
sys.path.insert(0, "tools/build")
import drjit as dr, mitsuba as mi
variant = sys.argv[1] if len(sys.argv) > 1 else "cuda_ad_rgb"
mi.set_variant(variant)
import mitsuba_ref as mr

W = H = int(sys.argv[2]) if len(sys.argv) > 2 else 1024
SPP = int(sys.argv[3]) if len(sys.argv) > 3 else 64

def rtcl_scene(path, extra=None):
    scene = mr.Scene(pathlib.Path(path))
    d = mr.mitsuba_scene(scene, SPP, W, H)
    if extra:
        d.update(extra)
    return d

def time_it(name, d, max_depth=None):
    for wavefront in (False, True):
        dr.set_flag(dr.JitFlag.SymbolicLoops, not wavefront)
        dr.set_flag(dr.JitFlag.LoopRecord, not wavefront) if hasattr(dr.JitFlag, "LoopRecord") else None
        s = mi.load_dict(d)
        img = mi.render(s, spp=SPP); dr.eval(img); dr.sync_thread()
        times = []
        for r in range(3):
            t0 = time.perf_counter(); img = mi.render(s, spp=SPP, seed=r + 1); dr.eval(img); dr.sync_thread()
            times.append(time.perf_counter() - t0)
        ms = statistics.median(times) * 1e3
        print(f"mitsuba {name} {'wavefront' if wavefront else 'megakernel'}: {ms:.1f} ms "
              f"(all {', '.join('%.1f' % (t * 1e3) for t in times)}), {W * H * SPP / ms / 1e3:.1f} M paths/s", flush=True)

time_it("cornell.json", rtcl_scene("scenes/cornell.json"))
blob_scene = json.load(open("scenes/cornell_blob.json"))
gold = blob_scene["materials"]["gold"]
no_blob = dict(blob_scene, meshes=blob_scene["meshes"][:1])
pathlib.Path("scenes/cornell_room_only.json").write_text(json.dumps(no_blob))
time_it("cornell_blob.json", rtcl_scene("scenes/cornell_room_only.json", {
    "blob": {"type": "ply", "filename": "scenes/models/blob.ply", "face_normals": True,
             "bsdf": mr.mitsuba_bsdf(gold, "materials.gold")}}))
cb = mi.cornell_box(); cb["sensor"]["film"]["width"] = W; cb["sensor"]["film"]["height"] = H
cb["sensor"]["film"]["rfilter"] = {"type": "box"}; cb["integrator"]["max_depth"] = 8
time_it("mi.cornell_box() depth 8", cb)
