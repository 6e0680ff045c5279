#!/bin/bash
# GPU batch 17: the scene pointer declared restrict (read-only loads through
# the non-coherent path, ld.global.nc), against d2e1621 without it.
# Persistent, -r 20, three interleaved rounds; the lake -r 10.
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
export PATH=/usr/local/cuda/bin:$PATH
G=$PWD/.gpu; T=$(mktemp -d)
echo "commit: $COMMIT (rtcl), rtcl-restrict = it with restrict on scene_global"; nvidia-smi -L
P=$($G/rtcl --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
python3 tools/genscene.py --balls 2000 -o $T/r2000.json
python3 tools/genscene.py --balls 20000 -o $T/r20000.json
python3 tools/genbench.py lake -o $T/lake --image 2000x2000 > /dev/null
RTCL_CACHE=0 RTCL_DUMP_BINARY=$T/x.ptx $G/rtcl-restrict -p $P -k persistent --size 64x64 -s $T/r2000.json -q -o $T/a.ppm
echo "  ld.global.nc in the restrict PTX: $(grep -c 'ld.global.nc' $T/x.ptx), plain ld.global: $(grep -c 'ld.global.[^n]' $T/x.ptx)"
for round in 1 2 3; do
  for b in rtcl rtcl-restrict; do
    for sc in paper60 r2000 r20000; do
      S=""; [ $sc != paper60 ] && S="-s $T/$sc.json"
      printf "  round %s %-14s %-7s " $round $b $sc; $G/$b -p $P -k persistent -r 20 $S -o $T/$b-$sc.ppm -q --stats $T/s.json; grep -o '"kernel_ms": [0-9.]*' $T/s.json | head -1
    done
    printf "  round %s %-14s lake    " $round $b; $G/$b -p $P -k persistent -r 10 -s $T/lake/lake-10.json -o $T/$b-lake.ppm -q --stats $T/s.json; grep -o '"kernel_ms": [0-9.]*' $T/s.json | head -1
  done
done
for sc in paper60 r2000 r20000 lake; do echo "  $sc: $(python3 tools/ppmdiff.py $T/rtcl-$sc.ppm $T/rtcl-restrict-$sc.ppm 2>&1 | tail -1 | sed 's|.*: ||')"; done
