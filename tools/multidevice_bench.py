#!/usr/bin/env python3
"""rtcl-multidevice-bench run from the source tree: rtcl_tools/commands/multidevice_bench.py says what it does."""
import sys

from rtcl_tools.commands.multidevice_bench import main

if __name__ == "__main__":
    sys.exit(main())
