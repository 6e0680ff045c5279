#!/usr/bin/env python3
"""rtcl-flops-hist run from the source tree: rtcl_tools/commands/flops_hist.py says what it does."""
import sys

from rtcl_tools.commands.flops_hist import main

if __name__ == "__main__":
    sys.exit(main())
