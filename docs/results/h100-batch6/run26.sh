#!/bin/bash
# GPU batch 26 (issue 22 item 3): batch 25's part 2 again after naive counts one
# work-group in 16 ($COMMIT); 9 processes each.
#  1. wall time of a 1,024-spp render (1,024 passes) off and on a terminal;
#  2. the kernel time of plain renders (one launch, no -r) of naive and cyclic
#     with the line on (-DRTCL_PROGRESS) and off: 7 processes each,
#     interleaved, median of their kernel_ms; dynamic as a control;
#  3. -r runs: the same build options on and off a terminal;
#  4. single long launches (serial; cyclic and dynamic with one group): the
#     shares the line shows during the launch, read on a second queue.
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
G=$PWD/.gpu; T=$(mktemp -d)
echo "commit: $COMMIT"; nvidia-smi -L
P=$($G/rtcl --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
on() { python3 $G/pty_run.py "$T/pty.txt" "$@" > /dev/null; }
off() { "$@" > /dev/null 2> "$T/err.txt" || cat "$T/err.txt"; }
ms() { python3 -c 'import json,sys; print("%.4f" % json.load(open(sys.argv[1]))["kernel_ms"])' "$1"; }
shares() { tr '\r' '\n' < "$T/pty.txt" | grep -o '[0-9]*% done' | uniq | tr '\n' ' ' | cut -c1-240; }
# warm the program caches
for k in naive cyclic dynamic; do off $G/rtcl -p $P -k $k -o $T/w.ppm; on $G/rtcl -p $P -k $k -o $T/w.ppm; done
echo "== 2. plain renders (one launch), kernel_ms median of 9 processes"
for k in naive cyclic; do for spp in 1 16; do
  : > $T/off.txt; : > $T/on.txt
  for i in 1 2 3 4 5 6 7 8 9; do
    off $G/rtcl -p $P -k $k --spp $spp -o $T/a.ppm --stats $T/a.json; ms $T/a.json >> $T/off.txt
    on $G/rtcl -p $P -k $k --spp $spp -o $T/b.ppm --stats $T/b.json; ms $T/b.json >> $T/on.txt
  done
  python3 - $k $spp $T/off.txt $T/on.txt <<'PY'
import sys, statistics as st
k, spp, a, b = sys.argv[1], sys.argv[2], [float(x) for x in open(sys.argv[3])], [float(x) for x in open(sys.argv[4])]
ma, mb = st.median(a), st.median(b)
print(f"  {k:8s} spp {spp:3s}: off {ma:.4f} ms, on {mb:.4f} ms ({100*(mb-ma)/ma:+.2f} %); off {min(a):.4f}-{max(a):.4f}, on {min(b):.4f}-{max(b):.4f}")
PY
  grep -o '"build_options": "[^"]*"' $T/b.json | grep -q RTCL_PROGRESS && echo "    (on: -DRTCL_PROGRESS)"
done; done
