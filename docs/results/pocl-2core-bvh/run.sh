#!/bin/bash
# Issue 11's CPU measurements on PoCL (this 2-core machine): the BVH's scaling
# curve, rtcl against POV-Ray 3.7, and the BVH's build time and device bytes
# per triangle at ~1 M triangles.  Run from the repository root after `make`:
#     docs/results/pocl-2core-bvh/run.sh [curve|povray|build ...] > run.txt
# (no argument: all three parts).  Scenes go to $WORK (default a temporary
# folder); every rtcl time is rtcl's own median of -r launches after a warm-up
# (OpenCL profiling events), every --stats figure is read back with grep.
set -u
WORK=${WORK:-$(mktemp -d /tmp/rtcl-pocl-bvh.XXXXXX)}
PY=/usr/bin/python3
PARTS=${*:-curve povray build}
SIZE=${SIZE:-2000x2000}           # the curve's image (--accel bvh)
NONE_SIZE=${NONE_SIZE:-1000x1000} # brute force's image (too slow at 2000x2000)
NONE_MAX=${NONE_MAX:-2000}        # brute force up to this many balls
BALLS=${BALLS:-60 200 400 1000 2000 5000 10000 20000}
R=${R:-3}
POV_SIZE=${POV_SIZE:-1000x1000}   # part 2's image
RUNS=${RUNS:-5}                   # part 2's runs of each program
BUILD_RUNS=${BUILD_RUNS:-3}       # part 3's runs of each scene

key() { grep -o "\"$1\": [0-9.a-z]*" "$2" | head -1 | sed 's/.*: //'; }
load() { cut -d' ' -f1-3 /proc/loadavg; }

header() {
  echo "# commit: $(git rev-parse --short HEAD)$(git diff --quiet HEAD -- host cl || echo ' (host/ or cl/ modified)')"
  echo "# cpu: $(grep -m1 'model name' /proc/cpuinfo | sed 's/.*: //'), $(nproc) CPUs"
  echo "# opencl: $(clinfo 2>/dev/null | grep -m1 'Platform Version' | sed 's/ *Platform Version *//')"
  echo "# device: $(./rtcl --list-devices | grep -m1 'Device #0' | sed 's/.*Device #0: //')"
  echo "# povray: $(command povray --version 2>&1 | grep -m1 "POV-Ray")"
  echo "# scenes in $WORK; load average at start: $(load)"
}

# One timed rtcl run: label, then rtcl's arguments; prints median, min, max, nodes.
timed() {
  local label=$1; shift
  ./rtcl -k dynamic -r $R --stats $WORK/st.json -o $WORK/img.ppm -q "$@" || { echo "$label FAILED"; return; }
  printf '%-22s median %9.1f ms  min %9.1f  max %9.1f  local %-5s nodes %-6s depth %-3s sah %-8s build_ms %s  load %s\n' \
    "$label" $(key kernel_ms $WORK/st.json) $(key kernel_ms_min $WORK/st.json) \
    $(key kernel_ms_max $WORK/st.json) $(key scene_in_local_memory $WORK/st.json) \
    "$(key nodes $WORK/st.json)" "$(key depth $WORK/st.json)" "$(key sah_cost $WORK/st.json)" \
    "$(key build_ms $WORK/st.json)" "$(load)"
}

curve() {
  echo "## 1. Scaling: tools/genscene.py --balls N (seed 2009, depth 5), -k dynamic -w 8x8, median of -r $R"
  echo "##    bvh at $SIZE; none (brute force) at $NONE_SIZE up to $NONE_MAX balls"
  for n in $BALLS; do
    $PY tools/genscene.py --balls $n --seed 2009 -o $WORK/r$n.json
    timed "r$n bvh $SIZE" -s $WORK/r$n.json --size $SIZE --accel bvh
    cp $WORK/img.ppm $WORK/r$n-bvh.ppm
    ./rtcl -k dynamic -s $WORK/r$n.json --size $SIZE --flops $WORK/f.npy --stats $WORK/st2.json -o $WORK/img.ppm -q
    echo "  r$n counting run (bvh, $SIZE): node_visits_per_ray $(key node_visits_per_ray $WORK/st2.json) rays $(key rays $WORK/st2.json) total_flops $(key total_flops $WORK/st2.json)"
    if [ $n -le $NONE_MAX ]; then
      timed "r$n none $NONE_SIZE" -s $WORK/r$n.json --size $NONE_SIZE --accel none
      cp $WORK/img.ppm $WORK/r$n-none.ppm
      timed "r$n bvh $NONE_SIZE" -s $WORK/r$n.json --size $NONE_SIZE --accel bvh
      cmp -s $WORK/img.ppm $WORK/r$n-none.ppm && echo "  r$n: bvh image byte-identical to none ($NONE_SIZE)" || echo "  r$n: bvh image DIFFERS from none ($NONE_SIZE)"
    fi
  done
}

povray() {
  echo "## 2. Whole process, rtcl (default kernel, one launch) against POV-Ray 3.7 +WT2 -A:"
  echo "##    tools/time_to_image.py, interleaved, $RUNS runs each after a warm-up, $POV_SIZE"
  $PY tools/genscene.py --balls 2000 --seed 2009 -o $WORK/r2000.json
  $PY tools/genbench.py mount --size 8 -o $WORK > /dev/null
  for scene in $WORK/r2000.json $WORK/spd-mount-8.json; do
    echo "### $(basename $scene)"
    $PY tools/time_to_image.py -s $scene --size $POV_SIZE --runs $RUNS
  done
}

# The build, the -v lines and --stats figures of one ~64x64 render of a big mesh.
build_one() {
  local scene=$1 i
  for i in $(seq $BUILD_RUNS); do
    ./rtcl -s $scene --size 64x64 -v --stats $WORK/b.json -o $WORK/b.png 2> $WORK/b.err > /dev/null
    grep -E "^rtcl: (BVH|device scene block|time:)" $WORK/b.err | sed 's/^/  /'
    echo "  stats: build_ms $(key build_ms $WORK/b.json) scene_bytes $(key scene_bytes $WORK/b.json) bytes_per_triangle $(key bytes_per_triangle $WORK/b.json) bvh.bytes $(key bytes $WORK/b.json)  load $(load)"
  done
}

build() {
  echo "## 3. BVH build time and device bytes per triangle, --size 64x64, $BUILD_RUNS runs each"
  $PY tools/genbench.py tetra --size 10 -o $WORK
  $PY tools/genbench.py mount --size 10 -o $WORK
  for scene in $WORK/spd-tetra-10.json $WORK/spd-mount-10.json; do
    echo "### $(basename $scene)"
    build_one $scene
  done
}

for part in $PARTS; do
  case $part in
    curve|povray|build) ;;
    *) echo "run.sh: unknown part '$part' (curve, povray, build)" >&2; exit 2 ;;
  esac
done
header
for part in $PARTS; do $part; done
echo "# load average at end: $(load)"
