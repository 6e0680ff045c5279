"""`pip install ./tools` (tools/pyproject.toml) into a fresh venv: the package and
one console script per tools/*.py, named as installed (rtcl-bench, ...), each
answering --help under its own name, and finding the rtcl installed beside it.

The venv takes numpy, matplotlib, pip and setuptools from the system
(--system-site-packages --without-pip: Debian's python3-numpy, python3-matplotlib,
python3-pip, python3-setuptools; a few seconds, not ensurepip's ten), and pip
builds offline (--no-deps --no-build-isolation --no-index).  The tools folder is
copied first: the build writes nothing into the source tree.
"""
import os
import pathlib
import shutil
import subprocess
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parent.parent
RTCL = os.environ.get("RTCL", str(ROOT / "rtcl"))
COMMANDS = sorted("rtcl-" + path.stem.replace("_", "-")
                  for path in (ROOT / "tools").glob("*.py"))


@pytest.fixture(scope="module")
def venv(tmp_path_factory):
    folder = tmp_path_factory.mktemp("venv")
    source = folder / "tools"
    shutil.copytree(ROOT / "tools", source,
                    ignore=shutil.ignore_patterns("__pycache__", "*.egg-info", "lib",
                                                  "bdist.*"))
    made = subprocess.run([sys.executable, "-m", "venv", "--system-site-packages", "--without-pip",
                           str(folder / "env")], capture_output=True, text=True, timeout=120)
    if made.returncode != 0:
        pytest.skip(f"python3 -m venv failed (python3-venv installed?): {made.stderr}")
    pip = subprocess.run([str(folder / "env" / "bin" / "python"), "-m", "pip", "install",
                          "-q", "--no-deps", "--no-build-isolation", "--no-index",
                          str(source)], capture_output=True, text=True, timeout=300)
    assert pip.returncode == 0, pip.stdout + pip.stderr
    return folder / "env"


def test_pyproject_names_one_console_script_per_tool():
    text = (ROOT / "tools" / "pyproject.toml").read_text()
    scripts = text.split("[project.scripts]")[1].split("\n[")[0]
    entries = dict(line.split(" = ") for line in scripts.strip().splitlines())
    assert sorted(entries) == COMMANDS
    for command, target in entries.items():
        module = target.strip('"').split(":")[0]
        wrapper = ROOT / "tools" / (command[len("rtcl-"):].replace("-", "_") + ".py")
        assert f"from {module} import main" in wrapper.read_text(), wrapper


def test_installed_package_imports_from_the_venv(venv, tmp_path):
    result = subprocess.run([str(venv / "bin" / "python"), "-c",
                             "import rtcl_tools.commands.bench as m; print(m.__file__)"],
                            cwd=tmp_path, capture_output=True, text=True, timeout=60)
    assert result.returncode == 0, result.stderr
    assert result.stdout.startswith(str(venv)), result.stdout


@pytest.mark.parametrize("command", COMMANDS)
def test_console_scripts_answer_help_with_their_installed_name(venv, tmp_path, command):
    result = subprocess.run([str(venv / "bin" / command), "--help"], cwd=tmp_path,
                            capture_output=True, text=True, timeout=60)
    assert result.returncode == 0, result.stderr
    assert result.stdout.startswith(f"usage: {command} ")
    assert ".py" not in result.stdout.splitlines()[0]


def test_console_script_runs_the_rtcl_beside_it(venv, tmp_path):
    if not os.access(RTCL, os.X_OK):
        pytest.skip(f"{RTCL} is not built")
    (venv / "bin" / "rtcl").symlink_to(os.path.abspath(RTCL))
    try:
        result = subprocess.run([str(venv / "bin" / "rtcl-bench-spp"), "--size", "8x8",
                                 "-r", "1", "--max-spp", "1", "-o", "spp"],
                                cwd=tmp_path, capture_output=True, text=True, timeout=300,
                                env={**os.environ, "PATH": "/usr/bin:/bin"})
    finally:
        (venv / "bin" / "rtcl").unlink()
    assert result.returncode == 0, result.stderr
    assert (tmp_path / "spp" / "spp.md").read_text().startswith("# Kernel time")
    assert "`rtcl-bench-spp --size 8x8 -r 1" in (tmp_path / "spp" / "spp.md").read_text()
