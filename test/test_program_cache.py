"""rtcl's program binary cache (host/device/progcache.h): a second render loads the
built program, says so in -v and --stats, and any trouble with the cache means
a build from source, never a failure (issue 12 item 3)."""
import json
import os
import pathlib
import shutil
import signal
import subprocess
import time

import pytest

ROOT = pathlib.Path(__file__).resolve().parent.parent
RTCL = os.environ.get("RTCL", str(ROOT / "rtcl"))
SMALL = ["--size", "24x16", "-k", "naive"]
HEADER = 32  # magic, key, binary hash, binary size


def environment(cache_home, **extra):
    env = dict(os.environ, XDG_CACHE_HOME=str(cache_home), **extra)
    # PoCL keeps its own cache under XDG_CACHE_HOME too: leave it where it
    # was, so that these tests measure rtcl's cache, not PoCL's cold build.
    env.setdefault("POCL_CACHE_DIR", str(pathlib.Path.home() / ".cache" / "pocl"))
    env.pop("RTCL_CACHE", None)
    env.update(extra)
    return env


def render(tmp_path, cache_home, *args, **env):
    result = subprocess.run([RTCL, *SMALL, "-o", "x.ppm", "--stats", "s.json", *args],
                            capture_output=True, text=True, cwd=tmp_path, timeout=300,
                            env=environment(cache_home, **env))
    assert result.returncode == 0, result.stderr
    stats = json.loads((tmp_path / "s.json").read_text())
    return stats["build_cached"], (tmp_path / "x.ppm").read_bytes(), result.stderr


def cache_files(cache_home):
    folder = cache_home / "rtcl"
    return sorted(folder.iterdir()) if folder.exists() else []


@pytest.fixture(scope="module")
def primed_template(tmp_path_factory):
    """One cold render's cache folder and image, built once for the tests
    that only need a cache holding the program (a build costs about a
    second here; the tests that watch the first build make their own)."""
    where = tmp_path_factory.mktemp("primed")
    cached, image, _ = render(where, where / "cache")
    assert cached is False and len(cache_files(where / "cache")) == 1
    return where / "cache", image


@pytest.fixture
def primed(tmp_path, primed_template):
    """A copy of primed_template's cache under tmp_path / "cache", and the
    image it rendered."""
    folder, image = primed_template
    shutil.copytree(folder, tmp_path / "cache")
    return tmp_path / "cache", image


def test_the_second_render_loads_the_cached_program(tmp_path):
    cached, image, _ = render(tmp_path, tmp_path / "cache")
    assert cached is False
    files = cache_files(tmp_path / "cache")
    assert len(files) == 1 and files[0].suffix == ".bin"
    assert files[0].read_bytes()[:8] == b"rtclbin1"
    cached, again, stderr = render(tmp_path, tmp_path / "cache", "-v")
    assert cached is True and again == image
    line = [l for l in stderr.splitlines() if l.startswith("rtcl: time: ")][0]
    assert " ms (cached), kernels " in line, line


def test_other_build_options_are_another_program(tmp_path):
    render(tmp_path, tmp_path / "cache")
    cached, _, _ = render(tmp_path, tmp_path / "cache", "--depth", "2")
    assert cached is False and len(cache_files(tmp_path / "cache")) == 2
    assert render(tmp_path, tmp_path / "cache", "--depth", "2")[0] is True


def test_other_pocl_build_flags_are_another_program(tmp_path):
    """PoCL's build settings from the environment change the binary: make test
    builds without LLVM's optimiser, make test-long with it, in one cache."""
    flags = {"POCL_EXTRA_BUILD_FLAGS": "-cl-opt-disable"}
    assert render(tmp_path, tmp_path / "cache", **flags)[0] is False
    cached, _, _ = render(tmp_path, tmp_path / "cache", POCL_EXTRA_BUILD_FLAGS="")
    assert cached is False and len(cache_files(tmp_path / "cache")) == 2
    assert render(tmp_path, tmp_path / "cache", **flags)[0] is True


def damage_truncate(data):
    return data[:len(data) // 2]


def damage_flip(data):
    middle = HEADER + (len(data) - HEADER) // 2
    return data[:middle] + bytes([data[middle] ^ 0x55]) + data[middle + 1:]


def damage_garbage_with_a_good_hash(data):
    """A whole, well-hashed file whose binary the device cannot load."""
    garbage = b"not a program binary" * 50
    digest = 0xcbf29ce484222325
    for byte in garbage:
        digest = ((digest ^ byte) * 0x100000001b3) & 0xffffffffffffffff
    return (data[:16] + digest.to_bytes(8, "little") + len(garbage).to_bytes(8, "little")
            + garbage)


@pytest.mark.parametrize("damage", [damage_truncate, damage_flip,
                                    damage_garbage_with_a_good_hash, lambda data: b""])
def test_a_damaged_cache_file_means_a_build_from_source(tmp_path, primed, damage):
    _, image = primed
    path = cache_files(tmp_path / "cache")[0]
    path.write_bytes(damage(path.read_bytes()))
    cached, again, stderr = render(tmp_path, tmp_path / "cache")
    assert cached is False and again == image and stderr == ""
    # Rebuilt and saved whole again.
    assert render(tmp_path, tmp_path / "cache")[0] is True


def test_an_unwritable_cache_folder_still_renders(tmp_path):
    (tmp_path / "file").write_text("a file where the cache folder would go")
    cache_home = tmp_path / "file" / "sub"
    cached, image, stderr = render(tmp_path, cache_home)
    assert cached is False and stderr == ""  # silent without -v
    cached, again, stderr = render(tmp_path, cache_home, "-v")
    assert cached is False and again == image
    warnings = [l for l in stderr.splitlines() if "program cache" in l]
    assert len(warnings) == 1 and "cannot write" in warnings[0], stderr


def test_rtcl_cache_0_turns_it_off(tmp_path, primed_template):
    for _ in range(2):
        cached, _, _ = render(tmp_path, tmp_path / "cache", RTCL_CACHE="0")
        assert cached is False
    assert cache_files(tmp_path / "cache") == []
    shutil.rmtree(tmp_path / "cache", ignore_errors=True)
    shutil.copytree(primed_template[0], tmp_path / "cache")
    assert render(tmp_path, tmp_path / "cache")[0] is True
    assert render(tmp_path, tmp_path / "cache", RTCL_CACHE="0")[0] is False


def test_a_cache_entry_that_is_a_fifo_is_a_miss_not_a_hang(tmp_path, primed):
    """Issue 24 finding 7: a FIFO in place of the cache file hung every render
    (fopen waited for a writer). Now it is opened without blocking, refused as
    not a regular file (said with -v), and the build's binary replaces it."""
    _, image = primed
    path = cache_files(tmp_path / "cache")[0]
    path.unlink()
    os.mkfifo(path)
    result = subprocess.run([RTCL, *SMALL, "-o", "x.ppm", "--stats", "s.json", "-v"],
                            capture_output=True, text=True, cwd=tmp_path, timeout=60,
                            env=environment(tmp_path / "cache"))
    assert result.returncode == 0, result.stderr
    assert f"rtcl: program cache: {path} is not a regular file; building from source" \
        in result.stderr.splitlines()
    assert (tmp_path / "x.ppm").read_bytes() == image
    assert path.is_file() and render(tmp_path, tmp_path / "cache")[0] is True


def test_temporary_files_of_writers_that_are_gone_are_removed(tmp_path, primed):
    """A writer killed between its temporary file and the rename (SIGKILL) left
    <key>.bin.tmp-* behind for good; a save now removes those whose writer is
    gone (its pid no longer runs; without a pid, older than an hour) and keeps
    those of a running writer."""
    entry = cache_files(tmp_path / "cache")[0]
    gone = subprocess.Popen(["true"])
    gone.wait()
    dead = entry.with_name(f"{entry.name}.tmp-{gone.pid}-AbCdEf")
    old_style = entry.with_name(f"{entry.name}.tmp-XyZ123")
    running = entry.with_name(f"{entry.name}.tmp-{os.getpid()}-GhIjKl")
    recent = entry.with_name(f"{entry.name}.tmp-MnOpQr")
    for path in (dead, old_style, running, recent):
        path.write_bytes(b"half a binary")
    os.utime(old_style, (1e9, 1e9))
    entry.unlink()  # a miss, so that the render saves
    assert render(tmp_path, tmp_path / "cache")[0] is False
    assert cache_files(tmp_path / "cache") == sorted([entry, running, recent])


def test_an_interrupt_while_the_cache_is_written_leaves_no_temporary_file(tmp_path):
    """Issue 24 finding 7: Ctrl-C between the cache's temporary file and its
    rename left <key>.bin.tmp-* behind; the interrupt now removes it. The
    test hook RTCL_TEST_SLOW_CACHE_WRITE holds the write open."""
    folder = tmp_path / "cache" / "rtcl"
    process = subprocess.Popen([RTCL, *SMALL, "-o", "x.ppm"], cwd=tmp_path,
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                               env=environment(tmp_path / "cache",
                                               RTCL_TEST_SLOW_CACHE_WRITE="20000"))
    try:
        deadline = time.monotonic() + 120
        while not (folder.exists() and any(".tmp-" in p.name for p in folder.iterdir())):
            assert process.poll() is None and time.monotonic() < deadline, \
                "no temporary cache file appeared"
            time.sleep(0.05)
        process.send_signal(signal.SIGINT)
        _, stderr = process.communicate(timeout=60)
    finally:
        process.kill()
        process.wait()
    assert process.returncode == 130, stderr
    assert "rtcl: interrupted; no output written" in stderr
    assert list(folder.iterdir()) == []
    assert not (tmp_path / "x.ppm").exists()
