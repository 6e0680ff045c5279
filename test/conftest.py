"""pytest settings for rtcl's tests.

Tests marked `slow` (long renders, the tools' end-to-end runs against rtcl,
redrawing the committed figures, interrupt sweeps) are left out of `make test`
and run by `make test-long`; `make check` runs both.  CI runs both.
"""

import os
import time


def pytest_configure(config):
    config.addinivalue_line("markers", "slow: a long test, run by make test-long (not make test)")


def pytest_terminal_summary(terminalreporter):
    """How long the whole `make test` took, Criterion's part included: the
    Makefile exports RTCL_TEST_START (seconds since the epoch) before it."""
    start = os.environ.get("RTCL_TEST_START")
    if not start:
        return
    try:
        seconds = time.time() - float(start)
    except ValueError:
        return
    minutes, rest = divmod(round(seconds), 60)
    what = os.environ.get("RTCL_TEST_WHAT", "the tests")
    terminalreporter.write_line(f"{what} took {minutes} min {rest:02d} s in all")
