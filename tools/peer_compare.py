#!/usr/bin/env python3
"""rtcl-peer-compare run from the source tree: rtcl_tools/commands/peer_compare.py says what it does."""
import sys

from rtcl_tools.checkout import python_with

python_with(required=("numpy",))
from rtcl_tools.commands.peer_compare import main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main())
