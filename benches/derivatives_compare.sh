#!/usr/bin/env bash
# Side-by-side timing of the derivatives of the dynamics: urdyn against Pinocchio 4.1 (C++),
# native build on both sides (urdyn's default release build, target-cpu=native through
# .cargo/config.toml; pinocchio-bench --native),
# in one run. Algorithms (same names on both sides):
#   rnea-derivatives   ∂τ/∂q, ∂τ/∂v (and M): Pinocchio's computeRNEADerivatives(q, v, a)
#   aba-derivatives    ∂q̈/∂q, ∂q̈/∂v, M⁻¹: Pinocchio's computeABADerivatives(q, v, tau)
#   jacobians          every joint's/body's world Jacobian: Pinocchio's computeJointJacobians(q)
# Robots: ur5 (fixed), solo12, talos_reduced and g1_29dof_rev_1_0 (floating) and chain_100
# (benches/gen_models.py). Writes benches/derivatives_results.md (and the raw JSON of every
# run under target/derivatives_compare/).
#
#   benches/derivatives_compare.sh [--rounds R] [--samples N] [--budget SECONDS]
#
# As benches/compare.sh: the machine is shared and noisy, so every robot is measured in R
# rounds (default 7) spread over the run, each round timing every robot by Pinocchio and
# then urdyn right after it (Pinocchio's run spends its first ~1.5 s in Python before it
# times anything, so the two timing windows are adjacent). The table gives, per robot and
# algorithm, the median over rounds of each side's median ns per call, and the median of the
# R per-round ratios urdyn/Pinocchio with their range.
#
# Environment: PINOCCHIO_BENCH (default ../shared/tools/pinocchio-bench/run beside the
# repository, or /work/shared/tools/pinocchio-bench/run); ERD_ROBOTS, example-robot-data's
# robots/ folder for g1 (default: found through the python3 that has example_robot_data,
# or /work/venv's).
set -euo pipefail
cd "$(dirname "$0")/.."
ROUNDS=7
SAMPLES=100
BUDGET=0.3
while [ $# -gt 0 ]; do
  case "$1" in
    --rounds) ROUNDS="$2"; shift 2 ;;
    --samples) SAMPLES="$2"; shift 2 ;;
    --budget) BUDGET="$2"; shift 2 ;;
    *) echo "derivatives_compare.sh: unknown option $1" >&2; exit 2 ;;
  esac
done
PIN="${PINOCCHIO_BENCH:-}"
if [ -z "$PIN" ]; then
  for c in ../shared/tools/pinocchio-bench/run /work/shared/tools/pinocchio-bench/run; do
    [ -x "$c" ] && PIN="$c" && break
  done
fi
[ -n "$PIN" ] || { echo "derivatives_compare.sh: pinocchio-bench not found (set PINOCCHIO_BENCH)" >&2; exit 1; }
ERD="${ERD_ROBOTS:-}"
if [ -z "$ERD" ]; then
  for py in python3 /work/venv/bin/python; do
    d=$("$py" -c 'import sysconfig, pathlib; p = pathlib.Path(sysconfig.get_paths()["purelib"]) / "cmeel.prefix/share/example-robot-data/robots"; print(p if p.is_dir() else "")' 2>/dev/null || true)
    [ -n "$d" ] && ERD="$d" && break
  done
fi
G1="$ERD/g1_description/urdf/g1_29dof_rev_1_0.urdf"
[ -f "$G1" ] || { echo "derivatives_compare.sh: $G1 not found (set ERD_ROBOTS to example-robot-data's robots/ folder)" >&2; exit 1; }

python3 benches/gen_models.py
# native: the default release build (.cargo/config.toml sets target-cpu=native; an
# environment RUSTFLAGS would replace it, so it is cleared)
unset RUSTFLAGS
cargo build --release --quiet --bin urdyn
BIN=target/release/urdyn

ALGOS=(rnea-derivatives aba-derivatives jacobians)
ALGO_FLAGS=()
for a in "${ALGOS[@]}"; do ALGO_FLAGS+=(--algo "$a"); done
# name | urdf | flags
ROBOTS=(
  "ur5|$(pwd)/assets/robots/ur5.urdf|"
  "solo12|$(pwd)/assets/robots/solo12.urdf|--floating-base"
  "talos_reduced|$(pwd)/assets/robots/talos_reduced.urdf|--floating-base"
  "g1_29dof_rev_1_0|$G1|--floating-base"
  "chain_100|$(pwd)/assets/synthetic/chain_100.urdf|"
)

OUT=target/derivatives_compare
rm -rf "$OUT"; mkdir -p "$OUT"
for round in $(seq 1 "$ROUNDS"); do
  echo "round $round start $(date -u +%H:%M) $(cut -d' ' -f1-3 /proc/loadavg)" >>"$OUT/load.txt"
  for entry in "${ROBOTS[@]}"; do
    IFS='|' read -r name urdf flags <<<"$entry"
    echo "[round $round/$ROUNDS] $name" >&2
    # shellcheck disable=SC2086
    "$PIN" "$urdf" $flags --json --native --samples "$SAMPLES" --budget "$BUDGET" "${ALGO_FLAGS[@]}" \
      2>/dev/null >"$OUT/$name.pinocchio.r$round.json" || echo "pinocchio-bench failed on $name" >&2
    # shellcheck disable=SC2086
    "$BIN" bench "$urdf" $flags --json --samples "$SAMPLES" --budget "$BUDGET" "${ALGO_FLAGS[@]}" \
      2>/dev/null >"$OUT/$name.urdyn.r$round.json" || echo "urdyn bench failed on $name" >&2
  done
done
echo "end $(date -u +%H:%M) $(cut -d' ' -f1-3 /proc/loadavg)" >>"$OUT/load.txt"

names=""
for entry in "${ROBOTS[@]}"; do
  IFS='|' read -r name urdf flags <<<"$entry"
  names="$names $name:$([ -n "$flags" ] && echo floating || echo fixed)"
done
python3 - "$OUT" benches/derivatives_results.md "${ALGOS[*]}" "$names" "$ROUNDS" "$SAMPLES" "$BUDGET" <<'EOF'
import glob, json, os, platform, sys, time

src, out_md, algos, names, rounds, samples, budget = sys.argv[1:8]
algos, names = algos.split(), names.split()


def median(xs):
    xs = sorted(xs)
    n = len(xs)
    return xs[n // 2] if n % 2 else 0.5 * (xs[n // 2 - 1] + xs[n // 2])


runs = {}  # name -> side -> round -> json
for f in glob.glob(os.path.join(src, "*.json")):
    name, side, rnd, _ = os.path.basename(f).rsplit(".", 3)
    text = open(f).read().strip()
    if text:
        runs.setdefault(name, {}).setdefault(side, {})[int(rnd[1:])] = json.loads(text)

cpu = "?"
try:
    for line in open("/proc/cpuinfo"):
        if line.startswith("model name"):
            cpu = line.split(":", 1)[1].strip()
            break
except OSError:
    pass
load = open(os.path.join(src, "load.txt")).read().strip().splitlines()
fmt = lambda x: f"{x:,.0f}"
lines = [
    "# Derivatives of the dynamics: urdyn vs Pinocchio 4.1 — measured side by side",
    "",
    f"Generated by `benches/derivatives_compare.sh` on {time.strftime('%Y-%m-%d %H:%M', time.gmtime())} UTC, "
    f"CPU: {cpu} ({os.cpu_count()} cores, shared with other jobs: absolute times are noisy, "
    "ratios are taken in one run). Native build on both sides (urdyn `-C target-cpu=native`, "
    "pinocchio-bench `--native`: `g++ -O3 -march=native`, header-only Pinocchio). "
    f"{rounds} rounds spread over the run; in each, every robot is timed by Pinocchio and then "
    f"by urdyn right after it ({samples} samples, budget {budget} s per algorithm).",
    "",
    "Algorithms: `rnea-derivatives` = ∂τ/∂q, ∂τ/∂v (Pinocchio `computeRNEADerivatives(q, v, a)`, "
    "which also fills M); `aba-derivatives` = ∂q̈/∂q, ∂q̈/∂v, M⁻¹ (`computeABADerivatives(q, v, tau)`); "
    "`jacobians` = every joint's world Jacobian (`computeJointJacobians(q)`). Random states, "
    "v, a, tau in [-1, 1].",
    "",
    "Machine load (1/5/15-min averages) during the run: " + "; ".join(load) + ".",
    "",
    "Median ns per call (the median over rounds of each round's median); ratio = urdyn / "
    "Pinocchio (lower is better), the median of the per-round ratios, [min – max] over rounds.",
    "",
    "| robot | base | nv | algorithm | urdyn ns | Pinocchio ns | ratio | range |",
    "|---|---|---:|---|---:|---:|---:|---|",
]
worst = {}
for entry in names:
    name, base = entry.split(":")
    sides = runs.get(name, {})
    u, p = sides.get("urdyn", {}), sides.get("pinocchio", {})
    any_run = next(iter(u.values()), None) or next(iter(p.values()), None) or {}
    nv = any_run.get("nv", "?")
    for a in algos:
        ux = [r["results"][a]["median_ns"] for r in u.values() if a in r.get("results", {})]
        px = [r["results"][a]["median_ns"] for r in p.values() if a in r.get("results", {})]
        rs = [u[k]["results"][a]["median_ns"] / p[k]["results"][a]["median_ns"]
              for k in sorted(set(u) & set(p))
              if a in u[k].get("results", {}) and a in p[k].get("results", {})]
        us = fmt(median(ux)) if ux else "–"
        ps = fmt(median(px)) if px else "–"
        rr = f"**{median(rs):.2f}**" if rs else "–"
        rg = f"[{min(rs):.2f} – {max(rs):.2f}]" if rs else ""
        if rs:
            worst[a] = max(worst.get(a, 0.0), median(rs))
        lines.append(f"| {name} | {base} | {nv} | `{a}` | {us} | {ps} | {rr} | {rg} |")
if worst:
    lines += ["", "Worst median ratio per algorithm over these robots: "
              + ", ".join(f"`{a}` {worst[a]:.2f}" for a in algos if a in worst) + "."]
missing = [e.split(":")[0] for e in names if not runs.get(e.split(":")[0], {}).get("urdyn")]
if missing:
    lines += ["", "No urdyn timings for: " + ", ".join(missing) + " (`urdyn bench` failed)."]
open(out_md, "w").write("\n".join(lines) + "\n")
print("\n".join(lines))
EOF
