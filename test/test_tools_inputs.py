"""The tools' inputs and what they refuse before their work (issue 39 items 2, 5, 11,
12, 13 and 15).

- No output names a file the tool reads, by its path, a symbolic link or a hard link
  (rtcl_tools.files: reading() and the writers, one rule for every tool).
- rtcl-imgdiff compares sizes before idiff, which answers FAILURE for images of
  different sizes, and is no comparison.
- A FIFO, folder or device as an input is refused at once with what it is; nothing
  blocks (every run here has a timeout).
- What can be checked is checked before the work: an -o that is a file where a
  folder goes, --max-spp beyond rtcl's --spp, -r 0, --bins and --balls that would
  take hours; the rtcl these tools get leaves a mark if anything runs it.
- The installed rtcl-povray needs no scene file for its default scene.
"""
import os
import pathlib
import shutil
import subprocess
import sys
import time

import numpy as np
import pytest

ROOT = pathlib.Path(__file__).resolve().parent.parent
TOOLS = ROOT / "tools"
sys.path.insert(0, str(TOOLS))

from rtcl_tools import files  # noqa: E402

SCENE = ROOT / "scenes" / "two_balls.json"


def run_tool(name, *args, cwd=None, timeout=60):
    return subprocess.run([sys.executable, str(TOOLS / name), *map(str, args)],
                          capture_output=True, text=True, cwd=cwd or ROOT, timeout=timeout)


def one_error_line(result):
    """The one line a refused run prints (no usage, no traceback)."""
    assert "Traceback" not in result.stderr, result.stderr
    lines = [line for line in result.stderr.splitlines() if line.strip()
             and not line.startswith(("usage:", " "))]
    assert len(lines) == 1, result.stderr
    return lines[0]


@pytest.fixture
def marking_rtcl(tmp_path):
    """An rtcl that leaves a mark and fails: the refusal must come before any run."""
    fake = tmp_path / "bin" / "rtcl"
    fake.parent.mkdir()
    fake.write_text(f"#!/bin/sh\ntouch {tmp_path / 'rtcl-ran'}\nexit 7\n")
    fake.chmod(0o755)
    return fake


def ran(tmp_path):
    return (tmp_path / "rtcl-ran").exists()


# ---- an output never names an input (item 2) ------------------------------------------

def name_input(tmp_path, source, how, name):
    """Returns the output path naming source: the same path, a symbolic link to it
    or a hard link (another name of its inode)."""
    if how == "path":
        return source
    output = tmp_path / name
    if how == "symlink":
        output.symlink_to(source)
    else:
        os.link(source, output)
    return output


def flops_input(tmp_path):
    path = tmp_path / "run.npy"
    np.save(path, np.arange(16, dtype="<u8").reshape(4, 4))
    return path


def schedule_input(tmp_path):
    path = tmp_path / "sched.npy"
    np.save(path, np.zeros((4, 4, 3), dtype=np.uint32))
    return path


def scene_input(tmp_path):
    path = tmp_path / "x.json"
    shutil.copyfile(SCENE, path)
    return path


# (tool, input maker, output name when not the input's own path, arguments with
# {input}, {output} and {rtcl}); an output naming the input by its own path is only
# possible where the tool takes that file name as an output.
CASES = [
    ("povray.py", scene_input, "x.pov", ["-s", "{input}", "-o", "{output}"]),
    ("povray.py", scene_input, "x.png", ["-s", "{input}", "--image", "{output}", "--time", "1"]),
    ("flops_hist.py", flops_input, "fig.png", ["{input}", "-o", "{output}"]),
    ("maps.py", flops_input, "maps.png", ["--work", "{input}", "-o", "{output}"]),
    ("schedule_replay.py", schedule_input, "replay.gif", ["{input}", "-o", "{output}"]),
    ("time_to_image.py", scene_input, "t.txt",
     ["--rtcl", "{rtcl}", "-s", "{input}", "-r", "1", "-o", "{output}"]),
    ("bench.py", scene_input, "out/bench.md",
     ["--rtcl", "{rtcl}", "--quick", "-s", "{input}", "-o", "{folder}"]),
    ("bench_spp.py", scene_input, "out/spp.md",
     ["--rtcl", "{rtcl}", "-s", "{input}", "-o", "{folder}"]),
    ("experiments.py", scene_input, "out/table1.md",
     ["--rtcl", "{rtcl}", "--quick", "-s", "{input}", "-o", "{folder}"]),
]
HOWS = ("path", "symlink", "hardlink")
# make test's 3 minutes: hard links through every tool under make test-long (the
# writers' own test below covers them in make test, povray.py here).
PARAMS = [pytest.param(tool, make, name, args, how, id=f"{tool}:{name}:{how}",
                       marks=[pytest.mark.slow] if how == "hardlink"
                       and tool != "povray.py" else [])
          for tool, make, name, args in CASES for how in HOWS
          if how != "path" or name.endswith((".pov", ".txt"))]


@pytest.mark.parametrize("tool, make, name, args, how", PARAMS)
def test_no_output_names_an_input(tmp_path, marking_rtcl, tool, make, name, args, how):
    source = make(tmp_path)
    before = source.read_bytes()
    if "/" in name:
        (tmp_path / name).parent.mkdir()
    output = name_input(tmp_path, source, how, name)
    values = {"input": source, "output": output, "rtcl": marking_rtcl,
              "folder": output.parent}
    result = run_tool(tool, *[arg.format(**values) for arg in args], cwd=tmp_path)
    assert result.returncode != 0
    line = one_error_line(result)
    assert "is an input of this run" in line and "not overwritten" in line, line
    assert source.read_bytes() == before
    assert not ran(tmp_path), "the refusal came after running rtcl"
    assert not list(tmp_path.rglob(".*.tmp"))


def test_the_writers_refuse_an_input_by_any_name(tmp_path):
    source = tmp_path / "scene.json"
    source.write_text("the input")
    (tmp_path / "link.json").symlink_to(source)
    os.link(source, tmp_path / "hard.json")
    with files.inputs_forgotten():
        files.reading([source, tmp_path / "missing.json", None])
        for name in ("scene.json", "link.json", "hard.json"):
            with pytest.raises(files.InputFileError, match="is an input of this run"):
                files.write_text(tmp_path / name, "replaced")
            with pytest.raises(files.InputFileError):
                files.write_all({tmp_path / name: "replaced"})
            with pytest.raises(files.InputFileError):
                files.remove(tmp_path / name)
        files.write_text(tmp_path / "other.json", "an output")
    files.write_text(tmp_path / "scene.json", "written once the inputs are forgotten")
    assert source.read_text().startswith("written")


# ---- rtcl-imgdiff: sizes before idiff (item 5) -------------------------------------------

def oiio_image(path, size, channels=3, value=0.5):
    """Writes a constant image of size "WxH" with oiiotool."""
    colour = ",".join([str(value)] * channels)
    subprocess.run(["oiiotool", "--pattern", f"constant:color={colour}", size, str(channels),
                    "-o", str(path)], check=True, capture_output=True, timeout=60)
    return path


needs_oiio = pytest.mark.skipif(not all(shutil.which(name) for name in
                                        ("oiiotool", "idiff", "iinfo")),
                                reason="OpenImageIO's tools (openimageio-tools) not installed")


@needs_oiio
@pytest.mark.parametrize("reference, other", [
    ("a.exr:16x16", "b.exr:16x12"),     # EXR against EXR
    ("a.png:16x16", "b.exr:16x12"),     # the reference read here, the other by idiff
    # make test's 3 minutes (OpenImageIO's programs take half a second each to start)
    pytest.param("a.exr:16x16", "p3.ppm:2x2", marks=pytest.mark.slow),  # an ASCII PPM
    pytest.param("a.exr:16x16", "b.exr:16x16:4", marks=pytest.mark.slow),  # 4 channels
])
def test_imgdiff_fails_on_images_of_different_sizes(tmp_path, reference, other):
    paths = []
    for spec in (reference, other):
        name, size, *channels = spec.split(":")
        if name.endswith(".ppm"):
            (tmp_path / name).write_text("P3\n2 2\n255\n0 0 0 1 1 1 2 2 2 3 3 3\n")
        else:
            oiio_image(tmp_path / name, size, int(channels[0]) if channels else 3)
        paths.append(tmp_path / name)
    result = run_tool("imgdiff.py", *paths, cwd=tmp_path)
    assert result.returncode == 1, result.stdout + result.stderr
    assert result.stdout.startswith(f"{paths[1]}: size ") and " differs from " in result.stdout
    assert result.stderr == ""


@needs_oiio
@pytest.mark.slow  # make test's 3 minutes; test_ppmdiff.py compares through idiff too
def test_imgdiff_through_idiff_still_compares_equal_sizes(tmp_path):
    oiio_image(tmp_path / "a.exr", "8x8", value=0.5)
    oiio_image(tmp_path / "b.exr", "8x8", value=0.5)
    oiio_image(tmp_path / "c.exr", "8x8", value=0.25)
    same = run_tool("imgdiff.py", tmp_path / "a.exr", tmp_path / "b.exr")
    assert same.returncode == 0 and "same pixels" in same.stdout, same.stdout + same.stderr
    differs = run_tool("imgdiff.py", tmp_path / "a.exr", tmp_path / "c.exr", "-t", "0.1")
    assert differs.returncode == 1 and "FAIL" in differs.stdout, differs.stdout


# ---- inputs that are not regular files (item 11) ------------------------------------------

@pytest.fixture
def fifo(tmp_path):
    path = tmp_path / "fifo"
    os.mkfifo(path)
    return path


def png(tmp_path):
    """Writes a 1x1 grey PNG."""
    import struct
    import zlib

    def chunk(kind, data):
        return (struct.pack(">I", len(data)) + kind + data
                + struct.pack(">I", zlib.crc32(kind + data)))
    path = tmp_path / "e.png"
    header = struct.pack(">IIBBBBB", 1, 1, 8, 0, 0, 0, 0)   # 1x1, 8 bits, grey
    path.write_bytes(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header)
                     + chunk(b"IDAT", zlib.compress(b"\x00\x80")) + chunk(b"IEND", b""))
    return path


@pytest.mark.parametrize("order", ["reference first", "fifo first"])
def test_imgdiff_refuses_a_fifo_at_once(tmp_path, fifo, order):
    names = [png(tmp_path), fifo] if order == "reference first" else [fifo, png(tmp_path)]
    start = time.monotonic()
    result = run_tool("imgdiff.py", *names, timeout=30)
    assert time.monotonic() - start < 20
    assert result.returncode == 2
    assert one_error_line(result) == \
        f"imgdiff.py: error: {fifo}: cannot read: is a FIFO (named pipe), not a regular file"


@needs_oiio
def test_imgdiff_refuses_a_fifo_before_idiff(tmp_path, fifo):
    result = run_tool("imgdiff.py", oiio_image(tmp_path / "a.exr", "4x4"), fifo, timeout=30)
    assert result.returncode == 2
    assert "is a FIFO (named pipe), not a regular file" in one_error_line(result)


@pytest.mark.parametrize("kind", ["FIFO (named pipe)", "folder"])
def test_flops_hist_says_what_an_input_is(tmp_path, fifo, kind):
    path = fifo if kind.startswith("FIFO") else tmp_path / "folder"
    path.mkdir(exist_ok=True) if kind == "folder" else None
    result = run_tool("flops_hist.py", path, "-o", tmp_path / "fig.png", timeout=30)
    assert result.returncode == 1
    assert one_error_line(result) == f"flops_hist.py: error: {path}: is a {kind}, not a " \
                                     "regular file"
    assert not (tmp_path / "fig.png").exists()


def test_open_input_never_blocks(tmp_path, fifo):
    with pytest.raises(files.NotRegularFileError, match="is a FIFO"):
        files.open_input(fifo)
    with pytest.raises(files.NotRegularFileError, match="is a folder"):
        files.open_input(tmp_path)
    with pytest.raises(files.NotRegularFileError, match="is a character device"):
        files.open_input("/dev/null")
    with pytest.raises(FileNotFoundError):
        files.open_input(tmp_path / "missing")


# ---- checked before the work (items 12, 13, 15) -------------------------------------------

@pytest.mark.parametrize("tool, args, message", [
    ("bench.py", ["--quick", "-o", "{file}"], "{file}: is a file, not a folder"),
    ("bench.py", ["--quick", "-o", "{file}/sub"], "{file}: is a file, not a folder"),
    ("bench_spp.py", ["-o", "{file}"], "{file}: is a file, not a folder"),
    ("experiments.py", ["--quick", "-o", "{file}"], "{file}: is a file, not a folder"),
    ("bench_spp.py", ["--max-spp", "99999999"], "--max-spp 99999999: expected 1 ... 65536"),
    ("bench.py", ["--quick", "-s", "{fifo}"], "{fifo}: is a FIFO (named pipe)"),
    ("multidevice_bench.py", ["--single", "0:0", "--multi", "0:0", "-r", "0"],
     "-r/--repeat 0: expected at least 1"),
    ("multidevice_bench.py", ["--single", "0:0", "--multi", "0:0", "-o", "{folder}"],
     "{folder}: is a folder, not a file"),
    ("time_to_image.py", ["-r", "1", "-o", "{folder}"], "{folder}: is a folder, not a file"),
    ("flops_hist.py", ["{npy}", "--bins", "100000000"], "--bins 100000000: expected 1 ... 1000"),
    ("genscene.py", ["--balls", "100000000"], "--balls must be 0 ... 1000000"),
])
def test_refused_before_the_work(tmp_path, marking_rtcl, fifo, tool, args, message):
    existing = tmp_path / "EXISTING_FILE"
    existing.write_text("kept\n")
    (tmp_path / "folder").mkdir()
    values = {"file": existing, "fifo": fifo, "folder": tmp_path / "folder",
              "npy": flops_input(tmp_path)}
    args = [arg.format(**values) for arg in args]
    if tool not in ("flops_hist.py", "genscene.py"):
        args += ["--rtcl", marking_rtcl]
    start = time.monotonic()
    result = run_tool(tool, *args, cwd=tmp_path, timeout=60)
    assert time.monotonic() - start < 30
    assert result.returncode in (1, 2)
    assert message.format(**values) in one_error_line(result)
    assert existing.read_text() == "kept\n"
    assert not ran(tmp_path)


def test_installed_povray_makes_its_default_scene(tmp_path):
    """An installed package (pip: .../lib/python3.11/site-packages) has no scenes/
    beside it: the default scene is made as tools/genscene.py makes it."""
    site = tmp_path / "lib" / "python3.11" / "site-packages"
    shutil.copytree(TOOLS / "rtcl_tools", site / "rtcl_tools",
                    ignore=shutil.ignore_patterns("__pycache__"))
    result = subprocess.run(
        [sys.executable, "-c", "import sys; sys.argv = ['rtcl-povray']; "
         "from rtcl_tools.commands.povray import main; sys.exit(main())"],
        capture_output=True, text=True, cwd=tmp_path, timeout=60,
        env=dict(os.environ, PYTHONPATH=str(site)))
    assert result.returncode == 0, result.stderr
    from_file = run_tool("povray.py", "-s", ROOT / "scenes" / "paper60.json")
    assert from_file.returncode == 0, from_file.stderr
    first, *rest = result.stdout.splitlines()
    assert "from paper60 (built in)" in first
    assert rest == from_file.stdout.splitlines()[1:]
    assert result.stdout.count("\nsphere {") >= 60


def test_a_missing_output_folder_is_refused_before_the_runs(tmp_path, marking_rtcl):
    """A single-file output is written beside its target: its folder must exist
    (folder outputs, -o DIR, are made)."""
    result = run_tool("multidevice_bench.py", "--single", "0:0", "--multi", "0:0", "-o",
                      tmp_path / "missing" / "m.md", "--rtcl", marking_rtcl, cwd=tmp_path)
    assert result.returncode == 1
    assert one_error_line(result) == \
        f"multidevice_bench.py: error: {tmp_path / 'missing' / 'm.md'}: No such file or " \
        f"directory (no folder {tmp_path / 'missing'})"
    assert not ran(tmp_path)
