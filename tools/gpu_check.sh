#!/usr/bin/env bash
# Renders the default scene (2000x2000, paper60) with every kernel on one
# device, checks that all images are byte-identical, and prints each kernel's
# median kernel time. Used for the NVIDIA runs (issue 2); works on any device.
#
#   tools/gpu_check.sh RTCL OUTDIR [rtcl options, e.g. -p 1 -d 0]
#
# REPEAT (default 10) timed launches per kernel; the serial kernel runs once,
# and only if a 250x250 trial predicts it finishes within SERIAL_LIMIT_S
# (default 240) seconds.
set -u
rtcl=$1
out=$2
shift 2
repeat=${REPEAT:-10}
serial_limit_s=${SERIAL_LIMIT_S:-240}
mkdir -p "$out"

"$rtcl" --list-devices
run() { # name, options...
	local name=$1
	shift
	echo "== $name: $rtcl $*"
	"$rtcl" "$@" "${device_options[@]}" -o "$out/$name.ppm" --encoding linear --stats "$out/$name.json" || echo "FAILED: $name"
}
device_options=("$@")

run naive -k naive -r "$repeat"
run cyclic -k cyclic -r "$repeat"
run dynamic -k dynamic -r "$repeat"
run naive_paper -k naive -w 16x10 -r "$repeat"
run cyclic_paper -k cyclic -w 8x8 --groups 25x25 -r "$repeat"
run dynamic_paper -k dynamic -w 8x8 --groups 10x10 -r "$repeat"

run serial_trial -k serial --size 250x250
trial_ms=$(python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["kernel_ms"])' "$out/serial_trial.json")
predicted_s=$(awk -v ms="$trial_ms" 'BEGIN { printf "%.0f", ms * 64 / 1000 }')
echo "serial at 2000x2000 predicted: ${predicted_s} s per launch (two launches: warm-up and timed)"
if [ "$((predicted_s * 2))" -le "$serial_limit_s" ]; then
	run serial -k serial
fi

echo "== identical images? (pixels only: the headers name the kernel)"
images=()
for f in "$out"/*.ppm; do
	case $f in *serial_trial*) ;; *) images+=("$f") ;; esac
done
python3 "$(dirname "$0")/ppmdiff.py" "$out/dynamic.ppm" "${images[@]}" || true
echo "== median kernel times"
python3 - "$out" <<'PY'
import glob, json, os, sys
for path in sorted(glob.glob(os.path.join(sys.argv[1], "*.json"))):
    s = json.load(open(path))
    print(f"{os.path.basename(path)[:-5]:16} {s['kernel']:8} -w {s['workgroup']:6} groups {s['groups']:8}"
          f" {s['width']}x{s['height']}  median {s['kernel_ms']:.3f} ms (min {s['kernel_ms_min']:.3f},"
          f" max {s['kernel_ms_max']:.3f}, n={s['repeat']})  {s['device']}")
PY
