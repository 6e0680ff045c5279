#!/bin/bash
# Issue 41, item 1 (one H100, nvidia-h100-x1): path regeneration in the
# persistent kernel and its work counter schemes, against the megakernels.
# scenes/cornell.json and scenes/studio_path.json (glass, rough glass,
# textures, an environment map) at 1024x1024, 64 spp: -k persistent with and
# without --regenerate x --fetch item|group|subgroup x --batch 1|4, and -k
# dynamic and -k naive as baselines; -r 5 (median kernel time of 5 after a
# warm-up), two interleaved rounds, M paths/s = pixels x spp / kernel time;
# every image compared with dynamic's by cmp. Then the registers and spills
# of the main variants (ptxas through -cl-nv-verbose, an uncached build),
# and a counting run (--flops) of four schedules at 512x512, 16 spp: flops
# (must agree), rays, and the SIMD efficiency measured per phase (the
# intersection steps and the traversal steps: does regeneration fill the
# warps, and what it does to traversal's coherence).
#
# Binaries: rtcl and rtcl-meshread built from the branch at COMMIT with
#   make OIIO=0 MPI=0 BUILD=build-gpu && mkdir -p .gpu/regen41 &&
#   cp rtcl build-gpu/rtcl-meshread .gpu/regen41/ && git rev-parse --short HEAD > .gpu/regen41/COMMIT
# libraries in .gpu/lib. Run from the repository root (scenes/ and its
# models are read from there):
#   bash docs/results/h100-regen/run.sh            # carry .gpu/regen41 and .gpu/lib
# About 5-6 minutes on an H100 (estimated from batch 98: a program build 3.6 s,
# 28 of them in the first round and 16 more after; a cornell frame 110 ms).
# SCENES="cornell" halves it; EXTRA=0 leaves out the registers and the
# counting runs (about 70 s).
# On PoCL, to check the script: SIZE=32x32 SPP=4 SIMD_SIZE=16x16 bash docs/results/h100-regen/run.sh
set -u
ROOT=$PWD
G=${G:-$ROOT/.gpu/regen41}
[ -e /etc/OpenCL/vendors/nvidia.icd ] || { [ -w /etc/OpenCL/vendors ] && echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd; }
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$ROOT/.gpu/lib:${LD_LIBRARY_PATH:-}
export RTCL_MESHREAD=$G/rtcl-meshread
export XDG_CACHE_HOME=$(mktemp -d) # programs built from this commit, none cached from before
OUT=${OUT:-$(mktemp -d)}
SIZE=${SIZE:-1024x1024}; SPP=${SPP:-64}; SIMD_SIZE=${SIMD_SIZE:-512x512}
SCENES=${SCENES:-cornell studio_path}; EXTRA=${EXTRA:-1}
T=$(mktemp -d); S=$OUT/stats; mkdir -p $S
exec > >(tee $OUT/regen.txt) 2>&1
echo "commit: $(cat $G/COMMIT 2>/dev/null || echo unknown)"; nvidia-smi -L 2>/dev/null; nproc; date -u
P=$($G/rtcl --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
P=${P:-0}
echo "platform $P; size $SIZE, $SPP spp"
RT="$G/rtcl -p $P -d 0"
PIX=$(python3 -c "w, h = '$SIZE'.split('x'); print(int(w) * int(h) * $SPP)")
ms() { python3 -c "import json,sys; d=json.load(open(sys.argv[1])); print('%.2f' % d['kernel_ms'])" $1; }

# tag: the options after -k
declare -A OPTS=([naive]="-k naive" [dynamic]="-k dynamic")
TAGS="naive dynamic"
for regen in 0 1; do
  for f in item group subgroup; do
    for b in 1 4; do
      tag=$([ $regen = 1 ] && echo regen || echo persistent)-$f-b$b
      OPTS[$tag]="-k persistent --fetch $f --batch $b$([ $regen = 1 ] && echo ' --regenerate')"
      TAGS="$TAGS $tag"
    done
  done
done

for sc in $SCENES; do
  $RT scenes/$sc.json --size $SIZE --spp 4 -q -o $T/prime.ppm 2>&1 | tail -3
  for round in 1 2; do
    for tag in $TAGS; do
      timeout 300 $RT ${OPTS[$tag]} scenes/$sc.json --size $SIZE --spp $SPP -r 5 -q \
        -o $T/$sc-$tag.pfm --stats $S/$sc-$tag-$round.json > $T/log 2>&1 ||
        { echo "$sc $tag round $round FAILED"; cat $T/log; continue; }
      t=$(ms $S/$sc-$tag-$round.json)
      echo "$sc $tag round $round: $t ms, $(python3 -c "print('%.1f' % ($PIX / $t / 1e3))") M paths/s"
    done
  done
  for tag in $TAGS; do
    [ $tag = dynamic ] && continue
    cmp -s $T/$sc-dynamic.pfm $T/$sc-$tag.pfm && echo "$sc $tag: same bytes as dynamic" ||
      echo "$sc $tag: IMAGE DIFFERS from dynamic"
  done
done
date -u

echo "== the table: median of -r 5 per round, M paths/s of the faster round"
python3 - "$S" "$PIX" "$SCENES" $TAGS <<'EOF'
import json, os, sys
stats, pix, scenes, tags = sys.argv[1], int(sys.argv[2]), sys.argv[3].split(), sys.argv[4:]
for sc in scenes:
    def ms(tag, r):
        p = os.path.join(stats, f"{sc}-{tag}-{r}.json")
        return json.load(open(p))["kernel_ms"] if os.path.exists(p) else None
    base = {t: min(x for x in (ms(t, 1), ms(t, 2)) if x) for t in ("dynamic", "persistent-item-b1")
            if ms(t, 1) or ms(t, 2)}
    print(f"\n{sc}\n| schedule | round 1 ms | round 2 ms | M paths/s | / dynamic | / persistent item b1 |")
    print("|---|---|---|---|---|---|")
    for t in tags:
        a, b = ms(t, 1), ms(t, 2)
        if not (a or b):
            print(f"| {t} | failed | | | | |")
            continue
        best = min(x for x in (a, b) if x)
        rel = lambda k: "%.3f" % (base[k] / best) if k in base else ""
        print(f"| {t} | {a or '-'} | {b or '-'} | {pix / best / 1e3:.1f} | {rel('dynamic')}× | "
              f"{rel('persistent-item-b1')}× |")
EOF

if [ "$EXTRA" = 1 ]; then
echo "== registers and spills (ptxas via -cl-nv-verbose, uncached builds, 64x64)"
for sc in $SCENES; do
  for tag in dynamic persistent-item-b1 regen-item-b1 regen-subgroup-b1; do
    echo "-- $sc $tag"
    RTCL_CACHE=0 RTCL_BUILD_OPTIONS=-cl-nv-verbose timeout 120 $RT ${OPTS[$tag]} scenes/$sc.json \
      --size 64x64 --spp $SPP -v -o $T/v.ppm 2>&1 |
      grep -iE "ptxas|registers|spill|stack|lmem" | grep -iE "render|used|spill|stack" | head -6
  done
done
date -u

echo "== counting runs (--flops): $SIMD_SIZE, 16 spp; flops must agree; SIMD efficiency measured"
for sc in $SCENES; do
  for tag in dynamic persistent-item-b1 regen-item-b1 regen-subgroup-b1; do
    timeout 200 $RT ${OPTS[$tag]} scenes/$sc.json --size $SIMD_SIZE --spp 16 -q -o $T/c.pfm \
      --flops $T/c.npy --stats $S/$sc-$tag-count.json > $T/log 2>&1 ||
      { echo "$sc $tag counting FAILED"; cat $T/log; continue; }
    python3 -c "
import json, sys
d = json.load(open(sys.argv[1])); m = d.get('simd_efficiency_measured')
simd = ('intersect %.3f, traversal %.3f, both %.3f' % (m['intersect'], m['traversal'], m['both'])
        if isinstance(m, dict) else m)
print('$sc $tag: flops %d, rays %d, par. eff. %.3f, model %s; SIMD measured: %s' % (
    d['total_flops'], d['rays'], d.get('parallel_efficiency', float('nan')),
    '%.3f' % d['simd_efficiency_model'] if 'simd_efficiency_model' in d else '-', simd))" \
      $S/$sc-$tag-count.json
  done
done
date -u
fi
# Everything under $OUT as one archive (at most 8 files come back)
(cd $OUT && tar czf /tmp/regen41.tgz . && rm -rf ./* && mv /tmp/regen41.tgz .)
