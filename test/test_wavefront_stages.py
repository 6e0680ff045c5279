"""The wavefront's stages form under the path integrator (issue 41;
docs/wavefront.md, "The stages form"): -k wavefront --wavefront-form stages
renders the single-pass kernels' image byte for byte, with their flops, rays
and work map, whatever the pool of paths in flight (a small pool makes slots
take new paths while other samples of their pixels are in flight); --stats
reports its kernels and queues; the options are refused where they do not
apply."""
import json
import os
import subprocess
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parent.parent
RTCL = os.environ.get("RTCL", str(ROOT / "rtcl"))
BOX = ROOT / "test" / "scenes" / "path_box.json"
CORNELL = ROOT / "scenes" / "cornell.json"
STUDIO = ROOT / "scenes" / "studio_path.json"  # glass, rough glass, textured models, a sky
STAGES = ["-k", "wavefront", "--wavefront-form", "stages"]


def rtcl(*args, env=None):
    return subprocess.run([RTCL, *map(str, args)], capture_output=True, text=True, cwd=ROOT,
                          timeout=300, env={**os.environ, **(env or {})})


def render(tmp_path, name, scene, *args, env=None):
    out = tmp_path / f"{name}.pfm"
    result = rtcl(scene, "-o", out, "-q", *args, env=env)
    assert result.returncode == 0, result.stderr
    return out.read_bytes()


def same_as_dynamic(tmp_path, scene, size, spp, pools, env=None, kernel=("-k", "dynamic")):
    dynamic = render(tmp_path, "dynamic", scene, *kernel, "--size", size, "--spp", spp)
    for pool in pools:
        pool_args = ["--paths-in-flight", pool] if pool else []
        stages = render(tmp_path, f"stages{pool}", scene, *STAGES, *pool_args, "--size", size,
                        "--spp", spp, env=env)
        assert stages == dynamic, f"{scene.name} {size} {spp} spp, {pool} paths in flight"


@pytest.mark.parametrize("spp", [pytest.param(1, marks=pytest.mark.slow), 4])
def test_the_box_is_the_dynamic_kernels_image(tmp_path, spp):
    # 17 slots for 400 pixels: each slot takes many paths, and with 4 spp
    # the samples of a pixel overlap in flight; the default pool holds all.
    same_as_dynamic(tmp_path, BOX, "20x20", spp, [17, None])


@pytest.mark.parametrize("launch", ["sync", pytest.param("device", marks=pytest.mark.slow)])
def test_the_studio_is_the_bounce_forms_image(tmp_path, launch):
    # Every BSDF kind's shade kernel, textures, a sky. Against the bounce
    # form, whose image is the dynamic kernel's (test_path.py), from the same
    # program: one build for make test; the slow test below compares with
    # -k dynamic itself.
    same_as_dynamic(tmp_path, STUDIO, "24x16", 3, [61], env={"RTCL_STAGES_LAUNCH": launch},
                    kernel=("-k", "wavefront"))


@pytest.mark.slow
@pytest.mark.parametrize("scene", [CORNELL, STUDIO])
@pytest.mark.parametrize("spp", [1, 2, 7])
def test_shipped_path_scenes_are_the_dynamic_kernels_image(tmp_path, scene, spp):
    same_as_dynamic(tmp_path, scene, "32x24", spp, [1, 100, None])


def test_shares_of_the_samples_over_two_devices_give_the_same_image(tmp_path):
    # --split samples: each device sums a share of every pixel's samples
    # (rt_piece.sum_begin), and the sums are joined on the host.
    dynamic = render(tmp_path, "dynamic", BOX, "-k", "dynamic", "--size", "16x12", "--spp", 6)
    two = {"POCL_DEVICES": "pthread pthread"}
    for split in ["samples", "dynamic"]:
        stages = render(tmp_path, f"stages_{split}", BOX, *STAGES, "--paths-in-flight", 40,
                        "--size", "16x12", "--spp", 6, "--devices", "0:0,0:1", "--split",
                        split, env=two)
        assert stages == dynamic, split


def counted(tmp_path, name, scene, *args, env=None):
    stats = tmp_path / f"{name}.json"
    render(tmp_path, name, scene, *args, "--stats", stats, "--work-map",
           tmp_path / f"{name}.npy", "--flops", tmp_path / f"{name}_items.npy", env=env)
    return (json.loads(stats.read_text()), np.load(tmp_path / f"{name}.npy"),
            np.load(tmp_path / f"{name}_items.npy"))


@pytest.mark.slow
@pytest.mark.parametrize("launch", ["sync", "device"])
def test_flops_rays_and_work_map_are_the_dynamic_kernels(tmp_path, launch):
    # RTCL_STAGES_LAUNCH=device: every queue launch fills the device and its
    # work-items read their queue's length there (docs/wavefront.md).
    size = ["--size", "12x10", "--spp", 3]
    d_stats, d_map, d_items = counted(tmp_path, "dynamic", STUDIO, "-k", "dynamic", *size)
    s_stats, s_map, s_items = counted(tmp_path, "stages", STUDIO, *STAGES,
                                      "--paths-in-flight", 29, *size,
                                      env={"RTCL_STAGES_LAUNCH": launch})
    assert d_stats["total_flops"] > 0
    assert s_stats["total_flops"] == d_stats["total_flops"]
    assert s_stats["rays"] == d_stats["rays"]
    assert (s_map == d_map).all()
    # Every launch's work-items, one after another: they add up to the same.
    assert s_items.sum() == d_items.sum() == d_stats["total_flops"]
    assert s_items.shape[1] > d_items.shape[1]


@pytest.mark.parametrize("launch", ["sync", pytest.param("device", marks=pytest.mark.slow)])
def test_stats_report_the_kernels_and_the_live_paths(tmp_path, launch):
    stats_file = tmp_path / "s.json"
    render(tmp_path, "s", BOX, *STAGES, "--paths-in-flight", 50, "--size", "10x8", "--spp", 2,
           "--stats", stats_file, env={"RTCL_STAGES_LAUNCH": launch})
    doc = json.loads(stats_file.read_text())
    st = doc["wavefront_stages"]
    k = st["kernels"]
    paths = 10 * 8 * 2
    assert st["paths_in_flight"] == 50
    assert sum(st["new_paths"]) == paths == k["new_path"]["items"]
    assert st["iterations"] == len(st["live_paths"]) == len(st["extension_rays"])
    assert max(st["live_paths"]) <= 50
    # Each iteration's segments: the paths started and those shaded that go on.
    for started, live, extended, shadow in zip(st["new_paths"], st["live_paths"],
                                               st["extension_rays"], st["shadow_rays"]):
        assert started <= extended <= started + live and shadow <= live
    shaded = sum(k[f"shade_{kind}"]["items"] for kind in
                 ["mapped", "diffuse", "conductor", "dielectric", "principled"])
    assert shaded == sum(st["live_paths"]) > 0
    assert k["extend"]["items"] == sum(st["extension_rays"])
    # The logic kernel looks at every slot once (the piece's first
    # iteration), then at each path once, when it ends.
    assert k["logic"]["items"] == 50 + paths
    assert k["begin"]["launches"] == k["finish"]["launches"] == 1
    assert k["advance"]["launches"] == k["new_path"]["launches"]
    assert st["state_bytes"] == sum(v["state_bytes"] for v in k.values())
    for name, kernel in k.items():
        assert kernel["kernel_ms"] >= 0, name
        assert kernel["state_bytes"] == kernel["items"] * kernel["bytes_per_item"], name
    assert doc["kernel_ms"] > 0


@pytest.mark.parametrize("args, message", [
    (["-k", "dynamic", "--wavefront-form", "stages"],
     "rtcl: --wavefront-form chooses how -k wavefront splits paths; it does not apply to "
     "-k dynamic"),
    (["-k", "wavefront", "--wavefront-form", "stage"],
     'rtcl: --wavefront-form: expected bounce or stages, got "stage"'),
    (["-k", "wavefront", "--paths-in-flight", 5],
     "rtcl: --paths-in-flight sets the pool of paths of -k wavefront --wavefront-form stages; "
     "it does not apply to the bounce form (give --wavefront-form stages)"),
    (["-k", "naive", "--paths-in-flight", 5],
     "rtcl: --paths-in-flight sets the pool of paths of -k wavefront --wavefront-form stages; "
     "it does not apply to -k naive"),
    ([*STAGES, "--paths-in-flight", 0],
     'rtcl: --paths-in-flight: expected an integer between 1 and 67108864, got "0"'),
    ([*STAGES, "--integrator", "whitted"],
     "rtcl: --wavefront-form chooses how -k wavefront splits the paths of the path "
     "integrator; this render uses the Whitted integrator (give --integrator path, or leave "
     "--wavefront-form out)"),
    (["-k", "wavefront", "--wavefront-form", "bounce", "--integrator", "whitted"],
     "rtcl: --wavefront-form chooses how -k wavefront splits the paths of the path "
     "integrator; this render uses the Whitted integrator (give --integrator path, or leave "
     "--wavefront-form out)"),
])
def test_misuse_is_refused(tmp_path, args, message):
    out = tmp_path / "x.pfm"
    result = rtcl(BOX, "--size", "8x8", "-o", out, *args)
    assert result.returncode == 2
    assert result.stderr.splitlines() == [message]
    assert not out.exists()
