#!/usr/bin/env bash
# Issue 26, the CPU path: the four-wide tree against the binary one on PoCL,
# the same binary and kernels, RTCL_TEST_BVH2=1 selecting the binary tree, in
# interleaved rounds on the same scenes (the machine is shared: a round of
# each side back to back, ROUNDS times, medians of -r 5 launches' OpenCL
# profiling events each). Run from the repository root:
#
#   ROUNDS=5 docs/results/pocl-cpu-bvh4/ab.sh SCENE-ARGS... > ab.txt
#
# Each SCENE-ARGS is one quoted argument list (e.g. "-s x.json --size 1000x1000").
# Each line: round, side (bvh2, bvh4), scene, kernel, median kernel ms, the -r
# times, the 1-minute load average; then whether the two sides' images are
# identical.
set -euo pipefail
ROUNDS=${ROUNDS:-5}
KERNELS=${KERNELS:-naive dynamic persistent}
RTCL=${RTCL:-./rtcl}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
echo "# $(git rev-parse --short HEAD)$(git diff --quiet HEAD -- cl host || echo '+changes'); $("$RTCL" --list-devices 2>/dev/null | grep -m1 -i pthread || true)"
echo "# $(date -u +%Y-%m-%dT%H:%MZ), $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2)"
for round in $(seq "$ROUNDS"); do
	for scene in "$@"; do
		for kernel in $KERNELS; do
			for side in bvh2 bvh4; do
				env=()
				[ "$side" = bvh2 ] && env=(env RTCL_TEST_BVH2=1)
				# shellcheck disable=SC2086
				"${env[@]}" "$RTCL" -q -k "$kernel" -r 5 $scene \
					-o "$work/$side.ppm" --stats "$work/$side.json"
				python3 - "$work/$side.json" "$round" "$side" "$scene" "$kernel" \
					"$(cut -d' ' -f1 /proc/loadavg)" <<'PY'
import json, statistics, sys
d = json.load(open(sys.argv[1]))
times = d["kernel_ms_all"]
print(f"{sys.argv[2]} {sys.argv[3]} {sys.argv[4]!r} {sys.argv[5]} "
      f"{statistics.median(times):.1f} ms  [{' '.join(f'{t:.1f}' for t in times)}]  load {sys.argv[6]}")
PY
			done
			cmp -s "$work/bvh2.ppm" "$work/bvh4.ppm" && echo "  images identical" ||
				echo "  IMAGES DIFFER"
		done
	done
done
