"""No tool overwrites or removes a file tracked by git (issue 22 item 2).

Each tool that writes is pointed (with -o/--out, or --replot) at a file tracked in
a temporary git repository, never the real one: it must exit non-zero with one
line naming the file and --update-committed, leave the file as it was, and for
the tools that run rtcl, refuse before running it (a --rtcl that leaves a mark
proves that).  --update-committed is the one way through.  Also: the tools find
the rtcl installed beside them before the one on PATH, and default to a new
rtcl-results/ folder.
"""
import pathlib
import subprocess
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parent.parent
TOOLS = ROOT / "tools"
sys.path.insert(0, str(TOOLS))

from rtcl_tools import files, locations  # noqa: E402

COMMITTED = "committed content\n"


@pytest.fixture
def repo(tmp_path):
    """A git work tree at tmp_path/repo."""
    folder = tmp_path / "repo"
    folder.mkdir()
    subprocess.run(["git", "init", "-q", str(folder)], check=True)
    return folder


def track(repo, name, content=COMMITTED):
    """Writes repo/name and adds it to git's index: a tracked file."""
    path = repo / name
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(content)
    subprocess.run(["git", "-C", str(repo), "add", name], check=True)
    return path


@pytest.fixture
def marking_rtcl(tmp_path):
    """An rtcl that leaves a mark and fails: the refusal must come before any run."""
    fake = tmp_path / "bin" / "rtcl"
    fake.parent.mkdir()
    fake.write_text(f"#!/bin/sh\ntouch {tmp_path / 'rtcl-ran'}\nexit 7\n")
    fake.chmod(0o755)
    return fake


def run_tool(name, *args, cwd=None):
    return subprocess.run([sys.executable, str(TOOLS / name), *map(str, args)],
                          capture_output=True, text=True, cwd=cwd or ROOT, timeout=300)


def flops_file(tmp_path):
    import numpy as np
    path = tmp_path / "run.npy"
    np.save(path, np.arange(16, dtype="<u8").reshape(4, 4))
    return path


# (tool, file to track relative to the repo, arguments with {repo}, {rtcl}, {npy})
WRITERS = [
    ("experiments.py", "study/table1.md",
     ["--rtcl", "{rtcl}", "--quick", "-o", "{repo}/study"]),
    ("experiments.py", "study/table1.md", ["--replot", "{repo}/study"]),
    ("bench.py", "b/bench.md", ["--rtcl", "{rtcl}", "--quick", "-o", "{repo}/b"]),
    ("bench_spp.py", "s/spp.csv", ["--rtcl", "{rtcl}", "-o", "{repo}/s"]),
    ("multidevice_bench.py", "m.md",
     ["--rtcl", "{rtcl}", "--single", "0:0", "--multi", "0:0", "-o", "{repo}/m.md"]),
    ("time_to_image.py", "t.txt", ["--rtcl", "{rtcl}", "-r", "1", "-o", "{repo}/t.txt"]),
    ("genscene.py", "scene.json", ["--balls", "3", "-o", "{repo}/scene.json"]),
    ("genbench.py", "scenes/random-balls-3.json",
     ["random-balls", "--balls", "3", "-o", "{repo}/scenes"]),
    ("povray.py", "x.pov", ["-s", str(ROOT / "scenes" / "two_balls.json"),
                            "-o", "{repo}/x.pov"]),
    ("flops_hist.py", "fig.png", ["{npy}", "-o", "{repo}/fig.png"]),
    ("peer_compare.py", "p/compare.md", ["/nonexistent-peer", "--rtcl", "{rtcl}",
                                         "-o", "{repo}/p"]),
    ("peer_compare.py", "c/counts.md", ["/nonexistent-peer", "--counts", "--rtcl", "{rtcl}",
                                        "-o", "{repo}/c"]),
    ("peer_compare.py", "u/cpu.md", ["/nonexistent-peer", "--cpu", "--rtcl", "{rtcl}",
                                     "-o", "{repo}/u"]),
    ("peer_compare.py", "r/rays.md", ["/nonexistent-peer", "--rays", "--rtcl", "{rtcl}",
                                      "-o", "{repo}/r"]),
]


@pytest.mark.parametrize("tool, tracked, args", WRITERS,
                         ids=[f"{tool}:{tracked}" for tool, tracked, _ in WRITERS])
def test_no_tool_overwrites_a_tracked_file(tmp_path, repo, marking_rtcl, tool, tracked, args):
    path = track(repo, tracked)
    if "--replot" in args:
        track(repo, "study/results.json", '{"meta": {"date": "x", "repeat": 1}, "runs": []}')
    values = {"repo": repo, "rtcl": marking_rtcl, "npy": "{npy}"}
    if "{npy}" in args:
        values["npy"] = flops_file(tmp_path)
    before = sorted(p.relative_to(repo) for p in repo.rglob("*") if ".git" not in p.parts)
    result = run_tool(tool, *[arg.format(**values) for arg in args], cwd=tmp_path)
    assert result.returncode != 0
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, result.stderr
    assert "is tracked by git: not overwritten" in lines[0] and tracked in lines[0]
    assert "--update-committed" in lines[0] and "Traceback" not in result.stderr
    assert path.read_text() == COMMITTED
    assert sorted(p.relative_to(repo) for p in repo.rglob("*")
                  if ".git" not in p.parts) == before
    assert not (tmp_path / "rtcl-ran").exists(), "the refusal came after running rtcl"


def test_update_committed_is_the_way_through(tmp_path, repo):
    path = track(repo, "scene.json")
    result = run_tool("genscene.py", "--balls", "3", "-o", path, "--update-committed",
                      cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert path.read_text().startswith("{") and path.read_text() != COMMITTED


def test_untracked_files_in_a_work_tree_and_files_outside_one_are_written(tmp_path, repo):
    track(repo, "kept.txt")
    files.write_text(repo / "new.txt", "new\n")
    files.write_all({repo / "sub" / "a.md": "a\n"})
    (tmp_path / "plain").mkdir()
    files.write_text(tmp_path / "plain" / "x.txt", "x\n")
    assert (repo / "new.txt").read_text() == "new\n"
    assert (repo / "sub" / "a.md").read_text() == "a\n"
    assert (tmp_path / "plain" / "x.txt").read_text() == "x\n"


def test_the_writers_refuse_tracked_files_and_folders(repo):
    path = track(repo, "results/table1.md")
    for write in (lambda: files.write_text(path, "new\n"),
                  lambda: files.write_all({repo / "results" / "other.md": "o\n", path: "n\n"}),
                  lambda: files.remove(path),
                  lambda: files.check_not_tracked([repo / "results"])):
        with pytest.raises(files.TrackedFileError, match="table1.md is tracked by git"):
            write()
    assert path.read_text() == COMMITTED
    assert not (repo / "results" / "other.md").exists()
    with files.committed_files_allowed(True):
        files.write_text(path, "regenerated\n")
    assert path.read_text() == "regenerated\n"
    with pytest.raises(files.TrackedFileError):
        files.write_text(path, "again\n")      # allowed only inside the block


def test_a_tracked_file_whose_folder_is_gone_is_still_refused(repo):
    path = track(repo, "gone/deep/table1.md")
    path.unlink()
    path.parent.rmdir()
    with pytest.raises(files.TrackedFileError):
        files.write_all({path: "x\n"})


# ---- where the tools look for rtcl and write by default ---------------------------------

def test_find_rtcl_prefers_the_rtcl_beside_the_command(tmp_path, monkeypatch):
    beside = tmp_path / "prefix" / "bin"
    beside.mkdir(parents=True)
    for name in ("rtcl", "rtcl-bench"):
        (beside / name).write_text("#!/bin/sh\n")
        (beside / name).chmod(0o755)
    on_path = tmp_path / "path"
    on_path.mkdir()
    (on_path / "rtcl").write_text("#!/bin/sh\n")
    (on_path / "rtcl").chmod(0o755)
    monkeypatch.setenv("PATH", str(on_path))
    monkeypatch.setattr(sys, "argv", [str(beside / "rtcl-bench")])
    assert locations.find_rtcl() == str(beside / "rtcl")
    assert locations.find_rtcl("/given/rtcl") == "/given/rtcl"
    monkeypatch.setattr(sys, "argv", [str(tmp_path / "elsewhere" / "rtcl-bench")])
    monkeypatch.setattr(locations, "SOURCE_ROOT", tmp_path / "not-a-checkout")
    assert locations.find_rtcl() == str(on_path / "rtcl")
    monkeypatch.setenv("PATH", str(tmp_path / "empty"))
    monkeypatch.chdir(tmp_path)
    with pytest.raises(locations.NotFound, match="--rtcl"):
        locations.find_rtcl()


def test_new_results_folders_never_reuse_one(tmp_path):
    import datetime
    now = datetime.datetime(2030, 1, 2, 3, 4, 5)
    first = locations.new_results_folder("dev", tmp_path / "rtcl-results", now)
    second = locations.new_results_folder("dev", tmp_path / "rtcl-results", now)
    assert first.name == "dev-20300102-030405" and second.name == "dev-20300102-030405-2"
    assert first.is_dir() and second.is_dir()


def test_update_committed_outside_a_checkout_is_one_line(monkeypatch, tmp_path):
    monkeypatch.setattr(locations, "SOURCE_ROOT", tmp_path)
    with pytest.raises(locations.NotFound, match="source tree"):
        locations.committed_results()


def test_peer_compare_names_a_folder_that_is_not_the_peers(tmp_path, marking_rtcl):
    (tmp_path / "peer").mkdir()
    (tmp_path / "peer" / "side.cpp").write_text("")
    result = run_tool("peer_compare.py", tmp_path / "peer", "--rtcl", marking_rtcl, "-o",
                      tmp_path / "out", cwd=tmp_path)
    assert result.returncode == 1
    assert result.stderr.strip().splitlines() == [
        f"peer_compare.py: error: {tmp_path / 'peer'} is not the peer's folder: no "
        "tiny_bvh.h, tiny_ocl.h, ply2bin.py"]
    assert not (tmp_path / "rtcl-ran").exists()
    counts = run_tool("peer_compare.py", tmp_path / "peer", "--counts", "--rtcl", marking_rtcl,
                      "-o", tmp_path / "out", cwd=tmp_path)
    assert counts.returncode == 1
    assert counts.stderr.strip().splitlines() == [
        f"peer_compare.py: error: {tmp_path / 'peer'} is not the peer's folder: no tiny_bvh.h"]
    on_cpu = run_tool("peer_compare.py", tmp_path / "peer", "--cpu", "--rtcl", marking_rtcl,
                      "-o", tmp_path / "out", cwd=tmp_path)
    assert on_cpu.returncode == 1
    assert on_cpu.stderr.strip().splitlines() == [
        f"peer_compare.py: error: {tmp_path / 'peer'} is not the peer's folder: no cside.cpp "
        "or tiny_bvh.h"]
    rays = run_tool("peer_compare.py", tmp_path / "peer", "--rays", "--rtcl", marking_rtcl,
                    "-o", tmp_path / "out", cwd=tmp_path)
    assert rays.returncode == 1
    assert rays.stderr.strip().splitlines() == [
        f"peer_compare.py: error: {tmp_path / 'peer'} is not the peer's folder: no "
        "tiny_bvh.h, ply2bin.py, tiny_ocl.h, traverse.cl"]
    rays_cpu = run_tool("peer_compare.py", tmp_path / "peer", "--rays", "--cpu", "--rtcl",
                        marking_rtcl, "-o", tmp_path / "out", cwd=tmp_path)
    assert rays_cpu.stderr.strip().splitlines() == [
        f"peer_compare.py: error: {tmp_path / 'peer'} is not the peer's folder: no "
        "tiny_bvh.h, ply2bin.py"]
    rays_counts = run_tool("peer_compare.py", tmp_path / "peer", "--rays", "--counts",
                           "-o", tmp_path / "out", cwd=tmp_path)
    assert rays_counts.returncode == 1
    assert rays_counts.stderr.strip().splitlines() == [
        "peer_compare.py: error: --rays and --counts do not go together: --rays times"]
    both = run_tool("peer_compare.py", tmp_path / "peer", "--cpu", "--counts", cwd=tmp_path)
    assert both.returncode == 2 and "not allowed with argument" in both.stderr
    assert not (tmp_path / "rtcl-ran").exists()
