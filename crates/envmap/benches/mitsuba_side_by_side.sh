#!/bin/sh
# Environment-map sampling throughput, brdf-lab beside Mitsuba 3 (issue 15), in one run.
#
#   sh crates/envmap/benches/mitsuba_side_by_side.sh [MAP.hdr ...]
#
# Environment: PEERS = directory of the peer scripts (mitsuba_warp_bench.py and its .venv,
# required), N = samples (default 4000000), THREADS = threads for both sides
# (default 2), BIN = the brdf-lab binary to time (default: target/release/brdf-lab, built
# here; another binary, e.g. a copy of a "before" build for interleaved A/B rounds, is
# timed as given and not built). Without maps: the built-in procedural sky only. For each map it exports the
# density Mitsuba's envmap emitter warps (luminance x sin(pi v_centre), float32 .npy), times
# Mitsuba's Hierarchical2D and DiscreteDistribution2D (--fair: uniforms drawn in the kernel,
# pdf kept; median of 5), then `brdf-lab envmap --compare` (same N, same threads), and prints
# one table row per map: the ratios of the 2-thread 'blk' column (serial xoshiro256++ per
# chunk) and of the 'lane' column (the same block path fed by the lane-parallel LaneRng).
# Mitsuba is a peer, never a dependency.
set -eu
PEERS=${PEERS:?set PEERS to the directory holding mitsuba_warp_bench.py and its .venv}
N=${N:-4000000}
THREADS=${THREADS:-2}
PY="$PEERS/.venv/bin/python"
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
# Two builds: with an --example selection cargo builds only the examples, not brdf-lab's binary.
if [ -z "${BIN:-}" ]; then
    cargo build --release -q -p brdf-lab-cli
    BIN=target/release/brdf-lab
fi
cargo build --release -q -p envmap --example export_density
EXPORT=target/release/examples/export_density
echo "load average at start: $(cut -d' ' -f1-3 /proc/loadavg)"
printf '| map | Mitsuba H2D M/s | Mitsuba D2D M/s | adaptive M/s (1 thr one / blk / lane, %s thr one / blk / lane) | envmap-cdf M/s (same) | adaptive / H2D (blk, lane) | cdf / D2D (blk, lane) | adaptive build ms | Mitsuba H2D build ms | adaptive 1->%s scaling (lane) |\n' "$THREADS" "$THREADS"
printf '|---|---|---|---|---|---|---|---|---|---|\n'
run_one() {
    name=$1
    shift
    "$EXPORT" "$TMP/d.npy" "$@" > /dev/null
    h2d=$("$PY" "$PEERS/mitsuba_warp_bench.py" --density "$TMP/d.npy" --warp hierarchical -n "$N" --repeat 5 --fair --threads "$THREADS")
    d2d=$("$PY" "$PEERS/mitsuba_warp_bench.py" --density "$TMP/d.npy" --warp discrete -n "$N" --repeat 5 --fair --threads "$THREADS")
    if [ $# -gt 0 ]; then set -- --map "$1"; fi
    ours=$(RAYON_NUM_THREADS=$THREADS "$BIN" envmap -n "$N" --compare "$@" 2>/dev/null)
    h_rate=$(echo "$h2d" | sed -n 's/^sampling: median .* = \([0-9.]*\) M samples.*/\1/p')
    d_rate=$(echo "$d2d" | sed -n 's/^sampling: median .* = \([0-9.]*\) M samples.*/\1/p')
    h_build=$(echo "$h2d" | sed -n 's/^build: \([0-9.]*\) ms/\1/p')
    # compare's last six columns: 1 thr one, 1 thr blk, T thr one, T thr blk, 1 thr lane, T thr lane
    a=$(echo "$ours" | awk '$1 == "envmap-adaptive" && $2 == "alias" { print $3, $(NF-5), $(NF-4), $(NF-1), $(NF-3), $(NF-2), $NF }')
    c=$(echo "$ours" | awk '$1 == "envmap-cdf" { print $(NF-5), $(NF-4), $(NF-1), $(NF-3), $(NF-2), $NF }')
    echo "$name $h_rate $d_rate $h_build $a $c" | awk '{
        printf "| %s | %s | %s | %s / %s / %s, %s / %s / %s | %s / %s / %s, %s / %s / %s | %.2f, %.2f | %.2f, %.2f | %s | %s | %.2f |\n",
            $1, $2, $3, $6, $7, $8, $9, $10, $11, $12, $13, $14, $15, $16, $17,
            $10 / $2, $11 / $2, $16 / $3, $17 / $3, $5, $4, $11 / $8 }'
}
run_one "procedural-sky"
for map in "$@"; do
    run_one "$(basename "$map" .hdr)" "$map"
done
echo "load average at end: $(cut -d' ' -f1-3 /proc/loadavg)"
