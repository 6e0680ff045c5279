#!/usr/bin/env python3
"""rtcl-path-study run from the source tree: rtcl_tools/commands/path_study.py says what it does."""
import sys

from rtcl_tools.checkout import python_with

python_with(required=("numpy",), wanted=("matplotlib",))
from rtcl_tools.commands.path_study import main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main())
