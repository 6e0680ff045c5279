#!/usr/bin/env python3
"""rtcl-bench-spp run from the source tree: rtcl_tools/commands/bench_spp.py says what it does."""
import sys

from rtcl_tools.checkout import python_with

python_with()  # needs no module beyond Python's own
from rtcl_tools.commands.bench_spp import main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main())
