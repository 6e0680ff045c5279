#!/bin/bash
# Issue 42, batch 99 (one H100): rtcl against TinyBVH on the same primary,
# diffuse-bounce and shadow rays (rtcl-peer-compare --rays, docs/bvh.md
# "Incoherent rays against TinyBVH"), one mesh per run so no cap cuts a mesh:
# GPU: SPD tetra 10 (1,048,576 triangles) and the lake (2,097,152), rays of a
# 2000x2000 image, -r 10, the peer's BVH_GPU HQ and SAH, CWBVH HQ
# (--variants aAc). Then CPU (PoCL on the device host's cores, quiet)
# against TinyBVH's CPU traversals: mount 8, tetra 10, lake at 1000x1000,
# -r 5, three rounds.
# Everything comes from this folder (.gpu/inc99): rtcl, rtcl-rays,
# rtcl-meshread (make OIIO=0 MPI=0 BUILD=build-gpu at COMMIT), tools/ of
# COMMIT, peer/ = shared/bench/tinybvh (TinyBVH 1.6.7's harness); libraries
# in .gpu/lib.
#   bash .gpu/inc99/run.sh [gpu|cpu|all]
set -u
G=$(cd "$(dirname "$0")" && pwd)
ROOT=$(cd "$G/../.." && pwd)
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$ROOT/.gpu/lib:${LD_LIBRARY_PATH:-}
export RTCL_MESHREAD=$G/rtcl-meshread
export XDG_CACHE_HOME=$(mktemp -d)
export RTCL_COMMIT=$(cat "$G/COMMIT")
OUT=${OUT:-$(mktemp -d)}
WHAT=${1:-all}
echo "commit: $RTCL_COMMIT"; nvidia-smi -L; nproc; date -u
"$G/rtcl" --list-devices | grep -i "platform" | head -6
one() { # tag, timeout, options...
  local tag=$1 cap=$2; shift 2
  local start=$(date +%s)
  timeout $cap python3 "$G/tools/peer_compare.py" "$G/peer" --rays --rtcl "$G/rtcl" \
    "$@" -o "$T/$tag" 2>&1 | grep -v "^|" | tail -8
  echo "$tag: exit ${PIPESTATUS[0]} after $(( $(date +%s) - start )) s"
  cat "$T/$tag/rays.md" 2>/dev/null
}
T=$(mktemp -d)
if [ "$WHAT" != cpu ]; then
  one gpu-tetra10 260 --meshes tetra:10 --size 2000x2000 -r 10 --variants aAc
  one gpu-lake 300 --meshes lake --size 2000x2000 -r 10 --variants aAc
fi
if [ "$WHAT" != gpu ]; then
  # one mesh a run, each under its own cap (CPU_CAP s), so that a slow one
  # leaves the others' results
  for m in mount:8 tetra:10 lake; do
    one cpu-${m%%:*} ${CPU_CAP:-170} --cpu --meshes $m --size 1000x1000 -r 5 --rounds ${CPU_ROUNDS:-3}
  done
fi
cd "$T" && for d in */; do d=${d%/}; rm -f $d/*.bin $d/*.rays 2>/dev/null; done
find "$T" -size +4M -delete
tar czf "$OUT/inc99.tgz" -C "$T" . ; ls -la "$OUT"; date -u
