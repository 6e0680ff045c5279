"""make install and make uninstall, and the man page kept in step with --help.

Installs the built ./rtcl (or $RTCL) with `make install DESTDIR=<tmp> PREFIX=/usr`
and checks the tree file by file, that the installed rtcl renders on the first
OpenCL device (PoCL in CI), that the man page formats without warnings, that
the tool commands run from any folder, and that `make uninstall` removes exactly
what install wrote. Nothing is written outside the temporary DESTDIR.
"""

import json
import os
import pathlib
import re
import shutil
import subprocess
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parent.parent
RTCL = os.environ.get("RTCL", str(ROOT / "rtcl"))
MAN_PAGE = ROOT / "docs" / "rtcl.1"
PREFIX = "usr"
# The commands the README and the man page name; one per tools/*.py.
TOOL_COMMANDS = {"rtcl-bench", "rtcl-bench-spp", "rtcl-experiments", "rtcl-flops-hist",
                 "rtcl-genbench", "rtcl-genscene", "rtcl-imgdiff", "rtcl-maps", "rtcl-multidevice-bench",
                 "rtcl-path-study", "rtcl-peer-compare", "rtcl-povray", "rtcl-ppmdiff",
                 "rtcl-schedule-replay",
                 "rtcl-time-to-image"}
MAN_SECTIONS = ["NAME", "SYNOPSIS", "DESCRIPTION", "OPTIONS", "ENVIRONMENT", "FILES",
                "EXIT STATUS", "EXAMPLES", "SEE ALSO"]
LONG_OPTION = re.compile(r"(?<![\w-])--[a-z][a-z-]*")
SHORT_OPTION = re.compile(r"(?<![\w-])-[a-zA-Z](?![\w-])")


def make_environment():
    """The environment for a nested make: the outer make's variables (SAN=1
    chooses the binary and its objects) but not its job server, whose file
    descriptors subprocess does not pass on."""
    env = {key: value for key, value in os.environ.items()
           if key not in ("MAKEFLAGS", "MFLAGS", "MAKELEVEL")}
    flags = os.environ.get("MAKEFLAGS", "")
    if " -- " in flags:
        env["MAKEFLAGS"] = " -- " + flags.split(" -- ", 1)[1]
    return env


def make(target, destdir):
    return subprocess.run(["make", "--no-print-directory", target, f"DESTDIR={destdir}",
                           f"PREFIX=/{PREFIX}", f"BIN={RTCL}"],
                          cwd=ROOT, capture_output=True, text=True, env=make_environment(),
                          timeout=120)


def install(destdir):
    before = os.stat(RTCL).st_mtime_ns
    result = make("install", destdir)
    assert result.returncode == 0, result.stdout + result.stderr
    assert os.stat(RTCL).st_mtime_ns == before, \
        "make install rebuilt rtcl (build it first with make):\n" + result.stdout
    return result


def files_under(folder):
    return {str(path.relative_to(folder)) for path in pathlib.Path(folder).rglob("*")
            if not path.is_dir()}


def expected_files():
    tools = sorted((ROOT / "tools").glob("*.py"))
    share = f"{PREFIX}/share/rtcl"
    return ({f"{PREFIX}/bin/rtcl", f"{PREFIX}/share/man/man1/rtcl.1",
             f"{share}/scenes/README.md"}
            | {f"{PREFIX}/bin/rtcl-" + path.stem.replace("_", "-") for path in tools}
            | {f"{share}/scenes/{path.name}" for path in (ROOT / "scenes").glob("*.json")}
            | {f"{share}/scenes/models/{path.relative_to(ROOT / 'scenes' / 'models')}"
               for path in (ROOT / "scenes" / "models").rglob("*") if path.is_file()}
            | {f"{share}/tools/rtcl_tools/{path.name}"
               for path in (ROOT / "tools" / "rtcl_tools").glob("*.py")}
            | {f"{share}/tools/rtcl_tools/commands/{path.name}"
               for path in (ROOT / "tools" / "rtcl_tools" / "commands").glob("*.py")}
            | {f"{share}/tools/rtcl_tools/{path.name}"
               for pattern in ("*.cpp", "*.cl")
               for path in (ROOT / "tools" / "rtcl_tools").glob(pattern)}
            | {f"{PREFIX}/lib/rtcl/rtcl-meshread", f"{PREFIX}/lib/rtcl/rtcl-rays"}
            | ({f"{PREFIX}/lib/rtcl/rtcl-oiio.so"} if has_oiio() else set()))


def has_oiio():
    """Whether rtcl was built with OpenImageIO (as a module; OIIO=0 refuses .tif)."""
    probe = subprocess.run([RTCL, "--size", "4x4", "-o", "/nonexistent-dir/x.tif"],
                           capture_output=True, text=True, timeout=300)
    return "no OpenImageIO" not in probe.stderr


@pytest.fixture(scope="module")
def installed(tmp_path_factory):
    destdir = tmp_path_factory.mktemp("destdir")
    install(destdir)
    return destdir


def is_ppm_8x8(path):
    """A binary PPM of 8x8 pixels; rtcl's header has comment lines before the size."""
    data = path.read_bytes()
    return data.startswith(b"P6\n") and b"\n8 8\n255\n" in data


def run_installed(destdir, args, cwd, env=None):
    path = f"{destdir}/{PREFIX}/bin{os.pathsep}{os.environ['PATH']}"
    return subprocess.run(args, cwd=cwd, capture_output=True, text=True, timeout=300,
                          env={**os.environ, "PATH": path, **(env or {})})


def test_install_writes_exactly_the_program_man_page_scenes_and_tools(installed):
    assert files_under(installed) == expected_files()
    bin_dir = installed / PREFIX / "bin"
    assert TOOL_COMMANDS <= {path.name for path in bin_dir.iterdir()}
    for path in bin_dir.iterdir():
        assert os.access(path, os.X_OK), path
    assert (installed / PREFIX / "share/rtcl/scenes/paper60.json").read_bytes() == \
        (ROOT / "scenes/paper60.json").read_bytes()


def test_installed_rtcl_runs_and_renders(installed, tmp_path):
    version = run_installed(installed, ["rtcl", "--version"], tmp_path)
    assert version.returncode == 0, version.stderr
    assert version.stdout == subprocess.run([RTCL, "--version"], capture_output=True,
                                            text=True).stdout
    render = run_installed(installed, ["rtcl", "--size", "8x8", "-o", "x.ppm"], tmp_path)
    assert render.returncode == 0, render.stderr
    assert is_ppm_8x8(tmp_path / "x.ppm")
    scene = installed / PREFIX / "share/rtcl/scenes/two_balls.json"
    render = run_installed(installed, ["rtcl", "-q", "-s", str(scene), "--size", "8x8", "-o",
                                       "balls.ppm"], tmp_path)
    assert render.returncode == 0, render.stderr
    assert (tmp_path / "balls.ppm").is_file()


def test_installed_rtcl_reads_meshes_through_the_installed_helper(tmp_path):
    """The mesh import helper is looked for in PREFIX/lib/rtcl first: an
    installed helper that fails is the one whose failure rtcl reports, and the
    installed one reads the shipped mesh scene."""
    destdir = tmp_path / "destdir"
    install(destdir)
    scene = destdir / PREFIX / "share/rtcl/scenes/glass_mesh.json"
    render = run_installed(destdir, ["rtcl", "-q", "-s", str(scene), "--size", "8x8", "-o",
                                     "mesh.ppm"], tmp_path)
    assert render.returncode == 0, render.stderr
    assert is_ppm_8x8(tmp_path / "mesh.ppm")
    helper = destdir / PREFIX / "lib/rtcl/rtcl-meshread"
    helper.unlink()
    helper.write_text("#!/bin/sh\nexit 3\n")
    helper.chmod(0o755)
    render = run_installed(destdir, ["rtcl", "-q", "-s", str(scene), "--size", "8x8", "-o",
                                     "broken.ppm"], tmp_path)
    assert render.returncode == 1
    assert "the mesh importer failed (exit status 3)" in render.stderr
    assert not (tmp_path / "broken.ppm").exists()


def test_installed_peer_compare_finds_the_installed_rtcl_rays(installed):
    """rtcl-peer-compare --rays runs rtcl-rays, installed in PREFIX/lib/rtcl
    beside the helper, and builds the peer side from its installed sources
    (neither was installed, and the installed tool failed)."""
    tools = installed / PREFIX / "share/rtcl/tools"
    probe = subprocess.run(
        [sys.executable, "-c",
         "import sys; sys.path.insert(0, sys.argv[1]);"
         "from rtcl_tools.commands import peer_compare as p;"
         "print(p.find_rtcl_rays(sys.argv[2]));"
         "[print(s) for s in (p.COUNTER_SOURCE, p.RAYS_SOURCE, p.RAYS_KERNELS)]",
         str(tools), str(installed / PREFIX / "bin/rtcl")],
        capture_output=True, text=True, timeout=60, cwd="/")
    assert probe.returncode == 0, probe.stderr
    found, *sources = probe.stdout.split("\n")[:4]
    assert found == str((installed / PREFIX / "lib/rtcl/rtcl-rays").resolve())
    for source in sources:
        assert source.startswith(str(tools)) and pathlib.Path(source).is_file(), source


def test_one_command_per_tool_script():
    scripts = {"rtcl-" + path.stem.replace("_", "-") for path in (ROOT / "tools").glob("*.py")}
    assert scripts == TOOL_COMMANDS


@pytest.mark.parametrize("command", sorted(TOOL_COMMANDS))
def test_installed_tool_commands_run_from_any_folder(installed, tmp_path, command):
    result = run_installed(installed, [command, "--help"], tmp_path)
    assert result.returncode == 0, result.stderr
    assert result.stdout.startswith(f"usage: {command} "), result.stdout[:200]
    assert not list(installed.rglob("__pycache__")), "a tool left __pycache__ when run"


@pytest.mark.slow  # ten programs; test_tools_package.py checks the installed rtcl is found
def test_installed_experiments_runs_the_installed_rtcl_outside_the_source_tree(installed,
                                                                                tmp_path):
    """Not ./rtcl of the current folder, and not one on PATH: the rtcl beside it,
    run by its absolute path; the results go to a new rtcl-results/ folder."""
    command = installed / PREFIX / "bin" / "rtcl-experiments"
    result = subprocess.run([str(command), "--quick", "--size", "16x16", "--no-sweep",
                             "--no-serial", "--no-reference", "--no-plots", "-r", "1"],
                            cwd=tmp_path, capture_output=True, text=True, timeout=300,
                            env={**os.environ, "PATH": "/usr/bin:/bin"})
    assert result.returncode == 0, result.stderr
    (folder,) = (tmp_path / "rtcl-results").iterdir()
    results = (folder / "results.json").read_text()
    assert f'"{installed / PREFIX / "bin" / "rtcl"} -k naive' in results


def test_installed_genscene_output_renders_with_installed_rtcl(installed, tmp_path):
    scene = run_installed(installed, ["rtcl-genscene", "--balls", "3", "--size", "8x8", "-o",
                                      "three.json"], tmp_path)
    assert scene.returncode == 0, scene.stderr
    render = run_installed(installed, ["rtcl", "-q", "-s", "three.json", "-o", "three.ppm"],
                           tmp_path)
    assert render.returncode == 0, render.stderr
    assert is_ppm_8x8(tmp_path / "three.ppm")


def test_installed_man_page_formats_without_warnings(installed):
    page = installed / PREFIX / "share/man/man1/rtcl.1"
    assert f"/{PREFIX}/share/rtcl/scenes/" in page.read_text()
    if shutil.which("groff") is None:
        pytest.skip("groff is not installed (.ci/install-deps installs groff-base)")
    result = subprocess.run(["groff", "-man", "-Tutf8", "-ww", "-z", str(page)],
                            capture_output=True, text=True)
    assert result.returncode == 0 and result.stderr == "", result.stderr


def test_uninstall_leaves_no_file(tmp_path):
    install(tmp_path)
    result = make("uninstall", tmp_path)
    assert result.returncode == 0, result.stdout + result.stderr
    assert files_under(tmp_path) == set()
    assert not (tmp_path / PREFIX / "share/rtcl").exists()


def test_uninstall_keeps_what_it_did_not_install(tmp_path):
    install(tmp_path)
    mine = {f"{PREFIX}/bin/rtcl-mine", f"{PREFIX}/share/rtcl/scenes/mine.json",
            f"{PREFIX}/share/man/man1/mine.1"}
    for name in mine:
        (tmp_path / name).write_text("mine\n")
    result = make("uninstall", tmp_path)
    assert result.returncode == 0, result.stdout + result.stderr
    assert files_under(tmp_path) == mine


# The man page against --help: options, kernels, environment variables.

def roff_text(source):
    """The man page's words: roff's escaped dash as a dash, no font changes."""
    return re.sub(r"\\f[BIRP]", "", source).replace("\\-", "-")


def man_sections():
    sections, name = {}, None
    for line in MAN_PAGE.read_text().splitlines():
        if line.startswith(".SH "):
            name = line[4:].strip('"')
            sections[name] = []
        elif name:
            sections[name].append(line)
    return sections


def help_text():
    result = subprocess.run([RTCL, "--help"], capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    return result.stdout


def help_defined_options(text):
    """The options --help lists, one per line: "  -k, --kernel NAME" or "      --size WxH"."""
    options = set()
    for line in text.splitlines():
        match = re.match(r"  (?:(-\w), )?(--[a-z][a-z-]*)", line) or \
            re.match(r" {6}(--[a-z][a-z-]*)", line)
        if match:
            options.update(group for group in match.groups() if group)
    return options


def man_defined_options():
    """The options the man page's OPTIONS section defines: the tag line after each .TP."""
    lines = man_sections()["OPTIONS"]
    options = set()
    for tag, line in zip(lines, lines[1:]):
        if tag.startswith(".TP"):
            text = roff_text(line)
            options.update(LONG_OPTION.findall(text) + SHORT_OPTION.findall(text))
    return options


def mentioned_options(text):
    return set(LONG_OPTION.findall(text) + SHORT_OPTION.findall(text))


def test_man_page_has_every_section():
    assert list(man_sections()) == MAN_SECTIONS


def test_man_page_and_help_define_the_same_options():
    in_help = help_defined_options(help_text())
    in_man = man_defined_options()
    assert len(in_help) > 20
    assert in_help - in_man == set(), "in --help but not in docs/rtcl.1's OPTIONS"
    assert in_man - in_help == set(), "in docs/rtcl.1's OPTIONS but not in --help"


def test_every_option_mentioned_is_defined():
    defined = help_defined_options(help_text())
    assert mentioned_options(help_text()) - defined == set()
    assert mentioned_options(roff_text(MAN_PAGE.read_text())) - defined == set()


def test_man_page_lists_every_kernel():
    text = help_text()
    section = text[text.index("--kernel"):text.index("--workgroup")]
    in_help = set(re.findall(r"^ {27}(\w+) ", section, re.MULTILINE))
    options = man_sections()["OPTIONS"]
    kernel_list = options[options.index(".RS"):options.index(".RE")]
    in_man = {line[3:] for tag, line in zip(kernel_list, kernel_list[1:])
              if tag.startswith(".TP") and line.startswith(".B ")}
    assert "reference" in in_help and in_help == in_man


def test_man_page_environment_covers_help_and_output_dates():
    in_help = set(re.findall(r"^  ([A-Z_]+)=", help_text(), re.MULTILINE))
    in_man = {match for line in man_sections()["ENVIRONMENT"]
              for match in re.findall(r"^\.BI ([A-Z_]+)= ", line)}
    assert in_help == {"RTCL_CL_DIR", "RTCL_BUILD_OPTIONS", "RTCL_DUMP_BINARY", "RTCL_CACHE",
                       "POCL_CACHE_DIR", "RTCL_MESH_TIME_LIMIT", "RTCL_MESH_MEMORY_LIMIT",
                       "RTCL_OIDN_LIBRARY", "RTCL_MPI_SUMS", "RTCL_FRAMES_READ"}
    assert in_man == in_help | {"SOURCE_DATE_EPOCH", "XDG_CACHE_HOME", "RTCL_MESHREAD"}


def test_man_page_names_the_version():
    version = subprocess.run([RTCL, "--version"], capture_output=True, text=True).stdout.strip()
    title = next(line for line in MAN_PAGE.read_text().splitlines() if line.startswith(".TH "))
    assert f'"{version}"' in title


# The man page's FILES section against what make install writes.

def man_files_entries(page_text):
    """FILES as (path, body) pairs: the .I path after each .TP and the lines up
    to the next .TP, the body in plain words."""
    lines = page_text.split("\n.SH FILES\n", 1)[1].split("\n.SH ", 1)[0].splitlines()
    entries, path, body = [], None, []
    for line in lines + [".TP"]:
        if line.startswith(".TP"):
            if path is not None:
                entries.append((path, body))
            path, body = None, []
        elif path is None and line.startswith(".I "):
            path = line[3:].strip()
        else:
            body.append(line)
    return entries


def bold_file_names(body):
    """The file and command names an entry sets in bold (.B, .BR, .RB words),
    less options and environment variables."""
    names = set()
    for line in body:
        if not re.match(r"\.(B|BR|RB) ", line):
            continue
        for word in re.split(r"[\s,()]+", roff_text(line.split(" ", 1)[1]).replace('"', " ")):
            word = word.rstrip(".:;")
            if re.fullmatch(r"[A-Za-z][\w.-]*", word) and not re.fullmatch(r"[A-Z_]+", word):
                names.add(word)
    return names


def test_man_page_files_section_lists_exactly_what_install_writes(installed):
    """Every installed file lies under a path FILES names; every folder FILES
    names holds exactly the files and folders its entry names (the tools'
    Python front-ends apart: FILES names their folder); and everything it names
    is installed (rtcl-oiio.so only in a build with OpenImageIO)."""
    page = (installed / PREFIX / "share/man/man1/rtcl.1").read_text()
    entries = man_files_entries(page)
    assert entries, "no FILES entries"
    installed_paths = sorted("/" + name for name in files_under(installed))
    listed = [path for path, _ in entries if not path.startswith("~")]
    for path in listed:
        assert (installed / path.lstrip("/")).exists(), \
            f"FILES names {path}, which make install did not write"
    unlisted = [path for path in installed_paths
                if not any(path == entry or (entry.endswith("/") and path.startswith(entry))
                           for entry in listed)]
    assert unlisted == [], "installed but under no path in the man page's FILES"
    tools_folder = f"/{PREFIX}/share/rtcl/tools/"
    for path, body in entries:
        if not path.endswith("/") or path.startswith("~"):
            continue
        named = bold_file_names(body)
        folder = installed / path.lstrip("/")
        present = {child.name for child in folder.iterdir()}
        missing = named - present - ({"rtcl-oiio.so"} if not has_oiio() else set())
        assert missing == set(), f"FILES names these in {path}, not installed"
        if path == tools_folder:
            continue
        # A subfolder with an entry of its own need not be named in its parent's.
        own_entries = {pathlib.PurePosixPath(entry).name for entry in listed
                       if entry.startswith(path) and entry != path}
        unnamed = present - named - own_entries
        assert unnamed == set(), f"installed in {path} but not named in its FILES entry"


def test_man_page_files_names_every_installed_tool_command(installed):
    commands = {path.name for path in (installed / PREFIX / "bin").iterdir()} - {"rtcl"}
    assert len(commands) >= 10
    text = roff_text((installed / PREFIX / "share/man/man1/rtcl.1").read_text())
    files = text.split("\n.SH FILES\n", 1)[1].split("\n.SH ", 1)[0]
    in_files = set(re.findall(r"\brtcl-[a-z][a-z-]*[a-z]\b(?![./])", files))
    assert in_files - {"rtcl-meshread", "rtcl-rays"} == commands


# The 8-bit encoding: what rtcl does, and what the docs a newcomer reads say.

USER_DOCS = ["README.md", "docs/GUIDE.md", "docs/SCENE.md", "docs/RENDERING.md", "docs/rtcl.1"]


def srgb_byte(c):
    encoded = 12.92 * c if c <= 0.0031308 else 1.055 * c ** (1 / 2.4) - 0.055
    return int(255 * encoded + 0.5)


def first_pixel(tmp_path, *options):
    out = tmp_path / "pixel.ppm"
    result = subprocess.run([RTCL, "-q", "-s", str(ROOT / "scenes/empty.json"), "--size", "2x2",
                             "-o", str(out), *options], capture_output=True, text=True,
                            timeout=300)
    assert result.returncode == 0, result.stderr
    data = out.read_bytes()
    return tuple(data[data.index(b"\n255\n") + 5:][:3])


def doc_paragraphs(name):
    """A document's paragraphs in plain words: blank-line separated in
    Markdown; in the man page, split at .PP, .TP, .SH and .SS, macros dropped."""
    text = (ROOT / name).read_text()
    if not name.endswith(".1"):
        return [part for part in re.split(r"\n\s*\n", text) if part.strip()]
    paragraphs = [[]]
    for line in text.splitlines():
        if re.match(r"\.(PP|TP|SH|SS)\b", line):
            paragraphs.append([])
        elif not line.startswith(".\\\""):
            paragraphs[-1].append(roff_text(re.sub(r"^\.[A-Z]{1,2} ", "", line)))
    return [" ".join(lines) for lines in paragraphs if lines]


def test_default_8bit_encoding_is_the_one_help_and_the_docs_state(tmp_path):
    """empty.json's background (0.3, 0.5, 0.8), rendered to PPM: the default
    bytes are the sRGB encoding, --encoding linear's are round(255 c); --help
    calls sRGB the default; and every paragraph of the user docs that gives an
    8-bit formula names the sRGB default and the linear option, and each of
    them says that sRGB is the default."""
    background = (0.3, 0.5, 0.8)
    srgb = tuple(srgb_byte(c) for c in background)
    linear = tuple(int(255 * c + 0.5) for c in background)
    assert first_pixel(tmp_path) == srgb
    assert first_pixel(tmp_path, "--encoding", "linear") == linear
    help_entry = help_text().split("--encoding", 1)[1].split("\n  -", 1)[0]
    assert re.search(r"sRGB curve\s+\(default\)", help_entry), help_entry
    for name in USER_DOCS:
        paragraphs = doc_paragraphs(name)
        for paragraph in paragraphs:
            if "round(255" in paragraph:
                for word in ("sRGB", "default", "linear"):
                    assert word in paragraph, f"{name}: an 8-bit formula without {word!r}:\n" \
                        + paragraph
        assert any("sRGB" in p and "default" in p for p in paragraphs), \
            f"{name} does not say that 8-bit output is sRGB-encoded by default"


# The README's and the guide's commands and links.

def code_lines(name):
    """The lines of a Markdown file's code: indented four spaces or fenced."""
    lines, fenced = [], False
    for line in (ROOT / name).read_text().splitlines():
        if line.startswith("```"):
            fenced = not fenced
        elif fenced or line.startswith("    "):
            lines.append(line.strip())
    return lines


def rtcl_commands(name):
    """The rtcl command lines in a file's code, comments dropped."""
    commands = []
    for line in code_lines(name):
        match = re.search(r"(?:^|\s)(?:\./)?rtcl(\s.*|$)", line.split(" #", 1)[0])
        if match and not line.startswith(("bin/", "lib/", "share/")):
            commands.append(match.group(1).strip())
    return commands


@pytest.mark.parametrize("name", ["README.md", "docs/GUIDE.md"])
def test_documented_commands_use_only_options_rtcl_has(name):
    defined = help_defined_options(help_text())
    commands = rtcl_commands(name)
    assert len(commands) >= 8
    used = {option for command in commands for option in mentioned_options(command)}
    assert used - defined == set(), f"{name} uses options that rtcl --help does not list"


def readme_scenes():
    """The README's first scene, and the same with its second step merged in."""
    blocks = re.findall(r"```json\n(.*?)```", (ROOT / "README.md").read_text(), re.S)
    first = json.loads(blocks[0])
    second = {**first, **json.loads("{" + blocks[1].strip().rstrip(",") + "}"), "version": 2}
    return first, second


def test_readme_first_scene_renders_as_written(tmp_path):
    """Both steps of the README's first scene render (the mesh path is relative
    to the source folder, where the README saves first.json), and a misspelt
    key gets the message the README quotes."""
    (tmp_path / "scenes").symlink_to(ROOT / "scenes")
    readme = (ROOT / "README.md").read_text()
    assert "./rtcl first.json -o first.png" in readme
    for step, scene in enumerate(readme_scenes()):
        (tmp_path / "first.json").write_text(json.dumps(scene))
        render = subprocess.run([RTCL, "-q", "first.json", "--size", "16x12", "-o",
                                 f"step{step}.ppm"], cwd=tmp_path, capture_output=True,
                                text=True, timeout=300)
        assert render.returncode == 0, render.stderr
    typo = readme_scenes()[0]
    typo["spheres"][0]["radus"] = typo["spheres"][0].pop("radius")
    (tmp_path / "first.json").write_text(json.dumps(typo))
    refused = subprocess.run([RTCL, "-s", "first.json", "-o", "typo.ppm"], cwd=tmp_path,
                             capture_output=True, text=True, timeout=60)
    assert refused.returncode == 1
    quoted = re.search(r"\(`(first\.json: [^`]*)`\)", readme).group(1)
    assert quoted in refused.stderr


DOCS_WITH_LINKS = ["README.md", "scenes/README.md", *sorted(
    str(path.relative_to(ROOT)) for path in [*(ROOT / "docs").glob("*.md"),
                                             *(ROOT / "docs/results").glob("*.md")])]


def heading_anchors(path):
    """GitHub's anchors for a Markdown file's headings."""
    anchors = set()
    for line in path.read_text().splitlines():
        match = re.match(r"#+ (.*)", line)
        if match:
            words = re.sub(r"[^\w\- ]", "", match.group(1).strip().lower())
            anchors.add(words.replace(" ", "-"))
    return anchors


@pytest.mark.parametrize("name", DOCS_WITH_LINKS)
def test_documentation_links_resolve(name):
    source = ROOT / name
    broken = []
    for target in re.findall(r"\]\(([^)\s]+)\)", source.read_text()):
        if re.match(r"[a-z]+:", target):
            continue
        file_part, _, anchor = target.partition("#")
        path = (source.parent / file_part).resolve() if file_part else source
        if not path.exists():
            broken.append(target)
        elif anchor and path.suffix == ".md" and anchor not in heading_anchors(path):
            broken.append(target)
    assert broken == [], f"{name}: links to nothing"
