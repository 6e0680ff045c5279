#!/usr/bin/env python3
"""rtcl-schedule-replay run from the source tree: rtcl_tools/commands/schedule_replay.py says what it does."""
import sys

from rtcl_tools.commands.schedule_replay import main

if __name__ == "__main__":
    sys.exit(main())
