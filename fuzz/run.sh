#!/usr/bin/env bash
# Fuzzes urdyn for a fixed time per target (outside CI): libFuzzer via
# libfuzzer-sys, built with the nightly toolchain and cargo-fuzz's coverage flags
# (no cargo-fuzz binary needed). Seeds come from tests/bad, tests/urdf, assets and
# the fixture states. Crashes land in fuzz/artifacts/TARGET/; each one found must
# become a file in tests/bad with a test.
#
# Usage: fuzz/run.sh [SECONDS_PER_TARGET (default 180)] [TARGET...]
# (targets: urdf_eval states_eval scene_load mjcf_load; default the first two)
set -euo pipefail
cd "$(dirname "$0")"
SECS=${1:-180}
shift || true
TARGETS=("$@")
[ ${#TARGETS[@]} -eq 0 ] && TARGETS=(urdf_eval states_eval)

export RUSTFLAGS="-Cpasses=sancov-module -Cllvm-args=-sanitizer-coverage-level=4 \
-Cllvm-args=-sanitizer-coverage-inline-8bit-counters -Cllvm-args=-sanitizer-coverage-pc-table \
-Cllvm-args=-sanitizer-coverage-trace-compares --cfg fuzzing -Cdebug-assertions -Coverflow-checks"
# --target keeps the instrumentation off build scripts and proc macros.
TRIPLE=$(rustc +nightly -vV | sed -n "s/^host: //p")
cargo +nightly build --release --target-dir target --target "$TRIPLE" --bins

mkdir -p seeds/urdf_eval seeds/states_eval seeds/scene_load seeds/mjcf_load logs
for f in ../tests/bad/*.urdf ../tests/urdf/*.urdf ../assets/*.urdf ../assets/robots/*.urdf; do
    [ -f "$f" ] || continue
    # 8 bytes of state seed (bit 1: floating base), then the URDF.
    { printf '\001\000\000\000\000\000\000\000'; cat "$f"; } > "seeds/urdf_eval/fixed_$(basename "$f")"
    { printf '\003\000\000\000\000\000\000\000'; cat "$f"; } > "seeds/urdf_eval/float_$(basename "$f")"
done
for f in ../tests/bad/states_* ; do cp "$f" seeds/states_eval/; done
# scene files: the bad corpus and the assets' scenes (relative to assets/: the
# target loads them there, so "lamp.urdf" resolves)
for f in ../tests/bad/scene/*.json ../assets/*.json; do
    [ -f "$f" ] && sed 's#\.\./\.\./\.\./assets/##g' "$f" > "seeds/scene_load/$(basename "$f")"
done
# MJCF: the bad corpus, the committed Gymnasium and dm_control models and the
# synthetic ones (the target reads includes under tests/fixtures/mjcf/dm_control)
for f in ../tests/bad/mjcf/*.xml ../tests/fixtures/mjcf/*/*.xml ../tests/fixtures/mjcf/dm_control/common/*.xml; do
    [ -f "$f" ] && cp "$f" "seeds/mjcf_load/$(basename "$(dirname "$f")")_$(basename "$f")"
done
for d in ../tests/fixtures/*/; do
    [ -f "$d/states.json" ] && cp "$d/states.json" "seeds/states_eval/$(basename "$d").json"
done

for t in "${TARGETS[@]}"; do
    mkdir -p "corpus/$t" "artifacts/$t"
    echo "== $t for ${SECS}s"
    ./target/"$TRIPLE"/release/"$t" "corpus/$t" "seeds/$t" \
        -max_total_time="$SECS" -max_len=262144 -timeout=10 -rss_limit_mb=2048 \
        -artifact_prefix="artifacts/$t/" -print_final_stats=1 > "logs/$t.log" 2>&1 || true
    grep -E "stat::number_of_executed_units|stat::average_exec_per_sec|ERROR|SUMMARY|Test unit written" "logs/$t.log" || true
    echo "artifacts: $(ls "artifacts/$t" | wc -l)"
done
