"""End-to-end tests of the command line's stricter checks (issue 14): launch
geometries the kernels cannot index, options given values they do not take,
empty file names, integers with signs or spaces, --flops without .npy, and
PoCL without a writable cache directory.

Like test_cli.py: a failing run prints exactly one line on stderr, exits with
the documented status and leaves no file behind.
"""
import os
import pathlib
import shutil
import subprocess
import tempfile

import pytest

ROOT = pathlib.Path(__file__).resolve().parent.parent
RTCL = os.environ.get("RTCL", str(ROOT / "rtcl"))
TINY = ["--size", "8x8"]


def rtcl(*args, env=None):
    return subprocess.run([RTCL, *args], capture_output=True, text=True, cwd=ROOT, env=env,
                          timeout=300)


def expect_failure(result, status, message, directory):
    assert result.returncode == status, (result.returncode, result.stderr)
    lines = result.stderr.splitlines()
    assert len(lines) == 1, result.stderr
    assert lines[0].startswith("rtcl: "), lines[0]
    assert message in lines[0], lines[0]
    assert result.stdout == ""
    assert sorted(os.listdir(directory)) == [], "a failed run left files behind"


# ---- launch geometry the kernels cannot index ---------------------------------

@pytest.mark.parametrize("kernel", ["cyclic", "dynamic", "persistent"])
def test_too_many_groups_is_refused_before_any_launch(kernel, tmp_path):
    # 2^32 work-groups used to crash PoCL (SIGILL or SIGFPE) inside the launch.
    result = rtcl("-k", kernel, "--groups", "65536x65536", *TINY,
                  "-o", str(tmp_path / "out.png"))
    expect_failure(result, 1,
                   "--groups 65536x65536: 4294967296 work-groups of 64 work-items is more than "
                   "the kernels can index (at most 2147483648 work-items in all); "
                   "choose fewer groups", tmp_path)


def test_work_item_limit_counts_work_items_not_groups(tmp_path):
    # 46341 x 46341 = 2147488281 one-item groups: just over 2^31 work-items.
    result = rtcl("-k", "dynamic", "-w", "1x1", "--groups", "46341x46341", *TINY,
                  "-o", str(tmp_path / "out.png"))
    expect_failure(result, 1, "2147488281 work-groups of 1 work-item is more than", tmp_path)


def test_persistent_pixel_counter_must_not_wrap(tmp_path):
    # 5,760,000 work-items each overshooting by a batch of 4096 pass 2^32 - 1.
    result = rtcl("-k", "persistent", "--groups", "300x300", "--batch", "4096", *TINY,
                  "-o", str(tmp_path / "out.png"))
    expect_failure(result, 1,
                   "--groups 300x300 with --batch 4096: the persistent kernel's 32-bit pixel "
                   "counter would count to", tmp_path)
    assert "choose fewer groups or a smaller --batch" in result.stderr


@pytest.mark.parametrize("kernel", ["cyclic", "dynamic", "persistent"])
def test_many_groups_within_the_limits_still_render(kernel, tmp_path):
    out = tmp_path / "out.ppm"
    result = rtcl("-q", "-k", kernel, "--groups", "300x300", "--batch", "100", *TINY,
                  "-o", str(out))
    assert result.returncode == 0, result.stderr
    assert out.stat().st_size > 0


def test_help_states_the_work_item_limit():
    assert "2^31 work-items in all" in rtcl("--help").stdout
