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
    batch = ["--batch", "100"] if kernel == "persistent" else []
    result = rtcl("-q", "-k", kernel, "--groups", "300x300", *batch, *TINY, "-o", str(out))
    assert result.returncode == 0, result.stderr
    assert out.stat().st_size > 0


def test_help_states_the_work_item_limit():
    assert "2^31 work-items in all" in rtcl("--help").stdout


# ---- options given values they do not take, unknown options -------------------

@pytest.mark.parametrize("arg,message", [
    ("--quiet=1", "option --quiet takes no value (see --help)"),
    ("--verbose=yes", "option --verbose takes no value (see --help)"),
    ("--help=1", "option --help takes no value (see --help)"),
    ("--version=2", "option --version takes no value (see --help)"),
    ("--list-devices=0", "option --list-devices takes no value (see --help)"),
    ("--qui=1", "option --quiet takes no value (see --help)"),  # an abbreviation
    ("--quiet=", "option --quiet takes no value (see --help)"),
    ("--nope", "unknown option --nope (see --help)"),
    ("--nope=3", "unknown option --nope (see --help)"),
    ("--ver", "ambiguous option --ver (see --help)"),  # --verbose or --version
    ("-x", "unknown option -x (see --help)"),
    ("-qx", "unknown option -x (see --help)"),
    ("-xq", "unknown option -x (see --help)"),
    ("--stats", "--stats needs a value (see --help)"),
    ("-vk", "-k needs a value (see --help)"),
])
def test_option_errors_name_the_option(arg, message, tmp_path):
    result = rtcl("-o", str(tmp_path / "out.png"), arg)
    expect_failure(result, 2, message, tmp_path)
    assert result.stderr == "rtcl: " + message + "\n"


# ---- empty file names are usage errors -----------------------------------------

@pytest.mark.parametrize("option,name", [
    ("-o", "-o/--output"), ("--output", "-o/--output"), ("-s", "-s/--scene"),
    ("--scene", "-s/--scene"), ("--stats", "--stats"), ("--flops", "--flops"),
    ("--work-map", "--work-map"),
])
def test_empty_file_name_is_a_usage_error(option, name, tmp_path):
    args = ["-o", str(tmp_path / "out.png")] if name != "-o/--output" else []
    result = rtcl(*TINY, *args, option, "")
    expect_failure(result, 2, name + ": the file name is empty", tmp_path)


# ---- integers: digits only --------------------------------------------------------

@pytest.mark.parametrize("args,message", [
    (["--size", " 8x 8"], '--size: expected WxH (e.g. 8x8), got " 8x 8"'),
    (["--size", "+8x+8"], '--size: expected WxH (e.g. 8x8), got "+8x+8"'),
    (["--size", "8x8 "], '--size: expected WxH (e.g. 8x8), got "8x8 "'),
    (["--size", "8x-8"], '--size: expected WxH (e.g. 8x8), got "8x-8"'),
    (["-w", "+8x8"], '-w/--workgroup: expected WxH (e.g. 8x8), got "+8x8"'),
    # The tab shown escaped (issue 24, finding 16).
    (["--groups", "\t2x2"], '--groups: expected WxH (e.g. 8x8), got "\\t2x2"'),
    (["--depth", "+3"], '--depth: expected an integer between 0 and 64, got "+3"'),
    (["--depth", " 3"], '--depth: expected an integer between 0 and 64, got " 3"'),
    (["-r", "+2"], '-r/--repeat: expected an integer between 1 and 100000, got "+2"'),
    (["--batch", " 4"], '--batch: expected an integer between 1 and 4096, got " 4"'),
    (["-p", "+0"], '-p/--platform: expected an integer between 0 and 1000, got "+0"'),
    (["-d", " 0"], '-d/--device: expected an integer between 0 and 1000, got " 0"'),
    (["--size", "99999999999999999999x8"],
     "--size: each size must be between 1 and 32768, got 99999999999999999999x8"),
])
def test_integers_are_digits_only(args, message, tmp_path):
    result = rtcl("-o", str(tmp_path / "out.png"), *args)
    expect_failure(result, 2, message, tmp_path)


def test_leading_zeros_are_still_decimal(tmp_path):
    out = tmp_path / "out.ppm"
    result = rtcl("-q", "--size", "010x08", "--depth", "03", "-o", str(out))
    assert result.returncode == 0, result.stderr
    fields = [f for line in out.read_bytes().split(b"\n")[:8] if not line.startswith(b"#")
              for f in line.split()]
    assert fields[:3] == [b"P6", b"10", b"8"]


# ---- --flops writes NumPy data: a .npy name ------------------------------------------

@pytest.mark.parametrize("name", ["f.txt", "f", "f.npy.json", "f.np"])
def test_flops_needs_a_npy_name(name, tmp_path):
    result = rtcl(*TINY, "-o", str(tmp_path / "out.png"), "--flops", str(tmp_path / name))
    expect_failure(result, 2, "--flops: the file name must end in .npy", tmp_path)
    assert str(tmp_path / name) in result.stderr


def test_flops_npy_extension_in_any_case(tmp_path):
    flops = tmp_path / "F.NPY"
    result = rtcl("-q", *TINY, "-o", str(tmp_path / "out.ppm"), "--flops", str(flops))
    assert result.returncode == 0, result.stderr
    assert flops.read_bytes().startswith(b"\x93NUMPY")


# ---- PoCL without a writable cache directory ---------------------------------------

POCL_VARIABLES = ("HOME", "XDG_CACHE_HOME", "POCL_CACHE_DIR")


def as_unprivileged(*args, **env):
    """Runs rtcl as `nobody` when we are root (root can create /nonexistent,
    so PoCL never fails for it), with the PoCL cache variables given in env
    and no others."""
    base = {k: v for k, v in os.environ.items() if k not in POCL_VARIABLES}
    prefix = []
    if os.geteuid() == 0:
        setpriv = shutil.which("setpriv")
        if not setpriv:
            pytest.skip("running as root without setpriv to drop privileges")
        prefix = [setpriv, "--reuid=65534", "--regid=65534", "--clear-groups"]
    return subprocess.run([*prefix, RTCL, *args], capture_output=True, text=True,
                          cwd="/", env={**base, **env}, timeout=300)


@pytest.fixture
def shared_dir():
    """A directory anyone may write in, for the unprivileged runs."""
    path = tempfile.mkdtemp(prefix="rtcl-test-")
    os.chmod(path, 0o777)
    yield pathlib.Path(path)
    shutil.rmtree(path, ignore_errors=True)


@pytest.fixture
def unprivileged_rtcl_works(shared_dir):
    cache = shared_dir / "cache"
    result = as_unprivileged("--list-devices", POCL_CACHE_DIR=str(cache))
    if "Device #0" not in result.stdout:
        pytest.skip("rtcl cannot run unprivileged here: " + result.stdout + result.stderr)


ADVICE = "set POCL_CACHE_DIR to a writable directory, e.g. POCL_CACHE_DIR=$(mktemp -d)"


@pytest.mark.parametrize("env,cause", [
    ({"HOME": "/nonexistent"},
     "cannot create /nonexistent/.cache/pocl (from HOME=/nonexistent): /nonexistent does not "
     "exist and / is not writable"),
    ({"HOME": "/", "XDG_CACHE_HOME": "/nonexistent/xdg"},
     "cannot create /nonexistent/xdg/pocl (from XDG_CACHE_HOME=/nonexistent/xdg)"),
    ({"HOME": "/", "POCL_CACHE_DIR": "/proc/rtcl-pocl"},
     "cannot create /proc/rtcl-pocl (from POCL_CACHE_DIR): /proc/rtcl-pocl does not exist "
     "and /proc is not writable"),
])
def test_no_writable_pocl_cache_is_explained(env, cause, shared_dir, unprivileged_rtcl_works):
    out = shared_dir / "out"
    out.mkdir()
    out.chmod(0o777)
    result = as_unprivileged(*TINY, "-o", str(out / "x.png"), **env)
    expect_failure(result, 1, "no OpenCL device found on any platform; PoCL needs a writable "
                   "cache directory and " + cause, out)
    assert ADVICE in result.stderr


def test_unwritable_home_is_explained(shared_dir, unprivileged_rtcl_works):
    home = shared_dir / "home"
    home.mkdir(mode=0o555)
    home.chmod(0o555)  # root's: not writable by nobody
    result = as_unprivileged(*TINY, "-o", str(shared_dir / "x.png"), HOME=str(home))
    expect_failure(result, 1, f"(from HOME={home}): {home}/.cache does not exist and {home} "
                   "is not writable", home)
    assert ADVICE in result.stderr


def test_list_devices_explains_a_platform_without_devices(shared_dir, unprivileged_rtcl_works):
    result = as_unprivileged("--list-devices", HOME="/nonexistent")
    assert result.returncode == 0, result.stderr
    assert " `-- no devices; PoCL needs a writable cache directory" in result.stdout
    assert ADVICE in result.stdout


def test_writable_pocl_cache_dir_renders(shared_dir, unprivileged_rtcl_works):
    out = shared_dir / "x.ppm"
    result = as_unprivileged("-q", *TINY, "-o", str(out), HOME="/nonexistent",
                             POCL_CACHE_DIR=str(shared_dir / "cache"))
    assert result.returncode == 0, result.stderr
    assert out.stat().st_size > 0


def test_help_names_pocl_cache_dir():
    assert "POCL_CACHE_DIR=DIR" in rtcl("--help").stdout


# ---- control bytes in paths and option values (issue 24, finding 16) ----------

ESC_CLEAR = "\x1b[2J"  # would clear the terminal if echoed raw


@pytest.mark.parametrize("args, shown", [
    (["-s", "a\nb" + ESC_CLEAR + ".json"], "a\\nb\\x1b[2J.json: cannot open"),
    (["-o", "missing\n/x.png"], "missing\\n/x.png: directory \"missing\\n\" does not exist"),
    (["-o", "x" + ESC_CLEAR + ".bmpx"], "x\\x1b[2J.bmpx: unknown image format"),
    (["--size", "8x" + ESC_CLEAR], "got \"8x\\x1b[2J\""),
    (["-k", "x\ny"], "unknown kernel \"x\\ny\""),
    (["--encoding", "\x1b"], "got \"\\x1b\""),
    (["--devices", "0:0,\n"], "got \"0:0,\\n\""),
    (["--fo\x1bo"], "unknown option --fo\\x1bo"),
    (["one\n.json", "two\t.json"], "two scenes given, \"one\\n.json\" and \"two\\t.json\""),
])
def test_control_bytes_are_escaped_in_messages(tmp_path, args, shown):
    if args[0] == "-o":
        args = [*TINY, *args]  # relative to tmp_path, the working directory
    result = subprocess.run([RTCL, *args], capture_output=True, text=True, cwd=tmp_path,
                            timeout=60)
    assert result.returncode != 0
    assert "\x1b" not in result.stderr and "\t" not in result.stderr
    lines = result.stderr.splitlines()
    assert len(lines) == 1, result.stderr
    assert shown in lines[0], lines[0]
    assert sorted(os.listdir(tmp_path)) == []


def test_control_bytes_in_a_scene_file_name_are_escaped_in_its_messages(tmp_path):
    scene = tmp_path / ("s\n" + ESC_CLEAR + ".json")
    scene.write_text("{}")
    result = rtcl("-s", str(scene), "-o", str(tmp_path / "x.png"))
    assert result.returncode == 1
    (line,) = result.stderr.splitlines()
    assert line == f"{tmp_path}/s\\n\\x1b[2J.json: format: required field is missing", line
    assert sorted(p.name for p in tmp_path.iterdir()) == [scene.name]


# ---- options that do not apply (issue 39, finding 18) -------------------------
# One rule (GUIDE.md, "Options that do not apply"): refused with one message
# naming what the option needs, before any work. The first four were accepted
# and ignored on a5dea23; the last three were refused already and keep it.

NOT_APPLYING = [
    (["-k", "naive", "--groups", "4x4"],
     "--groups sets the persistent work-groups of -k cyclic, dynamic and persistent; it does "
     "not apply to -k naive"),
    (["-k", "reference", "--groups", "4x4"], "it does not apply to -k reference"),
    (["-k", "dynamic", "--batch", "4"],
     "--batch sets the pixels a work-item of -k persistent fetches at a time; it does not "
     "apply to -k dynamic"),
    (["-k", "serial", "--queues", "2"],
     "--queues sets the command queues of -k naive, cyclic, dynamic and persistent; it does "
     "not apply to -k serial, which renders on one"),
    (["-k", "wavefront", "--queues", "2"], "it does not apply to -k wavefront"),
    (["--work-map-scale", "log"],
     "--work-map-scale sets the colours of a --work-map picture; give --work-map an image "
     "file (not .npy, .exr, .pfm or .hdr)"),
    (["--work-map", "w.npy", "--work-map-scale", "log"], "--work-map-scale sets the colours"),
    (["--work-map-bar", "bar.png"], "--work-map-bar: the bar is the legend of a --work-map "
     "picture"),
    (["--split", "static"], "--split chooses how pieces go to the devices of --devices or "
     "--mpi; it does not apply to a render without them"),
    (["--piece-rows", "4"], "--piece-rows cuts one image into bands"),
]


@pytest.mark.parametrize("args, message", NOT_APPLYING)
def test_an_option_that_does_not_apply_is_refused_naming_what_it_needs(tmp_path, args, message):
    result = subprocess.run([RTCL, *TINY, "-o", "o.png", *args], capture_output=True,
                            text=True, cwd=tmp_path, timeout=60)
    expect_failure(result, 2, message, tmp_path)


@pytest.mark.parametrize("args", [["-k", "cyclic", "--groups", "2x2"],
                                  ["-k", "persistent", "--batch", "4", "--groups", "2x2"],
                                  ["-k", "naive", "--queues", "2"],
                                  ["--work-map", "w.ppm", "--work-map-scale", "log"]])
def test_the_same_options_where_they_apply_render(tmp_path, args):
    result = subprocess.run([RTCL, *TINY, "-q", "-o", "o.png", *args], capture_output=True,
                            text=True, cwd=tmp_path, timeout=120)
    assert result.returncode == 0, result.stderr
    assert (tmp_path / "o.png").is_file()


def test_help_states_the_rule_for_options_that_do_not_apply():
    text = " ".join(rtcl("--help").stdout.split())
    assert "An option that sets something the run does not have is refused, naming what " \
           "it needs" in text
