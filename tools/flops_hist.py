#!/usr/bin/env python3
"""rtcl-flops-hist run from the source tree: rtcl_tools/commands/flops_hist.py says what it does."""
import sys

from rtcl_tools.checkout import python_with

python_with(required=("numpy", "matplotlib"))
from rtcl_tools.commands.flops_hist import main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main())
