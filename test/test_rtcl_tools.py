"""Tests of the package tools/rtcl_tools itself: the atomic writer, RtclFailed, the
scene validator against rtcl's own bad scenes, and that matplotlib stays out of
every tool until a plot is drawn."""
import os
import pathlib
import re
import subprocess
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tools"))
from rtcl_tools import files, runner, scene  # noqa: E402

BAD_SCENES = ROOT / "test" / "bad_scenes"
GOOD_SCENES = sorted((ROOT / "scenes").glob("*.json")) \
    + sorted((ROOT / "test" / "scenes").glob("*.json"))
# Bad scenes that only a loader that reads the mesh file can refuse (no triangles in
# it, a vertex not finite or placed beyond float, a file the importer cannot parse):
# the validator only checks that a mesh file exists and can be read (see scene.py).
RTCL_ONLY = {"mesh_file_unreadable", "mesh_no_triangles", "mesh_vertex_not_finite",
             "mesh_vertex_beyond_float", "mesh_ply_no_end_header",
             "mesh_importer_crashes"}


# ---- files: the atomic writer -------------------------------------------------------

def test_write_text_replaces_the_target(tmp_path):
    target = tmp_path / "out.md"
    target.write_text("old")
    files.write_text(target, "new\n")
    assert target.read_text() == "new\n"
    assert [p.name for p in tmp_path.iterdir()] == ["out.md"]


def test_failed_write_leaves_the_target_and_no_temporary_file(tmp_path):
    target = tmp_path / "out.md"
    target.write_text("old")
    with pytest.raises(RuntimeError):
        with files.atomic_output(target) as stream:
            stream.write("half")
            raise RuntimeError("interrupted")
    assert target.read_text() == "old"
    assert [p.name for p in tmp_path.iterdir()] == ["out.md"]


def test_failed_rename_leaves_no_temporary_file(tmp_path, monkeypatch):
    def broken_replace(source, target):
        raise OSError("disk full")
    monkeypatch.setattr(os, "replace", broken_replace)
    with pytest.raises(OSError):
        files.write_text(tmp_path / "out.md", "text")
    assert list(tmp_path.iterdir()) == []


def test_missing_folder_names_the_target(tmp_path):
    target = tmp_path / "no-such-dir" / "out.md"
    with pytest.raises(OSError) as caught:
        files.write_text(target, "text")
    assert caught.value.filename == str(target)


def test_written_files_follow_the_umask(tmp_path):
    old = os.umask(0o027)
    try:
        files.write_text(tmp_path / "a", "x")
        files.copy_file(tmp_path / "a", tmp_path / "b")
    finally:
        os.umask(old)
    for name in ("a", "b"):
        assert (tmp_path / name).stat().st_mode & 0o777 == 0o640


# ---- runner: RtclFailed ---------------------------------------------------------------

def fake_rtcl(tmp_path, script):
    path = tmp_path / "rtcl"
    path.write_text("#!/bin/sh\n" + script)
    path.chmod(0o755)
    return str(path)


def settings(tmp_path, rtcl):
    work = tmp_path / "work"
    work.mkdir()
    return runner.Settings(rtcl, ["--size", "8x8"], 1, work)


class Quiet(runner.Progress):
    def start(self, description):
        pass

    def fail(self, note="failed"):
        pass


def test_rtcl_failed_carries_command_status_and_stderr(tmp_path):
    rtcl = fake_rtcl(tmp_path, "echo 'rtcl: -w 64x128: too large' >&2\nexit 3\n")
    with pytest.raises(runner.RtclFailed) as caught:
        runner.run_rtcl(settings(tmp_path, rtcl), Quiet(1), "run", "naive", "64x128")
    error = caught.value
    assert error.command[0] == rtcl and error.command[1:3] == ["-k", "naive"]
    assert error.command[error.command.index("-w") + 1] == "64x128"
    assert error.returncode == 3
    assert error.stderr == "rtcl: -w 64x128: too large\n"
    assert error.reason == "-w 64x128: too large"
    assert "exit 3" in str(error) and "too large" in str(error)


def test_rtcl_that_cannot_start_has_no_status(tmp_path):
    missing = str(tmp_path / "no-such-rtcl")
    with pytest.raises(runner.RtclFailed) as caught:
        runner.run_rtcl(settings(tmp_path, missing), Quiet(1), "run", "naive")
    assert caught.value.returncode is None and caught.value.command[0] == missing
    assert caught.value.reason.startswith(f"cannot run {missing}")


def test_rtcl_reason_prefers_rtcls_own_line():
    assert runner.rtcl_reason("warning\nrtcl: no device\n") == "no device"
    assert runner.rtcl_reason("plain failure\n") == "plain failure"
    assert runner.rtcl_reason("") == "no message"


# ---- scene: the validator against rtcl's bad and good scenes --------------------------

def rtcl_message(bad):
    """Returns rtcl's message for bad (its .expect file) without the file name."""
    return bad.with_suffix(".expect").read_text(encoding="utf-8").strip().replace("{FILE}", "")


@pytest.mark.parametrize("bad", sorted(p for p in BAD_SCENES.glob("*.json")
                                        if p.stem not in RTCL_ONLY), ids=lambda p: p.stem)
def test_every_scene_rtcl_refuses_is_refused_with_its_message(bad):
    with pytest.raises(scene.SceneError) as caught:
        scene.load_scene(bad)
    expected, message = rtcl_message(bad), str(caught.value)
    if re.match(r":\d+:\d+: ", expected):
        return      # a JSON syntax error: Python words it its own way
    assert ": " + message == expected


@pytest.mark.parametrize("name", sorted(RTCL_ONLY))
def test_what_only_the_mesh_importer_sees_passes_the_validator(name):
    """Each exception is a real bad scene of rtcl's that the validator accepts: when
    it learns to refuse one, the test says to take it off the list."""
    bad = BAD_SCENES / f"{name}.json"
    assert rtcl_message(bad).startswith(": meshes[0].file: ")
    loaded = scene.load_scene(bad)
    assert os.path.isfile(loaded["meshes"][0]["file"])


def test_the_bad_scenes_cover_every_version_2_rule():
    names = {p.stem for p in BAD_SCENES.glob("*.json")}
    for needed in ("meshes_in_version_1", "triangles_in_version_1", "mesh_file_not_found",
                   "mesh_file_is_folder", "mesh_file_empty", "mesh_scale_zero",
                   "mesh_scale_zero_number", "mesh_rotate_not_array", "mesh_not_object",
                   "mesh_smooth_not_boolean", "mesh_unknown_material", "triangle_zero_area",
                   "triangle_vertex_not_vec3", "triangle_not_object", "triangles_not_array",
                   "samples_zero_v1", "samples_65537_v2"):
        assert needed in names


@pytest.mark.parametrize("good", GOOD_SCENES, ids=lambda p: p.name)
def test_every_shipped_scene_is_accepted(good):
    loaded = scene.load_scene(good)
    assert loaded["camera"]["fov"] > 0


def test_validator_fills_in_scene_md_defaults():
    loaded = scene.read_scene({"format": "rtcl-scene", "version": 1,
                               "camera": {"eye": [0, 0, -1], "look_at": [0, 0, 0]},
                               "spheres": [{"center": [0, 0, 0], "radius": 1}],
                               "planes": [{"point": [0, 0, 0], "normal": [0, 3, 0]}]})
    assert loaded["size"] == (640, 480) and loaded["max_depth"] == 5
    assert loaded["camera"]["up"] == (0.0, 1.0, 0.0) and loaded["camera"]["fov"] == 45
    assert loaded["spheres"][0]["material"] == scene.MATERIAL_DEFAULTS
    assert loaded["planes"][0]["normal"] == (0.0, 1.0, 0.0)


def test_validator_refuses_numbers_the_device_cannot_hold():
    doc = {"format": "rtcl-scene", "version": 1,
           "camera": {"eye": [0, 0, -1], "look_at": [0, 0, 0]},
           "spheres": [{"center": [0, 0, 0], "radius": 1e-20}]}
    with pytest.raises(scene.SceneError, match=r"spheres\[0\]\.radius: must be between"):
        scene.read_scene(doc)


# ---- every tool starts without matplotlib -----------------------------------------------

def blocking(tmp_path, *modules):
    """Returns an environment in which importing any of modules raises ImportError."""
    for module in modules:
        blocker = tmp_path / "blockers" / module
        blocker.mkdir(parents=True)
        (blocker / "__init__.py").write_text(f"raise ImportError('{module} is blocked')\n")
    return dict(os.environ, PYTHONPATH=str(tmp_path / "blockers"))


@pytest.mark.parametrize("tool", sorted(path.name for path in (ROOT / "tools").glob("*.py")))
def test_help_needs_no_matplotlib(tmp_path, tool):
    result = subprocess.run([sys.executable, str(ROOT / "tools" / tool), "--help"],
                            capture_output=True, text=True, cwd=tmp_path,
                            env=blocking(tmp_path, "matplotlib"), timeout=60)
    assert result.returncode == 0, result.stderr
    assert result.stdout.startswith(f"usage: {tool} ")


@pytest.mark.parametrize("tool, module, args", [
    ("flops_hist.py", "matplotlib", ["x.npy"]),
    ("experiments.py", "numpy", ["--quick"]),
    ("genbench.py", "numpy", ["balls", "-o", "out"]),
    ("maps.py", "matplotlib", ["--work", "x.npy"]),
])
def test_a_missing_module_is_one_line_saying_how_to_install_it(tmp_path, tool, module, args):
    result = subprocess.run([sys.executable, str(ROOT / "tools" / tool), *args],
                            capture_output=True, text=True, cwd=tmp_path,
                            env=blocking(tmp_path, module), timeout=60)
    assert result.returncode == 1
    # The Python that lacks it and the commands that install it (the blocked module
    # is blocked in every Python: none to run the tool under instead, checkout.py).
    assert result.stderr == (f"{tool}: needs {module}, which {sys.executable} lacks: `make "
                             f"deps` (Debian's python3-{module} for /usr/bin/python3, which "
                             f"tools/NAME.py then uses), or `{sys.executable} -m pip install "
                             f"{module}`\n")
    assert list(tmp_path.iterdir()) == [tmp_path / "blockers"]


# ---- one option style across the tools -------------------------------------------------

SHORT_FOR = {"--out": "-o", "--output": "-o", "--platform": "-p", "--device": "-d",
             "--scene": "-s", "--repeat": "-r", "--kernel": "-k"}


@pytest.mark.parametrize("tool", sorted(path.name for path in (ROOT / "tools").glob("*.py")))
def test_the_same_meaning_has_the_same_short_option(tool):
    args = ["balls", "--help"] if tool == "genbench.py" else ["--help"]
    result = subprocess.run([sys.executable, str(ROOT / "tools" / tool), *args],
                            capture_output=True, text=True, timeout=60)
    assert result.returncode == 0, result.stderr
    option_lines = [line.strip() for line in result.stdout.splitlines()
                    if line.strip().startswith("-")]
    for line in option_lines:
        names = re.findall(r"(?<![\w-])(--?[a-z][a-z-]*)", line.split("  ")[0])
        for long, short in SHORT_FOR.items():
            if long in names:
                assert short in names, f"{tool}: {line}"


def test_the_multidevice_bench_times_a_frame_by_its_wall_time():
    """One device's frame_ms (its launches and the gaps between them) is set
    beside several devices' wall time, not its kernel time alone; an rtcl
    without frame_ms gives kernel_ms."""
    from rtcl_tools.commands import multidevice_bench
    assert multidevice_bench.image_time({"kernel_ms": 1861.0, "frame_ms": 1932.0}) == 1932.0
    assert multidevice_bench.image_time({"kernel_ms": 1052.0}) == 1052.0
