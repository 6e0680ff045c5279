#!/bin/bash
# Per-sample cost with --spp N > 1 against N = 1 (docs/performance.md, "Why a
# sample costs more with --spp N > 1"). Builds nothing. Usage:
#   P=<platform index> BEFORE=/path/to/main/rtcl AFTER=/path/to/spp/rtcl .gpu-spp/measure.sh
# Probes need the spp branch's binary (cl/sample.cl): RTCL_PROBE_* are
# kernel macros passed with RTCL_BUILD_OPTIONS (cached per option string).
P=${P:?set P to the GPU platform index}; BEFORE=${BEFORE:?}; AFTER=${AFTER:?}
S=${S:-2000x2000}
t() { "$@" -o /tmp/x.ppm 2>&1 | grep -E '^time:' | head -1; }
nvidia-smi --query-gpu=name,clocks.sm,clocks.max.sm,power.draw --format=csv,noheader
for round in 1 2 3; do
	for K in dynamic persistent naive; do
		for N in 1 2 4; do
			echo "$round before $K spp $N: $(t "$BEFORE" -p $P -k $K --size $S -r 10 --spp $N)"
			echo "$round after  $K spp $N: $(t "$AFTER" -p $P -k $K --size $S -r 10 --spp $N)"
		done
		for probe in "-DRTCL_PROBE_SAMPLE_WORK" "-DRTCL_PROBE_JITTER" \
			     "-DRTCL_PROBE_JITTER -DRTCL_PROBE_SHIFT"; do
			echo "$round after  $K spp 1 $probe: $(RTCL_BUILD_OPTIONS="$probe" t "$AFTER" -p $P -k $K --size $S -r 10 --spp 1)"
		done
		# 1000x1000: one pass holds 4 samples (render_pass_samples), the loop in the kernel
		echo "$round after  $K 1000x1000 spp 1: $(t "$AFTER" -p $P -k $K --size 1000x1000 -r 10 --spp 1)"
		echo "$round after  $K 1000x1000 spp 4 (1 pass): $(t "$AFTER" -p $P -k $K --size 1000x1000 -r 10 --spp 4)"
	done
done
nvidia-smi --query-gpu=name,clocks.sm,clocks.max.sm,power.draw --format=csv,noheader
