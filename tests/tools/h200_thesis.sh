#!/usr/bin/env bash
# Run on the lent H200 with .device/ carried (the loader packages and a stripped release
# voxbrick beside this script's copy in .device/): bash .device/h200_thesis.sh
# The thesis complexities on the H200 (bench-gpu medians after warm-up), twice back to back.
set -u
for f in .device/debs/*.deb; do dpkg -x $f /; done; ldconfig
nvidia-smi --query-gpu=name,driver_version,clocks.sm --format=csv > $OUT/gpu.txt
for k in 1 2; do
  ./.device/voxbrick bench-gpu --frames 200 > $OUT/bench_gpu_$k.txt 2>&1
done
./.device/voxbrick stress --rays 20000 --size 64 --renders 8 --cpu-size 8 --cpu-renders 1 > $OUT/stress.txt 2>&1; echo "stress rc=$?" >> $OUT/stress.txt
cd $OUT && tar czf /tmp/r.tgz . && rm -rf $OUT/* && mv /tmp/r.tgz $OUT/
