#!/bin/bash
# 16384² finished pictures on the lent card's host: a base binary against a new one (8- and
# 16-bit PNG, 4 spp, the thesis scene), wall time and file size. Carry .device with the debs
# and the stripped binaries as .device/vb-base and .device/vb-new (see ../shared/device);
# run from the checkout: bash tests/tools/big_picture.sh
R=$PWD
for f in .device/debs/*.deb; do dpkg -x $f / >/dev/null; done; ldconfig
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader
echo "cores $(nproc)"
cd /tmp
$R/.device/vb-new new --thesis thesis.ron > /dev/null
for b in new base; do $R/.device/vb-$b render thesis.ron --out warm.png --width 1024 --height 576 --spp 4 > /dev/null; done
run() { # binary, label, extra args
  local t0=$(date +%s.%N)
  $R/.device/vb-$1 render thesis.ron --out big-$1-$2.png --width 16384 --height 16384 --spp 4 ${@:3} > log-$1-$2.txt 2>&1
  local rc=$?
  local t1=$(date +%s.%N)
  echo "$1 $2 rc $rc wall $(awk "BEGIN{print $t1 - $t0}") s size $(stat -c %s big-$1-$2.png) bytes :: $(tail -2 log-$1-$2.txt | tr '\n' ' ')"
  rm -f big-$1-$2.png
}
run base png8
run new png8
run new png16 --png16
run base png16 --png16
