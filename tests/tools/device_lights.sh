#!/usr/bin/env bash
# Issue 52, item 3, on a lent GPU with .device/ carried (the loader packages from
# ../shared/device and a stripped release voxbrick as .device/voxbrick):
#   cp tests/tools/device_lights.sh .device/ && bash .device/device_lights.sh
# `bench-gpu --lights` (light tree against BSDF only in the lamp room, thesis + lamps + sun and
# the city at night; GPU time by timestamp queries, relMSE against a 1024-spp reference) for:
#   0       8-wide descent (the renderer)
#   262144  8-wide descent with the light visibility cache (experiment bit 18)
#   131072  binary descent (the estimator before stop 57)
#   266240  the cache with one sun-or-faces choice per subgroup (bits 18 and 12)
# Each run writes its own file; one archive comes back even if a run times out.
set -u
cd "$(dirname "$0")/.."
for f in .device/debs/*.deb; do dpkg -x "$f" /; done; ldconfig
nvidia-smi --query-gpu=name,driver_version,clocks.sm,clocks.max.sm --format=csv > "$OUT/gpu.txt"
mkdir -p "$OUT/r"
pack() { (cd "$OUT" && tar czf /tmp/r.tgz gpu.txt r && rm -rf "$OUT/r" && mv /tmp/r.tgz "$OUT/"); }
trap pack EXIT
run() {
    local name=$1
    shift
    local t0=$SECONDS
    timeout "${T:-100}" ./.device/voxbrick "$@" > "$OUT/r/$name.txt" 2>&1
    echo "rc $? $((SECONDS - t0)) s" | tee -a "$OUT/r/$name.txt"
    grep -E "median|steady|edit:" "$OUT/r/$name.txt" | tail -9
}
for x in 0 262144 131072 266240; do
    run "lights-$x" bench-gpu --lights --reference-spp 1024 --experiment "$x"
done
