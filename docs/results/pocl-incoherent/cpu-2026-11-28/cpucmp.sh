#!/bin/bash
# cpucmp.sh NAME ROUNDS: CPU ms per pass of the peer's traversals (peer_rays with getrusage, peer_rays-cpu.patch)
# and CPU ms per launch of rtcl-rays (abc.sh base), interleaved.
B=/tmp/cpurays/base; name=$1
for r in $(seq $2); do
  /tmp/cpurays/peercpu/peer_rays trace $B/meshes/$name.bin 5 $(for k in primary bounce shadow; do echo $B/rays/$name/$k.rays /tmp/cpurays/peercpu/$k.hits; done) | grep -E "rays:|cpu median|trace median" | sed "s/^/$name round$r peer: /"
  echo "load $(cut -d' ' -f1 /proc/loadavg)"
  /tmp/cpurays/abc.sh $name 1 base | sed "s/round1/round$r/"
done
