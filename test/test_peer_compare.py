"""rtcl-peer-compare --cpu end to end (issue 26), with a stand-in for the peer's
folder (TinyBVH's harness is not part of the repository): its cside prints
fixed timings, so that the report's ratios can be checked against rtcl's own
--stats, and its ply2bin writes a placeholder. rtcl renders for real on PoCL."""
import json
import os
import pathlib
import re
import statistics
import subprocess
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parent.parent
RTCL = os.environ.get("RTCL", str(ROOT / "rtcl"))

CSIDE = r'''#include <cstdio>
int main() {
	std::printf("BVH (HQ)     build    12.0 ms  trace median    40.00 ms ->  1.0 Mrays/s (2 threads), hits 900\n");
	std::printf("BVH8_CPU     build    15.0 ms  trace median    20.00 ms ->  2.0 Mrays/s (2 threads), hits 901\n");
	return 0;
}
'''
PLY2BIN = "import sys\nopen(sys.argv[2], 'wb').write(bytes(4))\n"


@pytest.mark.slow
def test_cpu_report_sets_rtcl_against_the_peer_and_takes_out_the_frame_with_nothing(tmp_path):
    peer = tmp_path / "peer"
    peer.mkdir()
    (peer / "cside.cpp").write_text(CSIDE)
    (peer / "tiny_bvh.h").write_text("")
    (peer / "ply2bin.py").write_text(PLY2BIN)
    out = tmp_path / "out"
    result = subprocess.run(
        [sys.executable, str(ROOT / "tools" / "peer_compare.py"), peer, "--cpu", "--rtcl", RTCL,
         "--meshes", "tetra:2", "--size", "64x48", "-r", "3", "--kernels", "naive,dynamic",
         "-o", out], capture_output=True, text=True, cwd=tmp_path, timeout=600)
    assert result.returncode == 0, result.stderr
    raw = out / "raw"
    rtcl = {kernel: statistics.median(json.loads(
        (raw / f"rtcl-tetra-2-{kernel}.json").read_text())["kernel_ms_all"])
        for kernel in ("naive", "dynamic")}
    fastest = min(rtcl, key=rtcl.get)
    nothing = json.loads((raw / "rtcl-tetra-2-nothing-{}.json".format(fastest)).read_text())
    assert "-DRTCL_NO_TRIANGLES" in nothing["build_options"]  # the mesh left out
    outside = statistics.median(nothing["kernel_ms_all"])
    row = [line for line in (out / "cpu.md").read_text().splitlines()
           if line.startswith("| tetra-2 |")]
    assert len(row) == 1, (out / "cpu.md").read_text()
    cells = [cell.strip() for cell in row[0].strip("|").split("|")]
    assert cells[1] == f"naive {rtcl['naive']:.1f} / dynamic {rtcl['dynamic']:.1f}"
    assert cells[2] == "BVH (HQ) 40.0 / BVH8_CPU 20.0"
    assert cells[3] == f"{20.0 / rtcl[fastest]:.2f}x"
    assert cells[4] == f"{outside:.1f}"
    assert cells[5] == (f"{20.0 / (rtcl[fastest] - outside):.2f}x"
                        if rtcl[fastest] > outside else "-")
    assert re.fullmatch(r"[\d,]+ / 901", cells[6]) and cells[7] == "2"
