"""The study from a checkout (issue 44 item 5).

- tools/NAME.py runs under a Python that has its modules (rtcl_tools.checkout), or
  stops at once with one line naming them and the command that installs them.
- An interrupted or failed tools/experiments.py keeps its finished runs in its
  folder; --resume goes on without running them again.
- Ctrl-C and SIGTERM end it without a traceback and remove its temporary folder.
- On a CPU, Table 1's bounds say that SIMD efficiency (a GPU's warps) does not apply.
- --replot honours --fma-units for a CPU's study, and refuses it otherwise.
- The README's study section and the paper's geometries (--accel none).

The rtcl here is a shell script (fast): it writes --stats and --flops as rtcl does,
and fails or hangs at the call named in a file beside it.
"""
import json
import os
import pathlib
import re
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

ROOT = pathlib.Path(__file__).resolve().parent.parent
TOOLS = ROOT / "tools"
sys.path.insert(0, str(TOOLS))

from rtcl_tools import experiment, runner, table1  # noqa: E402

POCL = "pthread-haswell-AMD EPYC 7B13 (Portable Computing Language)"

FAKE_RTCL = r"""#!/bin/sh
here=$(dirname "$0")
n=$(( $(cat "$here/count" 2>/dev/null || echo 0) + 1 ))
echo "$n" > "$here/count"
echo "$*" >> "$here/calls"
if [ -e "$here/hang-at" ] && [ "$n" -ge "$(cat "$here/hang-at")" ]; then
    echo $$ > "$here/pid"; touch "$here/hanging"; exec sleep 600
fi
if [ -e "$here/fail-at" ] && [ "$n" -ge "$(cat "$here/fail-at")" ]; then
    echo "rtcl: device lost" >&2; exit 3
fi
k=; st=; fl=; w=8x8; g=4x4
while [ $# -gt 0 ]; do
    case "$1" in
        -q) shift; continue;;
        -k) k=$2;; --stats) st=$2;; --flops) fl=$2;; -w) w=$2;; --groups) g=$2;;
    esac
    shift 2
done
[ -n "$fl" ] && cp "$here/counts.npy" "$fl"
device=$(cat "$here/device")
[ "$k" = reference ] && device="CPU reference (C++, GLM, double precision, one core)"
{
    printf '{"device": "%s", "kernel": "%s", "kernel_ms": 10.0, ' "$device" "$k"
    printf '"workgroup": "%s", "groups": "%s", "global_size": [4, 4], ' "$w" "$g"
    printf '"width": 4, "height": 4, "max_depth": 5, "scene": "paper60.json (built-in)", '
    printf '"gflop": 1e-05, "parallel_efficiency": 0.5}\n'
} > "$st"
"""


@pytest.fixture
def fake_rtcl(tmp_path):
    folder = tmp_path / "bin"
    folder.mkdir()
    np.save(folder / "counts.npy", np.arange(1, 17, dtype="<u8").reshape(4, 4) * 100)
    (folder / "device").write_text("Fake GPU (NVIDIA CUDA)")
    fake = folder / "rtcl"
    fake.write_text(FAKE_RTCL)
    fake.chmod(0o755)
    return fake


def calls(fake):
    return (fake.parent / "calls").read_text().splitlines()


def running(pid):
    """Whether process pid runs (exists and is not a zombie)."""
    try:
        with open(f"/proc/{pid}/stat") as stat:
            return stat.read().rsplit(")", 1)[1].split()[0] != "Z"
    except (OSError, IndexError):
        return False


def assert_rtcl_ended(fake):
    """The hanging rtcl did not outlive the tool that ran it."""
    pid = int((fake.parent / "pid").read_text())
    deadline = time.monotonic() + 10
    while running(pid):
        if time.monotonic() > deadline:
            os.kill(pid, signal.SIGKILL)
            pytest.fail("the rtcl the tool ran was left running")
        time.sleep(0.05)


def tool_env(tmp_path):
    """The tools' environment, their temporary folders in tmp_path/tmp."""
    (tmp_path / "tmp").mkdir(exist_ok=True)
    return dict(os.environ, TMPDIR=str(tmp_path / "tmp"))


def experiments(tmp_path, *args, **options):
    return subprocess.run([sys.executable, str(TOOLS / "experiments.py"), *map(str, args)],
                          capture_output=True, text=True, cwd=tmp_path, timeout=300,
                          env=tool_env(tmp_path), **options)


# 7 runs: serial, reference, 5 paper geometries; no figures (a second each to draw)
QUICK = ("--quick", "--no-sweep", "--no-plots")


def run_names(folder):
    return [(run["role"], run["kernel"], run["workgroup"], run["groups"])
            for run in json.loads((folder / "results.json").read_text())["runs"]]


# ---- --resume ---------------------------------------------------------------------------

def test_a_failed_study_keeps_its_runs_and_resumes(tmp_path, fake_rtcl):
    (fake_rtcl.parent / "fail-at").write_text("4")
    out = tmp_path / "out"
    failed = experiments(tmp_path, "--rtcl", fake_rtcl, *QUICK, "-o", out)
    assert failed.returncode == 1
    assert "rtcl: device lost" in failed.stderr and "Traceback" not in failed.stderr
    assert f"3 run(s) kept in {out}/study-progress.json: `tools/experiments.py --resume " \
           f"{out}` goes on with the study" in failed.stderr
    assert sorted(path.name for path in out.iterdir()) == ["study-progress.json"]
    assert not list((tmp_path / "tmp").iterdir())

    (fake_rtcl.parent / "fail-at").unlink()
    resumed = experiments(tmp_path, "--resume", out)
    assert resumed.returncode == 0, resumed.stderr
    assert resumed.stderr.count("(measured before the interruption)") == 3
    assert len(calls(fake_rtcl)) == 4 + 4   # the failed run is run again, the rest once
    assert sorted(path.name for path in out.iterdir()) == ["results.json", "table1.md"]
    # The same study as one without an interruption.
    whole = experiments(tmp_path, "--rtcl", fake_rtcl, *QUICK, "-o", tmp_path / "whole")
    assert whole.returncode == 0, whole.stderr
    assert run_names(out) == run_names(tmp_path / "whole")
    assert len(run_names(out)) == 7


def test_resume_takes_the_studys_own_options(tmp_path, fake_rtcl):
    refused = experiments(tmp_path, "--resume", tmp_path, "--size", "64x64")
    assert refused.returncode == 2
    assert "--resume DIR goes on with the options the study started with: it takes no " \
           "--size" in refused.stderr
    nothing = experiments(tmp_path, "--resume", tmp_path)
    assert nothing.returncode == 1
    assert "no interrupted study here (study-progress.json is missing" in nothing.stderr


@pytest.mark.parametrize("signum", [signal.SIGTERM, signal.SIGINT])
def test_an_interrupted_study_ends_cleanly_and_resumes(tmp_path, fake_rtcl, signum):
    (fake_rtcl.parent / "hang-at").write_text("3")
    out = tmp_path / "out"
    process = subprocess.Popen([sys.executable, str(TOOLS / "experiments.py"), "--rtcl",
                                str(fake_rtcl), *QUICK, "-o", str(out)], cwd=tmp_path,
                               env=tool_env(tmp_path), stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True, start_new_session=True)
    try:
        deadline = time.monotonic() + 60
        while not (fake_rtcl.parent / "hanging").exists():
            assert time.monotonic() < deadline and process.poll() is None
            time.sleep(0.05)
        # Ctrl-C reaches the whole foreground process group, SIGTERM the tool alone.
        if signum == signal.SIGINT:
            os.killpg(process.pid, signum)
        else:
            process.send_signal(signum)
        _, stderr = process.communicate(timeout=60)
    finally:
        if process.poll() is None:
            os.killpg(process.pid, signal.SIGKILL)
    assert process.returncode == 128 + signum
    assert "Traceback" not in stderr
    assert_rtcl_ended(fake_rtcl)
    name = signal.Signals(signum).name
    assert stderr.splitlines()[-1] == \
        f"experiments.py: interrupted ({name}); 2 run(s) kept in {out}/study-progress.json: " \
        f"`tools/experiments.py --resume {out}` goes on with the study"
    assert not list((tmp_path / "tmp").iterdir()), "the temporary folder was left behind"

    (fake_rtcl.parent / "hang-at").unlink()
    resumed = experiments(tmp_path, "--resume", out, "--rtcl", fake_rtcl)
    assert resumed.returncode == 0, resumed.stderr
    assert len(run_names(out)) == 7 and not (out / "study-progress.json").exists()


def test_sigterm_ends_bench_without_a_traceback(tmp_path, fake_rtcl):
    (fake_rtcl.parent / "hang-at").write_text("1")
    process = subprocess.Popen([sys.executable, str(TOOLS / "bench.py"), "--rtcl",
                                str(fake_rtcl), "--quick", "-o", str(tmp_path / "b")],
                               cwd=tmp_path, env=tool_env(tmp_path), stderr=subprocess.PIPE,
                               stdout=subprocess.DEVNULL, text=True)
    deadline = time.monotonic() + 60
    while not (fake_rtcl.parent / "hanging").exists():
        assert time.monotonic() < deadline and process.poll() is None
        time.sleep(0.05)
    process.terminate()
    _, stderr = process.communicate(timeout=60)
    assert process.returncode == 143 and "Traceback" not in stderr
    assert_rtcl_ended(fake_rtcl)
    assert stderr.splitlines()[-1] == "bench.py: interrupted (SIGTERM); nothing written"
    assert not list((tmp_path / "tmp").iterdir()) and not (tmp_path / "b").exists()


# ---- the Python of a checkout -------------------------------------------------------------

@pytest.fixture(scope="module")
def bare_python(tmp_path_factory):
    """A Python without numpy or matplotlib: a virtual environment of this one,
    without its site packages."""
    folder = tmp_path_factory.mktemp("bare") / "env"
    made = subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(folder)],
                          capture_output=True, text=True, timeout=120)
    if made.returncode != 0:
        pytest.skip(f"python3 -m venv failed (python3-venv installed?): {made.stderr}")
    python = folder / "bin" / "python"
    lacks = subprocess.run([str(python), "-c", "import numpy"], capture_output=True)
    assert lacks.returncode != 0
    return python


def test_a_tool_runs_under_a_python_that_has_its_modules(tmp_path, bare_python):
    counts = tmp_path / "run.npy"
    np.save(counts, np.arange(16, dtype="<u8").reshape(4, 4))
    result = subprocess.run([str(bare_python), str(TOOLS / "flops_hist.py"), counts, "-o",
                             tmp_path / "fig.png"], capture_output=True, text=True,
                            cwd=tmp_path, timeout=120,
                            env=dict(os.environ, RTCL_PYTHON=sys.executable))
    assert result.returncode == 0, result.stderr
    assert (tmp_path / "fig.png").read_bytes().startswith(b"\x89PNG")


@pytest.mark.parametrize("tool", sorted(path.name for path in TOOLS.glob("*.py")))
def test_every_tool_starts_from_a_python_without_numpy(tmp_path, bare_python, tool):
    args = ["balls", "--help"] if tool == "genbench.py" else ["--help"]
    result = subprocess.run([str(bare_python), str(TOOLS / tool), *args],
                            capture_output=True, text=True, cwd=tmp_path, timeout=120,
                            env=dict(os.environ, RTCL_PYTHON=sys.executable))
    assert result.returncode == 0, result.stderr
    assert result.stdout.startswith(f"usage: {tool} ")


def test_without_a_python_that_has_them_one_line_says_what_to_install(tmp_path, bare_python):
    result = subprocess.run([str(bare_python), str(TOOLS / "maps.py"), "--work", "x.npy"],
                            capture_output=True, text=True, cwd=tmp_path, timeout=120,
                            env=dict(os.environ, RTCL_PYTHON=str(bare_python)))
    assert result.returncode == 1
    assert result.stderr == (
        f"maps.py: needs numpy and matplotlib, which {bare_python} lacks: `make deps` "
        "(Debian's python3-numpy python3-matplotlib for /usr/bin/python3, which "
        f"tools/NAME.py then uses), or `{bare_python} -m pip install numpy matplotlib`\n")
    assert list(tmp_path.iterdir()) == []


# ---- the bounds on a CPU, --replot --fma-units ------------------------------------------

def study_runs(device):
    def stats(kernel, kernel_ms):
        return {"device": device, "kernel": kernel, "kernel_ms": kernel_ms,
                "workgroup": "8x8", "groups": "4x4", "global_size": [32, 32], "width": 32,
                "height": 32, "max_depth": 5, "scene": "fake", "gflop": 1.0,
                "parallel_efficiency": 0.5, "simd_efficiency_model": 0.5,
                "simd_efficiency_measured": "not measurable on this device",
                "compute_units": 2, "max_clock_mhz": 2000}
    return [runner.Run("serial", "serial", None, None, "./rtcl -k serial", stats("serial", 1000)),
            runner.Run("paper", "cyclic", "8x8", "25x25", "./rtcl -k cyclic",
                       stats("cyclic", 100.0))]


def bounds_rows(markdown):
    rows = {}
    for line in markdown.split("## Bounds")[1].splitlines():
        if line.startswith("|") and not line.startswith("|---"):
            cells = [cell.strip() for cell in line.strip("|").split("|")]
            rows[cells[0]] = cells
    return rows


def test_the_bounds_on_a_cpu_say_simd_efficiency_does_not_apply():
    meta = {"date": "2026-11-28 00:00 UTC", "repeat": 5,
            "peak": {"gflops": 100.0, "formula": "a CPU's"}}
    cpu = table1.render_table1(study_runs(POCL), meta)
    section = cpu.split("## Bounds")[1]
    assert "On this CPU the SIMD columns do not apply" in section
    row = bounds_rows(cpu)["cyclic"]
    # time 100 ms, 1 GFLOP at 100 GFLOP/s = 10 ms: all of the factor 10 is elsewhere
    assert row[2:] == ["does not apply (CPU)", "–", "10.000", "–", "10.0×", "10.00%"]
    gpu = table1.render_table1(study_runs("Fake GPU (NVIDIA CUDA)"), meta)
    assert "does not apply" not in gpu
    assert bounds_rows(gpu)["cyclic"][2:5] == ["50.00% (modelled)", "50.00", "10.000"]


def replot(folder, *options):
    return subprocess.run([sys.executable, str(TOOLS / "experiments.py"), "--replot",
                           str(folder), "--no-plots", *options], capture_output=True,
                          text=True, timeout=120)


def stored_study(tmp_path, device, peak):
    folder = tmp_path / "study"
    folder.mkdir()
    runs = [dict(run.to_json()) for run in study_runs(device)]
    (folder / "results.json").write_text(json.dumps(
        {"meta": {"date": "2026-11-28 00:00 UTC", "repeat": 5, "peak": peak},
         "paper": {}, "runs": runs}))
    return folder


def test_replot_computes_a_cpus_peak_again_with_fma_units(tmp_path):
    stored = experiment.study_peak(study_runs(POCL)[0].stats, None, 1,
                                   {"flags": "fpu avx2 fma sse", "cpu cores": "2",
                                    "siblings": "2", "model name": "AMD EPYC 7B13"})
    assert stored["cpuinfo"] == {"flags": "avx2 fma", "cpu cores": "2", "siblings": "2",
                                 "model name": "AMD EPYC 7B13"}
    # 2 cores x 8 lanes x 1 FMA unit x 2 x 2 GHz = 64 GFLOP/s
    assert stored["gflops"] == pytest.approx(64.0)
    folder = stored_study(tmp_path, POCL, stored)
    result = replot(folder, "--fma-units", "2")
    assert result.returncode == 0, result.stderr
    table = (folder / "table1.md").read_text()
    assert "x 2 FMA unit(s) per core (--fma-units)" in table and "128.0 GFLOP/s" in table
    # 1 GFLOP at 128 GFLOP/s
    assert bounds_rows(table)["cyclic"][4] == "7.812"


@pytest.mark.parametrize("device, peak, message", [
    ("Fake GPU (NVIDIA CUDA)", {"gflops": 100.0, "formula": "table"},
     "ran on Fake GPU (NVIDIA CUDA), not a CPU: its peak takes no FMA units"),
    ("pthread-zen4-Some Other CPU (Portable Computing Language)",
     {"gflops": None, "formula": "unknown"},
     "results.json does not keep the flags of its CPU"),
])
def test_replot_refuses_fma_units_it_cannot_use(tmp_path, device, peak, message):
    folder = stored_study(tmp_path, device, peak)
    result = replot(folder, "--fma-units", "2")
    assert result.returncode == 1
    assert message in result.stderr and len(result.stderr.splitlines()) == 1
    assert not (folder / "table1.md").exists()


def test_replot_refuses_options_it_does_not_read(tmp_path):
    result = replot(tmp_path, "--size", "64x64")
    assert result.returncode == 2
    assert "it takes no --size" in result.stderr


# ---- the README --------------------------------------------------------------------------

def readme_section(title):
    text = (ROOT / "README.md").read_text()
    return text.split(f"\n## {title}\n")[1].split("\n## ")[0]


def test_the_readme_study_section_gives_quick_full_resume_and_times():
    study = readme_section("The study")
    for command in ("tools/experiments.py --quick", "tools/experiments.py --resume",
                    "rtcl-experiments", "make deps"):
        assert command in study, command
    assert re.search(r"--quick[^\n]*\n(?:[^\n]*\n)*?[^\n]*\d+ (?:s|min)", study)
    assert "estimate" in study


def test_the_readme_says_accel_none_for_the_papers_brute_force():
    for line in (ROOT / "README.md").read_text().splitlines():
        if "the paper's" in line and "geometry" in line and line.lstrip().startswith("./rtcl"):
            assert "--accel none" in line, line
