#!/usr/bin/env bash
# Frame times under machine noise: runs tools/sweeps/timing-order.toml (four configurations
# with the same run-time work) RUNS times with one core busy 2 s, idle 2 s beside it, and
# prints each run's median GPU frame times and the largest over the smallest. Times that
# agree (a ratio near 1) mean the noise fell on every configuration alike.
#   bash tools/timing-order.sh OUT [RELUME] [RUNS]
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:?usage: bash tools/timing-order.sh OUT [RELUME] [RUNS]}
relume=${2:-./target/release/relume}
runs=${3:-3}
mkdir -p "$out"
( while true; do timeout 2 sh -c 'while :; do :; done' || true; sleep 2; done ) &
load=$!
trap 'kill $load 2>/dev/null || true' EXIT
for i in $(seq 1 "$runs"); do
    echo "timing-order: run $i of $runs (a bench of four obscurance configurations, about a minute)"
    "$relume" bench tools/sweeps/timing-order.toml --out "$out/run-$i" --cache "$out/cache" > "$out/run-$i.log"
    awk -F, 'NR == 1 { for (c = 1; c <= NF; c++) if ($c == "gpu_frame_ms") col = c; next }
        { ms[NR] = $col; if (min == "" || $col < min) min = $col; if ($col > max) max = $col }
        END { printf "run %d: median GPU ms", run; for (r = 2; r <= NR; r++) printf " %.1f", ms[r]; printf "; largest/smallest %.3f\n", max / min }' \
        run="$i" "$out/run-$i/results.csv"
done
