#!/usr/bin/env python3
"""rtcl-schedule-replay run from the source tree: rtcl_tools/commands/schedule_replay.py says what it does."""
import sys

from rtcl_tools.checkout import python_with

python_with(required=("numpy", "PIL"))
from rtcl_tools.commands.schedule_replay import main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main())
