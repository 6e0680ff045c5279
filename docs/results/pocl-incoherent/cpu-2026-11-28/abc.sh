#!/bin/bash
# abc.sh NAME ROUNDS VARIANT... : CPU ms per launch (task-clock of -r 9 minus -r 1, /8), interleaved
B=/tmp/cpurays/base; name=$1; rounds=$2; shift 2
S=$B/meshes/$name-primary.json; R=$B/rays/$name
export POCL_WORK_GROUP_SPECIALIZATION=0
cpu() { RTCL_BUILD_OPTIONS="$1" perf stat -x, -e task-clock ${RAYS:-/work/wt/cpurays/build/rtcl-rays} -r $2 $EXTRA $S $R/$3.rays /tmp/cpurays/h-$name-$3-$4.hits 2>&1 >/dev/null | grep task-clock | cut -d, -f1; }
for r in $(seq $rounds); do
  for kind in ${KINDS:-primary bounce shadow}; do
    for v in "$@"; do
      vv=$v; [ "$v" = base ] && vv=""
      a=$(cpu "$vv" 1 $kind $v); b=$(cpu "$vv" 9 $kind $v)
      echo "$name $kind $v round$r cpu_ms_per_launch $(python3 -c "print(round(($b-$a)/8,1))")  load $(cut -d' ' -f1 /proc/loadavg)"
    done
  done
done
