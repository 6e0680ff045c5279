#!/usr/bin/env bash
# Issue 26, the CPU path: rtcl's kernels on PoCL with the kernel sources of
# two commits, in interleaved rounds on the same scenes (the machine is
# shared: a round of each side back to back, ROUNDS times, medians of -r 5
# launches' OpenCL profiling events each). Run from the repository root:
#
#   OLD=31d68e2 ROUNDS=5 docs/results/pocl-cpu-boxes/ab.sh SCENE... > ab.txt
#
# OLD's cl/ is read through RTCL_CL_DIR by the current ./rtcl, so that only
# the kernels differ (the host adds -DRTCL_CPU, which OLD's sources ignore).
# Each line: round, side, scene, kernel, median kernel ms, the -r times, the
# 1-minute load average; then whether the two sides' images are identical.
set -euo pipefail
OLD=${OLD:?name the old commit: OLD=...}
ROUNDS=${ROUNDS:-5}
KERNELS=${KERNELS:-naive dynamic persistent}
RTCL=${RTCL:-./rtcl}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
mkdir -p "$work/old-cl"
for f in $(git ls-tree --name-only "$OLD" cl/); do
	git show "$OLD:$f" >"$work/old-cl/$(basename "$f")"
done
echo "# new: $(git rev-parse --short HEAD)$(git diff --quiet HEAD -- cl host || echo '+changes'), old cl/: $OLD; $("$RTCL" --list-devices 2>/dev/null | grep -m1 -i pthread || true)"
echo "# $(date -u +%Y-%m-%dT%H:%MZ), $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2)"
for round in $(seq "$ROUNDS"); do
	for scene in "$@"; do
		for kernel in $KERNELS; do
			for side in old new; do
				dir=()
				[ "$side" = old ] && dir=(env RTCL_CL_DIR="$work/old-cl")
				"${dir[@]}" "$RTCL" -q -k "$kernel" -r 5 "$scene" \
					-o "$work/$side.ppm" --stats "$work/$side.json"
				python3 - "$work/$side.json" "$round" "$side" "$scene" "$kernel" \
					"$(cut -d' ' -f1 /proc/loadavg)" <<'PY'
import json, statistics, sys
d = json.load(open(sys.argv[1]))
times = d["kernel_ms_all"]
print(f"{sys.argv[2]} {sys.argv[3]} {sys.argv[4]} {sys.argv[5]} "
      f"{statistics.median(times):.1f} ms  [{' '.join(f'{t:.1f}' for t in times)}]  load {sys.argv[6]}")
PY
			done
			PYTHONPATH=tools python3 -c '
import sys
from rtcl_tools import ppm
same = ppm.pixels(sys.argv[1])[1] == ppm.pixels(sys.argv[2])[1]
print("  images identical" if same else "  IMAGES DIFFER")' "$work/old.ppm" "$work/new.ppm"
		done
	done
done
