#!/bin/bash
# GPU batch 31 (issue 23, the host in folders, a job and a record, one
# pipeline): images, flop counts and kernel times before (41af480, the
# session's start: rtcl-41af480) and after ($COMMIT: rtcl). Every kernel on
# the default scene (paper60, 2000x2000... its own size) and glass_mesh;
# three interleaved rounds of -r 10; each image and each --flops file of
# one binary compared byte for byte with the other's; an animation
# (--frames 0:2) and one image over the GPU and the CPU (--devices) too.
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
export RTCL_MESHREAD=$PWD/.gpu/rtcl-meshread
G=$PWD/.gpu; T=$(mktemp -d)
echo "commit: $COMMIT (rtcl), 41af480 (rtcl-41af480)"; nvidia-smi -L
P=$($G/rtcl --list-devices | awk '/^Platform/ && /NVIDIA/ {sub("#","",$2); sub(":","",$2); print $2}')
C=$($G/rtcl --list-devices | awk '/^Platform/ && /Portable/ {sub("#","",$2); sub(":","",$2); print $2}')
echo "NVIDIA platform $P, PoCL platform $C"
ms() { python3 -c 'import json,sys; print("%.4f" % json.load(open(sys.argv[1]))["kernel_ms"])' "$1"; }
same() { cmp -s "$1" "$2" && echo same || echo DIFFERENT; }
KERNELS="naive cyclic dynamic persistent wavefront serial"
SCENES="paper60 glass_mesh"
scene_args() { [ "$1" = paper60 ] && echo "" || echo "-s scenes/$1.json"; }
echo "== images and flop counts, before against after"
for s in $SCENES; do
  for k in $KERNELS; do
    size=""; [ $k = serial ] && size="--size 200x200"
    for b in rtcl-41af480 rtcl; do
      $G/$b -p $P -k $k $size $(scene_args $s) -o $T/$b.ppm -q --flops $T/$b.npy \
        || echo "FAILED: $b $k $s"
    done
    printf "  %-11s %-10s image %s, flops %s, sidecar %s\n" $s $k \
      "$(same $T/rtcl-41af480.ppm $T/rtcl.ppm)" "$(same $T/rtcl-41af480.npy $T/rtcl.npy)" \
      "$(cmp -s <(grep -v '"gflops"\|"mrays_per_s"' $T/rtcl-41af480.npy.json) \
                <(grep -v '"gflops"\|"mrays_per_s"' $T/rtcl.npy.json) && echo same || echo DIFFERENT)"
  done
done
for b in rtcl-41af480 rtcl; do
  mkdir -p $T/f-$b
  $G/$b -p $P -k dynamic --frames 0:2 --size 400x300 -o $T/f-$b/f.ppm -q || echo "FAILED frames $b"
  $G/$b --devices $P:0,$C:0 -k dynamic --size 400x300 -o $T/d-$b.ppm -q || echo "FAILED devices $b"
done
for f in 0000 0001 0002; do echo "  frames f_$f.ppm $(same $T/f-rtcl-41af480/f_$f.ppm $T/f-rtcl/f_$f.ppm)"; done
echo "  GPU+CPU image $(same $T/d-rtcl-41af480.ppm $T/d-rtcl.ppm)"
echo "== kernel times (ms, median of -r 10), three interleaved rounds"
for round in 1 2 3; do
  for s in $SCENES; do
    for k in naive cyclic dynamic persistent wavefront; do
      for b in rtcl-41af480 rtcl; do
        $G/$b -p $P -k $k -r 10 $(scene_args $s) -o $T/x.ppm -q --stats $T/st.json
        printf "  round %s %-12s %-11s %-10s %s\n" $round $b $s $k "$(ms $T/st.json)"
      done
    done
  done
done
