#!/usr/bin/env bash
# Valgrind memcheck on full renders of the built-in scene (`make valgrind`):
# a plain render, one with --flops, one with --work-map, and one with the
# work map and the schedule map together (the SIMD model), and the studio
# scene, whose mesh files bring materials and textures (their texels written
# into the device buffer from the scene's, issue 39 finding 14). Any invalid
# access, use of uninitialised memory or definite leak fails the run;
# test/valgrind.supp covers the OpenCL runtime's own reports only.
#
#   bash test/valgrind.sh [RTCL]     (default ./rtcl; run from anywhere)
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
rtcl="$(realpath "${1:-$root/rtcl}")"
out="$(mktemp -d)"
trap 'rm -rf "$out"' EXIT

memcheck() {
	echo "valgrind: rtcl $*"
	if ! valgrind --quiet --leak-check=full --show-leak-kinds=definite \
		--errors-for-leak-kinds=definite --error-exitcode=1 --num-callers=50 \
		--suppressions="$root/test/valgrind.supp" "$rtcl" "$@" >"$out/log" 2>&1; then
		cat "$out/log"
		echo "valgrind: FAILED: rtcl $*" >&2
		exit 1
	fi
}

memcheck --size 64x48 -o "$out/plain.ppm"
memcheck --size 64x48 -o "$out/flops.ppm" --flops "$out/flops.npy"
memcheck --size 64x48 -o "$out/work.ppm" --work-map "$out/work_map.ppm"
memcheck --size 64x48 -o "$out/sched.ppm" --work-map "$out/sched_work.npy" \
	--schedule-map "$out/sched.npy" --stats "$out/sched.json"
memcheck "$root/scenes/studio.json" --size 32x24 -o "$out/studio.ppm"
for f in plain.ppm flops.ppm flops.npy work.ppm work_map.ppm sched.ppm sched.npy sched.json \
	studio.ppm; do
	[ -s "$out/$f" ] || { echo "valgrind: $f was not written" >&2; exit 1; }
done
echo "valgrind: 5 renders, no errors and no definite leaks"
