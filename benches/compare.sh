#!/usr/bin/env bash
# Side-by-side timing of urdyn and Pinocchio 4.1 (C++) on the same URDFs, in one run,
# in both build flavours: generic x86-64 (urdyn release build vs pinocchio-bench
# --generic) and native (urdyn with RUSTFLAGS="-C target-cpu=native" vs --native).
# Writes benches/results.json (raw medians) and benches/results.md (table of medians
# and urdyn/Pinocchio ratios), then benches/scaling.png (benches/plot).
#
#   benches/compare.sh [--rounds R] [--samples N] [--budget SECONDS] [--flavour generic|native|both]
#
# The machine is shared and noisy (2 cores; a burst of load during one side's
# measurement moves a single ratio by ±30%), so every model is measured in R rounds
# (default 7), spread over the run: a round times every model of both flavours, each
# model by Pinocchio and then urdyn, back to back. Pinocchio's run spends its first
# ~1.5 s in Python (URDF to model) before it times anything, so this order puts the two
# timing windows next to each other (the machine's speed drifts by up to 2x over a
# few seconds, with or without load). The table reports, per model and algorithm,
# the median over rounds of each side's median and the median of the R per-round
# ratios, with their range.
#
# Environment: PINOCCHIO_BENCH (default ../shared/tools/pinocchio-bench/run beside the
# repository, or /work/shared/tools/pinocchio-bench/run).
set -euo pipefail
cd "$(dirname "$0")/.."
ROUNDS=7
SAMPLES=100
BUDGET=0.3
FLAVOURS="generic native"
while [ $# -gt 0 ]; do
  case "$1" in
    --rounds) ROUNDS="$2"; shift 2 ;;
    --samples) SAMPLES="$2"; shift 2 ;;
    --budget) BUDGET="$2"; shift 2 ;;
    --flavour) FLAVOURS="$2"; [ "$2" = both ] && FLAVOURS="generic native"; shift 2 ;;
    *) echo "compare.sh: unknown option $1" >&2; exit 2 ;;
  esac
done
PIN="${PINOCCHIO_BENCH:-}"
if [ -z "$PIN" ]; then
  for c in ../shared/tools/pinocchio-bench/run /work/shared/tools/pinocchio-bench/run; do
    [ -x "$c" ] && PIN="$c" && break
  done
fi
[ -n "$PIN" ] || { echo "compare.sh: pinocchio-bench not found (set PINOCCHIO_BENCH)" >&2; exit 1; }

python3 benches/gen_models.py
# generic: the baseline x86-64 build (an empty RUSTFLAGS overrides the
# target-cpu=native of .cargo/config.toml)
RUSTFLAGS="" cargo build --release --quiet --bin urdyn --target-dir target/generic
if [[ " $FLAVOURS " == *" native "* ]]; then
  RUSTFLAGS="-C target-cpu=native" cargo build --release --quiet --bin urdyn --target-dir target/native
fi

# name | urdf | flags | pinocchio? (mimic robots are timed by urdyn alone)
ROBOTS=(
  "ur5|assets/robots/ur5.urdf||yes"
  "kinova|assets/robots/kinova.urdf||yes"
  "solo12|assets/robots/solo12.urdf|--floating-base|yes"
  "anymal|assets/robots/anymal.urdf|--floating-base|yes"
  "talos_reduced|assets/robots/talos_reduced.urdf|--floating-base|yes"
  "panda (mimic)|assets/robots/panda.urdf||no"
)
for n in 5 10 20 50 100 200 500 1000; do ROBOTS+=("chain_$n|assets/synthetic/chain_$n.urdf||yes"); done
for d in 4 6 8; do ROBOTS+=("tree_$d|assets/synthetic/tree_$d.urdf||yes"); done

OUT=target/compare
rm -rf "$OUT"; mkdir -p "$OUT"
bench_urdyn() { # flavour key urdf flags round
  local bin=target/generic/release/urdyn
  [ "$1" = native ] && bin=target/native/release/urdyn
  # shellcheck disable=SC2086
  "$bin" bench "$3" $4 --json --samples "$SAMPLES" --budget "$BUDGET" 2>/dev/null \
    >"$OUT/$1.$2.urdyn.r$5.json"
}
bench_pin() { # flavour key urdf flags round
  # shellcheck disable=SC2086
  "$PIN" "$(pwd)/$3" $4 --json --"$1" --samples "$SAMPLES" --budget "$BUDGET" 2>/dev/null \
    >"$OUT/$1.$2.pinocchio.r$5.json"
}
for round in $(seq 1 "$ROUNDS"); do
  echo "round $round start $(date -u +%H:%M) $(cut -d' ' -f1-3 /proc/loadavg)" >>"$OUT/load.txt"
  for flavour in $FLAVOURS; do
    for entry in "${ROBOTS[@]}"; do
      IFS='|' read -r name urdf flags pin <<<"$entry"
      key="${name%% *}"
      echo "[round $round/$ROUNDS, $flavour] $name" >&2
      [ "$pin" = yes ] && bench_pin "$flavour" "$key" "$urdf" "$flags" "$round"
      bench_urdyn "$flavour" "$key" "$urdf" "$flags" "$round"
    done
  done
done
echo "end $(date -u +%H:%M) $(cut -d' ' -f1-3 /proc/loadavg)" >>"$OUT/load.txt"
python3 benches/make_table.py "$OUT" benches/results.json benches/results.md
if cargo build --release --quiet --manifest-path benches/plot/Cargo.toml 2>/dev/null; then
  benches/plot/target/release/urdyn-plot benches/results.json benches/scaling.png
else
  echo "compare.sh: plot crate did not build; scaling.png not redrawn" >&2
fi
