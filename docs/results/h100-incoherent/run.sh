#!/bin/bash
# GPU batch "incoherent" (issue 42, H100): rtcl against TinyBVH's OpenCL kernels
# on the same primary, diffuse-bounce and shadow rays (rtcl-peer-compare --rays,
# docs/bvh.md "Incoherent rays against TinyBVH"): SPD mount 8 (131,072
# triangles), SPD tetra 10 (1,048,576) and the lake (2,097,152), rays of a
# 2000x2000 image, -r 10; the peer's BVH_GPU built HQ and SAH, BVH4_GPU and CWBVH built HQ
# (--variants aAqc). rtcl-rays builds its programs from source (fresh cache).
#
# Everything it needs is in the folder this script is in (.gpu/incoherent of
# the tree the device runs in): rtcl, rtcl-rays and rtcl-meshread built with
# `make OIIO=0 MPI=0`, tools/ (the branch's tools), peer/ (TinyBVH 1.6.7's
# harness, the folder shared/bench/tinybvh), COMMIT; the libraries in .gpu/lib.
# The peer's programs are built on the device (g++, OpenCL headers).
#   bash .gpu/incoherent/run.sh            # results under $OUT
# RAYS_LOCAL=1: the same steps on a CPU OpenCL device (PoCL) on a small mesh,
# the NVIDIA parts left out, to check the script before a GPU run.
set -u
G=$(cd "$(dirname "$0")" && pwd)
ROOT=$(cd "$G/../.." && pwd)
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$ROOT/.gpu/lib:${LD_LIBRARY_PATH:-}
export RTCL_MESHREAD=$G/rtcl-meshread
export XDG_CACHE_HOME=$(mktemp -d)
export RTCL_COMMIT=$(cat "$G/COMMIT")
OUT=${OUT:-$(mktemp -d)}
T=$(mktemp -d)
echo "commit: $RTCL_COMMIT"
if [ "${RAYS_LOCAL:-0}" = 1 ]; then
  MODE=(--cpu --meshes tetra:5 --size 96x64 -r 2)
else
  nvidia-smi -L
  MODE=(--meshes mount:8,tetra:10,lake --size 2000x2000 -r 10 --variants aAqc)
fi
"$G/rtcl" --list-devices | grep -i "platform" | head -4
start=$(date +%s)
timeout 225 python3 "$G/tools/peer_compare.py" "$G/peer" --rays --rtcl "$G/rtcl" \
  "${MODE[@]}" -o "$T/rays" 2>&1 | grep -v "^|" | tail -20
echo "exit ${PIPESTATUS[0]} after $(( $(date +%s) - start )) s"
mkdir -p "$OUT/rays"
cp "$T"/rays/rays.md "$T"/rays/rays.csv "$OUT/rays/" 2>/dev/null
cp -r "$T/rays/raw" "$OUT/rays/" 2>/dev/null
cat "$OUT/rays/rays.md" 2>/dev/null
rm -rf "$T"
