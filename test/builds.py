"""What kind of build the tests run (make test SAN=1 runs them on build-san/)."""
import subprocess


def built_with_asan(program):
    """Whether program links AddressSanitizer, which reserves terabytes of
    address space at start: a test that limits the address space (RLIMIT_AS)
    cannot run it."""
    result = subprocess.run(["ldd", str(program)], capture_output=True, text=True)
    return "libasan" in result.stdout
