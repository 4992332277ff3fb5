#!/usr/bin/env bash
# Constrained dynamics and its derivatives, urdyn against Pinocchio 4.1 (C++, -march=native),
# side by side in one run on the same machine (issue 28, cli.md `bench` additions):
# solo12 with its four feet held (`--hold`, CONTACT_3D) and talos_reduced with both
# soles held (`--hold6`, CONTACT_6D). Writes benches/constraint_results.md.
# Usage: benches/constraint_compare.sh [SAMPLES]
set -euo pipefail
cd "$(dirname "$0")/.."
SAMPLES=${1:-300}
URDYN=target/release/urdyn
PIN=${PINOCCHIO_BENCH:-/work/shared/tools/pinocchio-bench/run}
[ -x "$URDYN" ] || cargo build --release
OUT=benches/constraint_results.md
ALGOS=(--algo constraint-dynamics --algo constraint-dynamics-derivatives --algo aba-derivatives)
{
  echo "# Constrained dynamics: urdyn vs Pinocchio 4.1 (median ns, one run, $(date -u +%F))"
  echo
  echo "| robot | constraints | algorithm | urdyn | Pinocchio | ratio |"
  echo "|---|---|---|---|---|---|"
} > "$OUT"
run_case() {
  local label=$1 urdf=$2 pinurdf=$3; shift 3
  local cons=("$@")
  local u p
  u=$($URDYN bench "$urdf" --floating-base "${cons[@]}" "${ALGOS[@]}" --samples "$SAMPLES" --json)
  p=$($PIN "$pinurdf" --floating-base "${cons[@]}" "${ALGOS[@]}" --samples "$SAMPLES" --json)
  python3 - "$label" "${cons[*]}" "$u" "$p" >> "$OUT" <<'PY'
import json, sys
label, cons, u, p = sys.argv[1], sys.argv[2], json.loads(sys.argv[3]), json.loads(sys.argv[4])
pr = p.get("results", p)
for algo in ("constraint-dynamics", "constraint-dynamics-derivatives", "aba-derivatives"):
    a = u["results"][algo]["median_ns"]
    b = pr[algo]["median_ns"]
    print(f"| {label} (nv {u['nv']}) | `{cons}` | {algo} | {a:.0f} | {b:.0f} | {a / b:.2f} |")
PY
}
run_case solo12 assets/robots/solo12.urdf solo_description/robots/solo12.urdf \
  --hold FL_FOOT --hold FR_FOOT --hold HL_FOOT --hold HR_FOOT
run_case talos_reduced assets/robots/talos_reduced.urdf talos_data/robots/talos_reduced.urdf \
  --hold6 left_sole_link --hold6 right_sole_link
echo >> "$OUT"
echo "urdyn's talos_reduced reduces its gripper mimic joints (nv 32 + 6); Pinocchio's URDF parser makes them independent joints." >> "$OUT"
cat "$OUT"
