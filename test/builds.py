"""What kind of build the tests run (make test SAN=1 runs them on build-san/)."""
import subprocess


def built_with_asan(program):
    """Whether program links AddressSanitizer, which reserves terabytes of
    address space at start: a test that limits the address space (RLIMIT_AS)
    cannot run it."""
    result = subprocess.run(["ldd", str(program)], capture_output=True, text=True)
    return "libasan" in result.stdout


def ompi_session_base():
    """A folder for Open MPI's session files of this test process alone
    (OMPI_MCA_orte_tmpdir_base), removed at exit: two mpiruns of the parallel
    test workers racing to make the shared /tmp/ompi.HOST.UID failed one with
    "File exists" (orte_session_dir, seen in CI)."""
    import atexit
    import shutil
    import tempfile

    folder = tempfile.mkdtemp(prefix="rtcl-ompi-")
    atexit.register(shutil.rmtree, folder, True)
    return folder
