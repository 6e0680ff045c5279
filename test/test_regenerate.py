"""Path regeneration and the fetch schemes of the persistent kernel (issue 41,
item 1; docs/wavefront.md, "-k persistent"): `--regenerate` and every
`--fetch` give the image, flop count, rays and work map of the other kernels
byte for byte, with several samples per pixel and with the samples split into
passes; the options are refused where they do not apply; `--stats` says which
scheme ran."""
import json
import os
import subprocess
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parent.parent
RTCL = os.environ.get("RTCL", str(ROOT / "rtcl"))
BOX = ROOT / "test" / "scenes" / "path_box.json"  # diffuse walls, glass, a conductor
CORNELL = ROOT / "scenes" / "cornell.json"
STUDIO = ROOT / "scenes" / "studio_path.json"  # smooth and rough glass


def rtcl(*args, env=None):
    return subprocess.run([RTCL, *map(str, args)], capture_output=True, text=True, cwd=ROOT,
                          timeout=300, env={**os.environ, **(env or {})})


def render(tmp_path, name, scene, *args, env=None, size="16x16", spp=3):
    out = tmp_path / f"{name}.pfm"
    result = rtcl(scene, "--size", size, "--spp", spp, "-q", "-o", out, *args, env=env)
    assert result.returncode == 0, result.stderr
    return out.read_bytes()


def test_regenerated_image_is_the_dynamic_kernels(tmp_path):
    """Regenerated paths fetched by work-group blocks, the samples in passes
    of one: the dynamic kernel's image, byte for byte (the other schemes and
    batches: test_every_scheme_gives_the_same_image, slow)."""
    want = render(tmp_path, "dynamic", BOX, "-k", "dynamic")
    assert len(set(want)) > 10  # an image, not a blank
    got = render(tmp_path, "regenerated", BOX, "-k", "persistent", "--regenerate", "--fetch",
                 "group", env={"RTCL_TEST_PASS_SAMPLES": "1"})
    assert got == want, "regenerated differs from -k dynamic"


def counts(tmp_path, name, scene, *args):
    stats, work = tmp_path / f"{name}.json", tmp_path / f"{name}.npy"
    result = rtcl(scene, "--size", "12x12", "--spp", "3", "-q", "-o", tmp_path / f"{name}.pfm",
                  "--stats", stats, "--work-map", work, *args)
    assert result.returncode == 0, result.stderr
    doc = json.loads(stats.read_text())
    return doc, np.load(work), (tmp_path / f"{name}.pfm").read_bytes()


@pytest.mark.slow
def test_regenerated_counts_are_the_dynamic_kernels(tmp_path):
    """--flops' total, the rays and the work map (the flops per pixel) of a
    regenerated render are the dynamic kernel's: a work-item's flops between
    a pixel's start and its end are the pixel's."""
    want, want_map, want_image = counts(tmp_path, "dynamic", BOX, "-k", "dynamic")
    got, got_map, got_image = counts(tmp_path, "regenerate", BOX, "-k", "persistent",
                                     "--regenerate")
    assert want["total_flops"] > 0
    assert got["total_flops"] == want["total_flops"]
    assert got["rays"] == want["rays"]
    assert (got_map == want_map).all()
    assert got_image == want_image


def test_stats_say_which_scheme_ran(tmp_path):
    out = tmp_path / "s.json"
    result = rtcl(BOX, "--size", "8x8", "--spp", "2", "-q", "-o", tmp_path / "x.pfm", "-k",
                  "persistent", "-w", "4x2", "--regenerate", "--fetch", "group", "--stats", out)
    assert result.returncode == 0, result.stderr
    doc = json.loads(out.read_text())
    assert (doc["regenerate"], doc["fetch"], doc["fetch_lanes"]) == (True, "group", 8)
    assert "-DRTCL_REGENERATE" in doc["build_options"]
    result = rtcl(BOX, "--size", "8x8", "--spp", "2", "-q", "-o", tmp_path / "y.pfm", "-k",
                  "persistent", "--stats", out)
    assert result.returncode == 0, result.stderr
    doc = json.loads(out.read_text())
    assert (doc["regenerate"], doc["fetch"], doc["fetch_lanes"]) == (False, "item", 1)
    result = rtcl(BOX, "--size", "8x8", "--spp", "2", "-q", "-o", tmp_path / "z.pfm", "-k",
                  "dynamic", "--stats", out)
    assert result.returncode == 0, result.stderr
    assert "fetch" not in json.loads(out.read_text())


@pytest.mark.slow
@pytest.mark.parametrize("scene", [CORNELL, STUDIO, BOX], ids=["cornell", "studio", "box"])
def test_every_scheme_gives_the_same_image(tmp_path, scene):
    """Cornell, the path-traced studio with its glass and the test box, at
    --spp 5, in one pass and in passes of 2: every fetch scheme and batch,
    regenerated or not, gives -k dynamic's and -k naive's image."""
    want = render(tmp_path, "dynamic", scene, "-k", "dynamic", spp=5)
    assert render(tmp_path, "naive", scene, "-k", "naive", spp=5) == want
    for fetch in ["item", "group", "subgroup"]:
        for batch in ["1", "4"]:
            for regenerate in [[], ["--regenerate"]]:
                for env in [None, {"RTCL_TEST_PASS_SAMPLES": "2"}]:
                    name = f"{fetch}-{batch}-{len(regenerate)}-{env is None}"
                    got = render(tmp_path, name, scene, "-k", "persistent", "--fetch", fetch,
                                 "--batch", batch, *regenerate, env=env, spp=5)
                    assert got == want, f"{name} differs from -k dynamic"


@pytest.mark.slow
@pytest.mark.parametrize("fetch", ["item", "group", "subgroup"])
def test_every_scheme_counts_what_dynamic_counts(tmp_path, fetch):
    """The flops, rays, work map and schedule map (a permutation of the
    pixels: each started once) of every scheme, regenerated, at a work-group
    shape whose chunks overhang the image's edges."""
    want, want_map, want_image = counts(tmp_path, "dynamic", STUDIO, "-k", "dynamic",
                                        "-w", "8x4")
    got, got_map, got_image = counts(tmp_path, fetch, STUDIO, "-k", "persistent", "-w", "8x4",
                                     "--regenerate", "--fetch", fetch, "--batch", "2",
                                     "--schedule-map", tmp_path / "s.npy")
    assert (got["total_flops"], got["rays"]) == (want["total_flops"], want["rays"])
    assert (got_map == want_map).all()
    assert got_image == want_image
    tickets = np.load(tmp_path / "s.npy")[..., 2]
    assert sorted(tickets.ravel()) == list(range(144))


def failure(result, message):
    assert result.returncode == 2, result.stderr
    assert result.stderr.strip() == message
    assert result.stdout == ""


def test_regenerate_needs_the_persistent_kernel(tmp_path):
    failure(rtcl(BOX, "-k", "dynamic", "--regenerate", "-o", tmp_path / "x.pfm"),
            "rtcl: --regenerate sets how the work-items of -k persistent take their work; "
            "it does not apply to -k dynamic")
    assert not (tmp_path / "x.pfm").exists()


def test_fetch_needs_the_persistent_kernel(tmp_path):
    failure(rtcl(BOX, "-k", "naive", "--fetch", "group", "-o", tmp_path / "x.pfm"),
            "rtcl: --fetch sets how the work-items of -k persistent take their work; "
            "it does not apply to -k naive")
    failure(rtcl(BOX, "-k", "reference", "--fetch", "item", "-o", tmp_path / "x.pfm"),
            "rtcl: --fetch sets how the work-items of -k persistent take their work; "
            "it does not apply to -k reference")


def test_fetch_names_its_choices(tmp_path):
    failure(rtcl(BOX, "-k", "persistent", "--fetch", "warp", "-o", tmp_path / "x.pfm"),
            'rtcl: --fetch: expected item, group or subgroup, got "warp"')


def test_regenerate_needs_the_path_integrator(tmp_path):
    message = ("rtcl: --regenerate restarts paths of the path integrator; this render is "
               "Whitted's (give --integrator path or a scene with \"integrator\": \"path\")")
    failure(rtcl(ROOT / "scenes" / "two_balls.json", "-k", "persistent", "--regenerate", "-o",
                 tmp_path / "x.pfm"), message)
    failure(rtcl(BOX, "--integrator", "whitted", "-k", "persistent", "--regenerate", "-o",
                 tmp_path / "x.pfm"), message)
    assert not (tmp_path / "x.pfm").exists()


@pytest.mark.slow
def test_group_blocks_are_the_groups_own(tmp_path):
    """--fetch group with work-groups running at once (PoCL's optimised
    build, make test-long's): each group draws from its own block. With the
    block a kernel-scope __local variable, PoCL 3.1 shared it between the
    groups it ran at once, and a block's chunk went untraced in 5 renders of
    8 of this one."""
    want = render(tmp_path, "dynamic", CORNELL, "-k", "dynamic", size="24x24", spp=4)
    for i in range(6):
        got = render(tmp_path, f"group{i}", CORNELL, "-k", "persistent", "--regenerate",
                     "--fetch", "group", size="24x24", spp=4)
        assert got == want, f"render {i} differs from -k dynamic"
