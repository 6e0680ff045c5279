#!/bin/bash
# Issue 41's batch (one H100): which schedule wins on paths. Four scenes
# (scenes/cornell.json; scenes/studio_path.json; the lake with glass,
# rtcl-genbench lake-path at size 10, 2.1 M triangles; scenes/materials_path.json,
# nine BSDF kinds with textures) at SIZE 1024x1024, SPP 64 (the lake LAKE_SPP
# 16); every schedule: -k naive, dynamic, persistent, persistent with
# --regenerate --fetch item, group and subgroup, wavefront --wavefront-form
# bounce and stages; -r REPEAT (5: the median kernel time of 5 after a
# warm-up), ROUNDS (2) interleaved rounds; every image compared byte for byte
# with dynamic's; in round 1 a counting run (--flops: paths per bounce, SIMD
# efficiency per phase, flops) for each schedule in COUNTED (default dynamic;
# "all" for every one, a counting build and render more a run); Mitsuba
# 3.9.1 cuda_ad_rgb, megakernel and wavefront, on the same scenes, samples and
# size (through tools/build/mitsuba_ref.py's mapping; studio_path through its
# approximations: the plane as a 1000-unit square), after round 1, at most
# MITSUBA_S (170) seconds; the registers and spills of each schedule's kernel
# on the materials scene; then tools/path_study.py over the results.
# An option this rtcl does not take (--regenerate, --fetch, --wavefront-form:
# in main since 96b81cd; an older binary lacks them) is probed first (rtcl given the options and a
# scene that does not exist answers exit status 2 for an option it does not
# take) and its schedule skipped with a line saying so; without
# --wavefront-form the wavefront runs as plain "-k wavefront" (the bounce
# form).
#
# From the repository root on the device:
#   COMMIT=<commit> bash docs/results/h100-paths-study/run.sh
# Binaries: $B (default .gpu/study41): rtcl and rtcl-meshread of COMMIT, built
# with make OIIO=0 MPI=0 BUILD=build-gpu; libraries in .gpu/lib; Mitsuba from
# $MI (default .gpu-pt/mi/mitsuba-cp312.tar.xz; MITSUBA=0 skips it). On PoCL
# (a check of the script, not a measurement):
#   OUT=/tmp/o B=. PLATFORM=0 SIZE=32x32 SPP=2 LAKE_SPP=1 LAKE_SIZE=3 REPEAT=1 \
#     MITSUBA=0 COUNTED=all bash docs/results/h100-paths-study/run.sh
# COUNT_ONLY=1 makes the counting runs alone (every schedule's unless COUNTED
# says), for a second call: copy its stats/*__counted.json beside the first
# call's and run tools/path_study.py on them together.
# Everything lands under $OUT: log.txt, paths.md, path_lengths.png and
# paths-study.tgz (the --stats files, the study, the images' checks, the work
# maps of dynamic's counting runs).
# Expected on one H100: about 300-450 s (README.md: builds, the lake's load
# and BVH in each of its 14 runs, Mitsuba's compilations); BUDGET (480 s)
# skips what is left of the timed runs and Mitsuba once spent, the study
# always runs.
set -u
ROOT=$PWD
B=${B:-$ROOT/.gpu/study41}; MI=${MI:-$ROOT/.gpu-pt/mi/mitsuba-cp312.tar.xz}
SIZE=${SIZE:-1024x1024}; SPP=${SPP:-64}; LAKE_SPP=${LAKE_SPP:-16}; LAKE_SIZE=${LAKE_SIZE:-10}
REPEAT=${REPEAT:-5}; ROUNDS=${ROUNDS:-2}; BUDGET=${BUDGET:-480}
COUNTED_GIVEN=${COUNTED:-}; COUNTED=${COUNTED:-dynamic}
MITSUBA=${MITSUBA:-1}; OUT=${OUT:?OUT must name the folder for the results}
[ -e /etc/OpenCL/vendors ] && [ -w /etc/OpenCL/vendors ] && [ -n "$(command -v nvidia-smi)" ] &&
  echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$ROOT/.gpu/lib:${LD_LIBRARY_PATH:-}
[ -x $B/rtcl-meshread ] && export RTCL_MESHREAD=$B/rtcl-meshread
RTCL=$B/rtcl
T=$(mktemp -d); S=$OUT/stats; mkdir -p $S $T/img
exec > >(tee $OUT/log.txt) 2>&1
echo "commit: ${COMMIT:-unknown}; rtcl: $RTCL"; nvidia-smi -L 2>/dev/null; date -u
P=${PLATFORM:-$($RTCL --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2; exit}')}
P=${P:-0}; DEV="-p $P -d 0"
echo "platform $P: $($RTCL --list-devices | grep -A1 "^Platform #$P" | tail -1)"

# The scenes: NAME=FILE:SAMPLES
python3 tools/genbench.py lake-path --size $LAKE_SIZE -o $T/lake > /dev/null || echo "lake-path: genbench FAILED"
SCENES="cornell=scenes/cornell.json:$SPP studio_path=scenes/studio_path.json:$SPP"
SCENES="$SCENES lake_path=$T/lake/lake-path-$LAKE_SIZE.json:$LAKE_SPP materials_path=scenes/materials_path.json:$SPP"
# ONLY="cornell materials_path": those scenes alone (a short second call).
if [ -n "${ONLY:-}" ]; then
  kept=""; for sc in $SCENES; do [[ " $ONLY " == *" ${sc%%=*} "* ]] && kept="$kept $sc"; done
  SCENES=$kept
fi

# The schedules, LABEL=options (spaces as commas), those this rtcl takes.
CANDIDATES="naive=-k,naive dynamic=-k,dynamic persistent=-k,persistent
persistent-regen-item=-k,persistent,--regenerate,--fetch,item
persistent-regen-group=-k,persistent,--regenerate,--fetch,group
persistent-regen-subgroup=-k,persistent,--regenerate,--fetch,subgroup
wavefront-bounce=-k,wavefront,--wavefront-form,bounce
wavefront-stages=-k,wavefront,--wavefront-form,stages"
SCHEDULES=""
for c in $CANDIDATES; do
  label=${c%%=*}; opts=${c#*=}; opts=${opts//,/ }
  # A scene that does not exist: rtcl reads its options (exit status 2 for
  # one it does not take or a combination it refuses) before the scene, so
  # the probe costs no program build.
  $RTCL $DEV $opts --size 8x8 --spp 1 -q -o $T/probe.pfm $T/no-such-scene.json > $T/probe.log 2>&1
  if [ $? != 2 ]; then
    SCHEDULES="$SCHEDULES $c"
  elif [ $label = wavefront-bounce ]; then
    echo "schedule $label skipped: $(head -1 $T/probe.log); plain -k wavefront (the bounce form) instead"
    SCHEDULES="$SCHEDULES wavefront=-k,wavefront"
  else
    echo "schedule $label skipped: this rtcl does not take '$opts': $(head -1 $T/probe.log)"
  fi
done
echo "schedules:$(for c in $SCHEDULES; do printf ' %s' ${c%%=*}; done)"
counted() { [ "$COUNTED" = all ] || [[ " $COUNTED " == *" $1 "* ]]; }
ms() { python3 -c "import json,sys; d=json.load(open(sys.argv[1])); print('%.2f' % d['kernel_ms'])" $1; }

run_round() {
  local round=$1
  for sc in $SCENES; do
    name=${sc%%=*}; file=${sc#*=}; spp=${file##*:}; file=${file%:*}
    for c in $SCHEDULES; do
      label=${c%%=*}; opts=${c#*=}; opts=${opts//,/ }
      if [ $SECONDS -ge $BUDGET ]; then echo "budget spent ($SECONDS s): $name $label round $round not run"; continue; fi
      count=""; [ $round = 1 ] && counted $label && count="--flops $T/flops.npy"
      # dynamic's counting run also draws the flops per pixel (log scale).
      [ -n "$count" ] && [ $label = dynamic ] &&
        count="$count --work-map $S/${name}-work.png --work-map-scale log --work-map-bar $S/${name}-work-bar.png"
      st=$S/${name}__${label}__r$round.json
      if ! timeout 120 $RTCL $DEV $opts $file --size $SIZE --spp $spp -r $REPEAT -q $count \
          -o $T/img/$name-$label.pfm --stats $st > $T/log 2>&1; then
        echo "$name $label round $round FAILED"; cat $T/log; rm -f $st; continue
      fi
      t=$(ms $st); w=${SIZE%x*}; h=${SIZE#*x}
      echo "rtcl $name $label round $round: $t ms, $(python3 -c "print('%.1f' % ($w*$h*$spp/$t/1e3))") M paths/s${count:+ (and a counting run)} [${SECONDS} s]"
    done
  done
}

# COUNT_ONLY=1: a second call for the counting runs the first could not
# afford (COUNTED, default all): -r 1 and --flops, SCENE__LABEL__counted.json,
# whose times rtcl-path-study does not use; nothing else.
if [ "${COUNT_ONLY:-0}" = 1 ]; then
  [ "$COUNTED" = dynamic ] && [ -z "${COUNTED_GIVEN:-}" ] && COUNTED=all
  for sc in $SCENES; do
    name=${sc%%=*}; file=${sc#*=}; spp=${file##*:}; file=${file%:*}
    for c in $SCHEDULES; do
      label=${c%%=*}; opts=${c#*=}; opts=${opts//,/ }
      counted $label || continue
      if [ $SECONDS -ge $BUDGET ]; then echo "budget spent ($SECONDS s): $name $label not counted"; continue; fi
      st=$S/${name}__${label}__counted.json
      timeout 120 $RTCL $DEV $opts $file --size $SIZE --spp $spp -r 1 -q --flops $T/flops.npy \
        -o $T/img/$name-$label.pfm --stats $st > $T/log 2>&1 || { echo "$name $label counting FAILED"; cat $T/log; rm -f $st; continue; }
      echo "counted $name $label [${SECONDS} s]"
    done
  done
  (cd $OUT && tar czf $T/paths-counted.tgz stats && rm -rf stats && mv $T/paths-counted.tgz .)
  echo "done in $SECONDS s"; exit 0
fi

# Round 1 (with the counting runs), Mitsuba (at most MITSUBA_S seconds), then
# the other rounds: Mitsuba's comparison is not left to what the budget spares.
run_round 1
date -u
if [ "$MITSUBA" = 1 ] && [ $SECONDS -lt $BUDGET ]; then
  mkdir -p $T/site && tar xJf $MI -C $T/site
  MS=""; for sc in $SCENES; do name=${sc%%=*}; MS="$MS $name=${sc#*=}"; done
  PYTHONPATH=$T/site timeout ${MITSUBA_S:-170} python3 docs/results/h100-paths-study/pt_mitsuba.py \
    $S/mitsuba.jsonl $SIZE $SPP $MS 2>&1 | grep -v Warning
elif [ "$MITSUBA" = 1 ]; then
  echo "budget spent ($SECONDS s): Mitsuba not run"
fi
date -u
for round in $(seq 2 $ROUNDS); do run_round $round; done
for sc in $SCENES; do
  name=${sc%%=*}
  for c in $SCHEDULES; do
    label=${c%%=*}; [ $label = dynamic ] && continue
    [ -f $T/img/$name-$label.pfm ] || continue
    cmp -s $T/img/$name-dynamic.pfm $T/img/$name-$label.pfm && echo "$name $label: same bytes as dynamic" || echo "$name $label: IMAGE DIFFERS from dynamic"
  done
done | tee $S/images.txt
# The counting runs' paths per bounce and SIMD per phase, as the summary says them.
for f in $S/*__r1.json; do python3 -c "
import json, sys
d = json.load(open(sys.argv[1]))
if 'paths' in d:
    p = d['paths']; print(sys.argv[1].split('/')[-1], 'paths', p['count'], 'mean %.3f max %d' % (p['mean_length'], p['max_length']), 'live', p['live_per_bounce'], 'simd', d.get('simd_efficiency_measured'))
" $f; done
# Registers and spills of each schedule's kernel (the materials scene: every BSDF, textures).
for c in $SCHEDULES; do
  label=${c%%=*}; opts=${c#*=}; opts=${opts//,/ }
  # A fresh build (no cache) with NVIDIA's report: ptxas's "Compiling entry",
  # "spill stores/loads" and "Used N registers" lines, one kernel to a line.
  echo "$label: $(RTCL_CACHE=0 RTCL_BUILD_OPTIONS=-cl-nv-verbose $RTCL $DEV $opts scenes/materials_path.json --size 64x64 --spp 1 -v -o $T/v.pfm 2>&1 |
    grep -oE "entry function '[a-z_0-9]+'|[0-9]+ bytes spill stores, [0-9]+ bytes spill loads|Used [0-9]+ registers" | tr '\n' ' ' | sed "s/entry function/\n    /g")"
done
date -u
python3 tools/path_study.py $S -o $OUT/study
cp $OUT/study/paths.md $OUT/ 2>/dev/null; cp $OUT/study/path_lengths.png $OUT/ 2>/dev/null
echo "done in $SECONDS s"
(cd $OUT && tar czf $T/paths-study.tgz stats study && rm -rf stats study && mv $T/paths-study.tgz .)
