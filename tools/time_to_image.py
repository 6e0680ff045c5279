#!/usr/bin/env python3
"""rtcl-time-to-image run from the source tree: rtcl_tools/commands/time_to_image.py says what it does."""
import sys

from rtcl_tools.commands.time_to_image import main

if __name__ == "__main__":
    sys.exit(main())
