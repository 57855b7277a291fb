#!/usr/bin/env bash
# Seeds the fuzz corpora from assets/ and small generated projects, then fuzzes the loaders:
# projects, .vox, Qubicle .qb, Sponge .schem and heightmap PNGs.
# Usage: app/fuzz/run.sh [seconds per target, default 600]. Needs `cargo install cargo-fuzz`
# and a nightly toolchain (cargo fuzz uses sanitizer flags).
set -euo pipefail
cd "$(dirname "$0")"
seconds=${1:-600}
root=../..
mkdir -p corpus/project_ron corpus/vox_import corpus/qb_import corpus/schem_import corpus/heightmap
cp "$root"/assets/vox/*.vox seeds/vox_import/*.vox corpus/vox_import/
cp "$root"/assets/qb/*.qb seeds/qb_import/*.qb corpus/qb_import/
cp "$root"/assets/schem/*.schem corpus/schem_import/
cp "$root"/assets/vox/*.png corpus/heightmap/ 2>/dev/null || true
cargo build --release --manifest-path "$root/Cargo.toml" -p app --bin voxbrick -q
voxbrick=$root/target/release/voxbrick
"$voxbrick" new --terrain --size 16x16x16 --water-level 6 --height-min 2 --height-max 12 corpus/project_ron/terrain.ron 2>/dev/null
"$voxbrick" convert "$root/assets/vox/mmmm_chr_robot.vox" corpus/project_ron/robot.ron 2>/dev/null
"$voxbrick" convert "$root/assets/vox/dotvox_metal-material.vox" corpus/project_ron/metal.ron 2>/dev/null
"$voxbrick" new --terrain --size 32x16x32 corpus/heightmap/t.ron 2>/dev/null
"$voxbrick" render corpus/heightmap/t.ron --device cpu --spp 1 --width 32 --height 24 --out corpus/heightmap/grey.png 2>/dev/null || true
rm -f corpus/heightmap/t.ron
for target in ${TARGETS:-project_ron vox_import qb_import schem_import heightmap}; do
    # A crash stops that target only (its input is in artifacts/$target); the others still run.
    cargo +nightly fuzz run --fuzz-dir . "$target" "corpus/$target" -- \
        -max_total_time="$seconds" -rss_limit_mb=4096 -timeout=20 -print_final_stats=1 2>&1 | tail -25 ||
        echo "$target: the fuzzer stopped on a finding (see artifacts/$target)"
done
