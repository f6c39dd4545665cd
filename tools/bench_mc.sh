#!/usr/bin/env bash
# Monte Carlo performance benchmark (docs/monte-carlo.md, "Performance").
#
#   tools/bench_mc.sh [CAMPAIGN] [RUNS]
#
# 1. `helicon bench --json`: derivative, one closed-loop step, real-time factor.
# 2. The campaign (default campaigns/robustness-10.toml: 20 s flights with
#    sensors, q-method + fusion and the state estimator in the loop, thesis
#    wind, 25 dispersed parameters) with RUNS runs (default 1000), on 1 thread
#    and on 2 threads: wall time of the whole command (flights, statistics,
#    plots), simulated flight time actually flown (runs that diverge stop
#    early), speed-up, and a check that both runs.csv files are identical.
set -euo pipefail
cd "$(dirname "$0")/.."
CAMPAIGN=${1:-campaigns/robustness-10.toml}
RUNS=${2:-1000}
cargo build --release -q -p helicon-cli
BIN=target/release/helicon
OUT=$(mktemp -d)
trap 'rm -rf "$OUT"' EXIT

echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs)"
echo "load:    $(cut -d' ' -f1-3 /proc/loadavg) (1/5/15 min; other work on the machine slows the figures below)"
echo "bench:   $($BIN bench --json)"

wall() { # threads -> "wall_s cpu_percent"
  /usr/bin/time -f "%e %P" -o "$OUT/time$1" \
    "$BIN" mc "$CAMPAIGN" --runs "$RUNS" --threads "$1" --out "$OUT/t$1" 2>/dev/null
  tr -d '%' < "$OUT/time$1"
}
simulated() { # folder -> total simulated seconds, completed runs
  awk -F, 'NR==1{for(i=1;i<=NF;i++){if($i=="t_end_s")c=i; if($i=="outcome")o=i}; next}
           {s+=$c; if($o=="completed")n++} END{printf "%.0f s simulated, %d/%d runs completed", s, n, NR-1}' "$1/runs.csv"
}
read -r W2 C2 <<< "$(wall 2)"
read -r W1 C1 <<< "$(wall 1)"
cmp -s "$OUT/t1/runs.csv" "$OUT/t2/runs.csv" && SAME=identical || SAME=DIFFERENT
printf 'campaign: %s, %d runs: %s\n' "$CAMPAIGN" "$RUNS" "$(simulated "$OUT/t2")"
printf '1 thread:  %6.1f s wall (%s %% CPU)\n' "$W1" "$C1"
printf '2 threads: %6.1f s wall (%s %% CPU; below ~190 %% the machine was shared)\n' "$W2" "$C2"
printf 'speed-up:  %6.2f x   (runs.csv 1 vs 2 threads: %s)\n' "$(echo "$W1 / $W2" | bc -l)" "$SAME"
