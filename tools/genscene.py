#!/usr/bin/env python3
"""rtcl-genscene run from the source tree: rtcl_tools/commands/genscene.py says what it does."""
import sys

from rtcl_tools.commands.genscene import main

if __name__ == "__main__":
    sys.exit(main())
