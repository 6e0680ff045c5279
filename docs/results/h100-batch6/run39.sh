#!/bin/bash
# GPU batch 39 (issue 25, correctness): test/test_simd_measured.py, the measured
# SIMD efficiency at its two ends (serial: 1/32; a scene of misses in full
# warps: 100 %), run as a script (no pytest on the GPU machine).
set -u
echo libnvidia-opencl.so.1 > /etc/OpenCL/vendors/nvidia.icd
export LD_LIBRARY_PATH=/usr/local/nvidia/lib64:$PWD/.gpu/lib:${LD_LIBRARY_PATH:-}
echo "commit: $COMMIT"; nvidia-smi -L
RTCL=$PWD/.gpu/rtcl python3 test/test_simd_measured.py; echo "exit status $?"
