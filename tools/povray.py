#!/usr/bin/env python3
"""rtcl-povray run from the source tree: rtcl_tools/commands/povray.py says what it does."""
import sys

from rtcl_tools.commands.povray import main

if __name__ == "__main__":
    sys.exit(main())
