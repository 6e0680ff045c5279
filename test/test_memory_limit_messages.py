"""Under an address-space limit (`ulimit -v`) too small for the OpenCL
runtime, rtcl says so on stderr and writes nothing (docs/GUIDE.md, "Exit
status and messages"). PoCL's compiler crashed there (SIGSEGV when asked for
the built binary, std::bad_alloc's abort in the build) and rtcl ended with
nothing of its own on stderr; under a smaller limit PoCL's platform does not
start and rtcl said only that no driver was installed."""
import os
import pathlib
import resource
import signal
import subprocess

import pytest

import builds

ROOT = pathlib.Path(__file__).resolve().parent.parent
RTCL = os.environ.get("RTCL", str(ROOT / "rtcl"))
ASAN = builds.built_with_asan(RTCL)  # AddressSanitizer reserves terabytes of address space
pytestmark = pytest.mark.skipif(ASAN, reason="AddressSanitizer needs its address space")


def limited_run(tmp_path, mib):
    """rtcl under mib MiB of address space with empty caches (rtcl's and
    PoCL's: the compiler runs), rendering the Cornell box into tmp_path/out."""
    def limit():
        resource.setrlimit(resource.RLIMIT_AS, (mib << 20, mib << 20))
    env = {**os.environ, "XDG_CACHE_HOME": str(tmp_path / "cache"),
           "POCL_CACHE_DIR": str(tmp_path / "pocl")}
    (tmp_path / "out").mkdir()
    return subprocess.run([RTCL, "-s", "scenes/cornell.json", "--size", "16x16", "--spp", "1",
                           "-q", "-o", str(tmp_path / "out" / "x.png")], cwd=ROOT, env=env,
                          capture_output=True, text=True, preexec_fn=limit, timeout=120)


def own_lines(stderr):
    return [line for line in stderr.splitlines() if line.startswith("rtcl:")]


def test_a_compiler_crash_under_a_memory_limit_is_named(tmp_path):
    result = limited_run(tmp_path, 450)
    # Killed by the signal the compiler raised, after rtcl's one line.
    assert result.returncode in (-signal.SIGSEGV, -signal.SIGABRT, -signal.SIGBUS), \
        (result.returncode, result.stderr)
    lines = own_lines(result.stderr)
    assert len(lines) == 1, result.stderr
    assert lines[0].startswith("rtcl: crashed (SIG"), lines
    assert "while building the kernels for " in lines[0]
    assert lines[0].endswith("; no output written. rtcl runs with an address-space limit of "
                             "450 MiB (`ulimit -v`), which the OpenCL runtime may have run "
                             "out of: raise or lift it"), lines
    assert os.listdir(tmp_path / "out") == []


def test_a_runtime_that_cannot_start_under_a_memory_limit_is_named(tmp_path):
    result = limited_run(tmp_path, 150)
    assert result.returncode == 1, result.stderr
    assert own_lines(result.stderr) == [
        "rtcl: no OpenCL platform found: rtcl runs with an address-space limit of 150 MiB "
        "(`ulimit -v`), which may be too little for the OpenCL runtime to start: raise or "
        "lift it (else install an OpenCL driver, e.g. `apt-get install pocl-opencl-icd`, "
        "and check /etc/OpenCL/vendors)"]
    assert os.listdir(tmp_path / "out") == []
