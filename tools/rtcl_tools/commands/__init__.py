"""The tools' commands, one module each with main(argv=None) -> exit status.

Installed as rtcl-NAME (tools/pyproject.toml's [project.scripts], or the
wrappers of `make install`), run from a checkout as tools/NAME.py, a thin
wrapper; NAME's _ becomes - in the command's name.
"""
