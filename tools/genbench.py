#!/usr/bin/env python3
"""rtcl-genbench run from the source tree: rtcl_tools/commands/genbench.py says what it does."""
import sys

from rtcl_tools.checkout import python_with

python_with(required=("numpy",))
from rtcl_tools.commands.genbench import main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main())
