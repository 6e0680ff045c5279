#!/usr/bin/env python3
"""rtcl-maps run from the source tree: rtcl_tools/commands/maps.py says what it does."""
import sys

from rtcl_tools.commands.maps import main

if __name__ == "__main__":
    sys.exit(main())
