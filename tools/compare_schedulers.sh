#!/usr/bin/env bash
# Issue 5: the beyond-the-paper schedulers (persistent, wavefront) against naive
# and dynamic on one device, default scene 2000x2000: median kernel times,
# parallel efficiency and Figure-7 histograms.
#
#   tools/compare_schedulers.sh RTCL OUTDIR [rtcl options, e.g. -p 1]
#
# Writes OUTDIR/schedulers.md (table), OUTDIR/schedulers_hist.png and the
# --stats JSON of every run; the .npy counts stay in a temporary folder.
set -eu
rtcl=$1
out=$2
shift 2
repeat=${REPEAT:-10}
python=${PYTHON:-python3}
tools=$(cd "$(dirname "$0")" && pwd)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
mkdir -p "$out"

runs=(
	"naive:-k naive -w 8x8"
	"dynamic:-k dynamic -w 8x8"
	"persistent_b1:-k persistent -w 8x8 --batch 1"
	"persistent_b4:-k persistent -w 8x8 --batch 4"
	"persistent_b16:-k persistent -w 8x8 --batch 16"
	"wavefront:-k wavefront -w 8x8"
)
for entry in "${runs[@]}"; do
	name=${entry%%:*}
	# shellcheck disable=SC2086 # the options are words
	"$rtcl" ${entry#*:} "$@" -r "$repeat" -q -o "$tmp/$name.ppm" --flops "$tmp/$name.npy" \
		--stats "$out/$name.json"
	echo "$name done" >&2
done
"$python" "$tools/flops_hist.py" --log -o "$out/schedulers_hist.png" \
	"$tmp/naive.npy" "$tmp/dynamic.npy" "$tmp/persistent_b1.npy" "$tmp/wavefront.npy"
"$python" - "$out" "$tmp" "$tools" "${runs[@]}" <<'PY'
import json, os, sys
out, tmp, tools, runs = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4:]
sys.path.insert(0, tools)
from ppmdiff import differences, pixels  # noqa: E402

reference = pixels(os.path.join(tmp, "naive.ppm"))[1]
rows = ["| run | options | time ms (median) | GFLOP/s | parallel efficiency | first NDRange |"
        " channel values differing from naive (max) |",
        "|---|---|---|---|---|---|---|"]


def differing(name):
    count, largest = differences(reference, pixels(os.path.join(tmp, name + ".ppm"))[1])
    return f"{count} ({largest}/255)"


for entry in runs:
    name, options = entry.split(":", 1)
    s = json.load(open(os.path.join(out, name + ".json")))
    rows.append(f"| {name} | `{options}` groups {s['groups']} | {s['kernel_ms']:.3f} |"
                f" {s['gflops']:.0f} | {100 * s['parallel_efficiency']:.1f}% |"
                f" {s['global_size'][0]}x{s['global_size'][1]} | {differing(name)} |")
first = json.load(open(os.path.join(out, runs[0].split(":", 1)[0] + ".json")))
head = [f"# Schedulers on {first['device']}", "",
        f"driver {first['driver']}; {first['scene']}, {first['width']}x{first['height']},"
        f" depth {first['max_depth']}; {first['gflop']:.3f} GFLOP counted;"
        f" median of {first['repeat']} launches (wavefront: of frames).", ""]
open(os.path.join(out, "schedulers.md"), "w").write("\n".join(head + rows) + "\n")
print("\n".join(head + rows))
PY
