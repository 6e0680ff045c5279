#!/bin/bash
# tree.sh NAME ROUNDS: rtcl-rays built with the tree's settings changed (BVH_TRIANGLE_COST 6, BVH_MAX_LEAF 4) against build/, interleaved
for r in $(seq $2); do for b in build:/work/wt/cpurays/build t6:/tmp/cpurays/build-t6 l4:/tmp/cpurays/build-l4; do
  TAG=${b%%:*}- RAYS=${b#*:}/rtcl-rays /tmp/cpurays/abc.sh $1 1 base | sed "s/round1/round$r/"
done; done
