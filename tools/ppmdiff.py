#!/usr/bin/env python3
"""rtcl-ppmdiff run from the source tree: rtcl_tools/commands/imgdiff.py says what it does."""
import sys

from rtcl_tools.commands.imgdiff import main

if __name__ == "__main__":
    sys.exit(main())
