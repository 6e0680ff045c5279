#!/bin/bash
# Batch 60 (one GPU; two where lent): in batch 59 every render whose program came from rtcl's
# program cache was slower than one built from source (default scene 1861
# against 1732 ms, lake 1248 against 1078): the cached binary was built without
# the build options. OLD = .gpu/rtcl-old (eeb26f3, built with none), NEW =
# .gpu/rtcl (the options passed). "fresh" = RTCL_CACHE=0 (built from source
# every run), "cached" = from the cache, primed first. Then two GPUs against
# one, all from the cache, default scene 2048 spp. Median of -r 3, kernel ms,
# and one device's frame wall time (frame_ms, d7eae24), which is what two
# devices' figure is.
# Before (here): make OIIO=0 MPI=0 BUILD=/tmp/gb BIN=.gpu/rtcl; for OLD,
#   git worktree add /tmp/old eeb26f3 && make -C /tmp/old OIIO=0 MPI=0 \
#     BUILD=/tmp/gbo BIN=$PWD/.gpu/rtcl-old; and .gpu/lib, .gpu/rtcl-meshread.
#   COMMIT=<commit> bash docs/results/multidevice/h200x2/run60.sh
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
export RTCL_MESHREAD=$PWD/.gpu/rtcl-meshread
export XDG_CACHE_HOME=$(mktemp -d)
G=$PWD/.gpu; NEW=$G/rtcl; OLD=$G/rtcl-old
T=$(mktemp -d); O=$T/json; mkdir -p $O
echo "commit: $COMMIT"; nvidia-smi -L
P=$($NEW --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
python3 tools/genbench.py lake -o $T/lake > /dev/null
declare -A S=([default]="-k dynamic --size 2000x2000 --spp 1024" [lake]="-k dynamic -s $T/lake/lake-10.json --size 2000x2000 --spp 256")
show() { python3 -c "
import json, sys
d = json.load(open(sys.argv[1]))
print('median %.1f ms (min %.1f, max %.1f), frame wall %.1f ms, build_cached %s' % (d['kernel_ms'], d['kernel_ms_min'], d['kernel_ms_max'], d.get('frame_ms', float('nan')), d.get('build_cached')))" $1; }
one() { # tag, binary, cache (0 = off), scene, extra...
  local tag=$1 bin=$2 cache=$3 s=$4; shift 4
  RTCL_CACHE=$cache $bin -p $P -d 0 ${S[$s]} -r 3 -q -o $T/$tag.ppm --stats $O/$tag.json "$@"
  echo "$tag: $(show $O/$tag.json)"; cmp -s $T/$tag.ppm $T/ref-$s.ppm || echo "  IMAGE DIFFERS from the first"; }
for s in default lake; do
  $NEW -p $P -d 0 ${S[$s]} --size 64x64 -q -o $T/prime.ppm   # primes the cache
  RTCL_CACHE=0 $NEW -p $P -d 0 ${S[$s]} -q -o $T/ref-$s.ppm
  rounds=2; [ $s = lake ] && rounds=1
  for round in $(seq $rounds); do
    one $s-fresh-new-$round $NEW 0 $s
    one $s-cached-new-$round $NEW 1 $s
    one $s-cached-old-$round $OLD 1 $s
  done
done
S[default]="-k dynamic --size 2000x2000 --spp 2048"
$NEW -p $P -d 0 ${S[default]} -r 3 -q -o $T/one.ppm --stats $O/one2048.json
echo "default 2048 spp one GPU (cached, NEW): $(show $O/one2048.json)"
if [ $(nvidia-smi -L | wc -l) -ge 2 ]; then
  $NEW --devices $P:0,$P:1 ${S[default]} -r 3 -q -o $T/two.ppm --stats $O/two2048.json
  echo "default 2048 spp two GPUs (cached, NEW): $(show $O/two2048.json)"
  cmp -s $T/one.ppm $T/two.ppm && echo "  image identical to one GPU's" || echo "  IMAGE DIFFERS"
fi
RTCL_CACHE=0 $NEW -p $P -d 0 ${S[default]} -r 3 -q -o $T/onef.ppm --stats $O/one2048f.json
echo "default 2048 spp one GPU (fresh, NEW): $(show $O/one2048f.json)"
# Do two queues' kernels overlap on this GPU? (hiding a launch's idle end, README)
cc -O2 -o $T/queue_overlap tools/device/queue_overlap.c -lOpenCL && $T/queue_overlap $P 0
tar czf $OUT/batch60-json.tgz -C $T json
