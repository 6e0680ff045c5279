"""host/'s layering rule (docs/STYLE.md, "Layers"), checked by
tools/build/layers.py: the checkout keeps it, and the checker catches an
include or a call that breaks it."""
import os
import shutil
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
LAYERS = os.path.join(ROOT, "tools", "build", "layers.py")
BUILD = os.path.join(ROOT, "build")


def layers(*args, root=ROOT):
    return subprocess.run([sys.executable, LAYERS, "--root", root, *args],
                          capture_output=True, text=True, timeout=120)


def test_the_checkout_keeps_the_layering_rule():
    args = ["--objects", BUILD] if os.path.isdir(os.path.join(BUILD, "render")) else []
    result = layers(*args)
    assert result.returncode == 0, result.stdout + result.stderr
    assert "layers: 0 violations" in result.stdout


def copy_tree(tmp_path):
    shutil.copytree(os.path.join(ROOT, "host"), tmp_path / "host")
    (tmp_path / "docs").mkdir()
    shutil.copy(os.path.join(ROOT, "docs", "STYLE.md"), tmp_path / "docs")
    return tmp_path


def test_an_include_pointing_up_is_caught(tmp_path):
    root = copy_tree(tmp_path)
    launch = root / "host" / "render" / "launch.c"
    launch.write_text('#include "run/mode.h"\n' + launch.read_text())
    result = layers(root=str(root))
    assert result.returncode == 1
    assert "host/render/launch.c: includes run/mode.h: render/ may use " \
           "base, device, layout, scene" in result.stdout
    assert "layers: 1 violation " in result.stdout


def test_a_bare_include_and_a_file_outside_the_folders_are_caught(tmp_path):
    root = copy_tree(tmp_path)
    files = root / "host" / "base" / "files.c"
    files.write_text('#include "quote.h"\n' + files.read_text())
    (root / "host" / "stray.c").write_text("int stray;\n")
    result = layers(root=str(root))
    assert result.returncode == 1
    assert 'host/base/files.c: includes "quote.h": write it with its folder, ' \
           '"base/quote.h"' in result.stdout
    assert "host/stray.c: not in a folder of the Layers table" in result.stdout


def test_a_call_up_without_an_include_is_caught_in_the_objects(tmp_path):
    if shutil.which("cc") is None or shutil.which("nm") is None:
        import pytest
        pytest.skip("no C compiler or nm")
    root = copy_tree(tmp_path)
    build = tmp_path / "objects"
    for folder, source in (("base", "int base_helper(void) { return mode_up(); }\n"
                                    "int mode_up(void);\n"),
                           ("run", "int mode_up(void) { return 1; }\n")):
        (build / folder).mkdir(parents=True)
        (tmp_path / f"{folder}.c").write_text(
            "int mode_up(void);\n" + source.replace("int mode_up(void);\n", ""))
        subprocess.run(["cc", "-c", "-o", str(build / folder / f"{folder}_part.o"),
                        str(tmp_path / f"{folder}.c")], check=True)
    result = layers("--objects", str(build), root=str(root))
    assert result.returncode == 1
    assert "base/base_part.o: calls mode_up of run/run_part: base/ may use no other folder" \
        in result.stdout
