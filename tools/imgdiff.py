#!/usr/bin/env python3
"""rtcl-imgdiff run from the source tree: rtcl_tools/commands/imgdiff.py says what it does."""
import sys

from rtcl_tools.checkout import python_with

python_with()  # needs no module beyond Python's own
from rtcl_tools.commands.imgdiff import main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main())
