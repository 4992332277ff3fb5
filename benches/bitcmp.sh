#!/usr/bin/env bash
# benches/bitcmp.sh A_BIN B_BIN OUTDIR [DURATION]: the same simulations run by two urdyn binaries
# and their CSVs compared byte for byte, to tell a change that keeps every output bit for bit from
# one that changes arithmetic: 12 of MuJoCo's models (tests/fixtures/mjcf, 1 s) and the 16 scenes
# of benches/scenes (DURATION s, default 1; piles 0.5 s, the 1024-object piles 0.2 s). Needs
# example-robot-data in $PYTHON (default python3) for the scenes that name "{erd}".
# Prints each case that differs (or fails) and "bitcmp: N of 28 differ".
set -u
A=$1; B=$2; OUT=$3; DUR=${4:-1}
REPO=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
ERD=$(${PYTHON:-python3} -c "import sysconfig,os;print(os.path.join(sysconfig.get_paths()['purelib'],'cmeel.prefix','share'))")
[ -d "$ERD/example-robot-data/robots" ] || { echo "bitcmp: no example-robot-data below $ERD (set PYTHON to a python that has it)" >&2; exit 2; }
mkdir -p "$OUT/a" "$OUT/b" "$OUT/scenes"
python3 - "$REPO" "$ERD" "$OUT/scenes" <<'PY'
import json, os, sys, glob
repo, erd, out = sys.argv[1:]
for path in glob.glob(repo + "/benches/scenes/*.json"):
    sc = json.load(open(path)); base = os.path.dirname(path)
    def fix(p):
        p = p.replace("{erd}", erd + "/example-robot-data/robots")
        return p if os.path.isabs(p) else os.path.normpath(os.path.join(base, p))
    for m in sc["models"]:
        for k in ("urdf", "srdf", "mjcf"):
            if k in m: m[k] = fix(m[k])
    for o in sc.get("obstacles", []):
        if "mesh" in o: o["mesh"] = fix(o["mesh"])
    json.dump(sc, open(os.path.join(out, os.path.basename(path)), "w"), indent=1)
PY
cases=()
for m in gymnasium/humanoid gymnasium/ant dm_control/quadruped dm_control/humanoid_CMU gymnasium/hopper gymnasium/walker2d gymnasium/half_cheetah dm_control/cheetah dm_control/walker dm_control/finger dm_control/ball_in_cup dm_control/stacker; do
  cases+=("mj_${m//\//_}|$REPO/tests/fixtures/mjcf/$m.xml --duration 1")
done
for s in $OUT/scenes/*.json; do
  n=$(basename $s .json); d=$DUR; [[ $n == pile_* ]] && d=0.5; [[ $n == *1024 ]] && d=0.2
  cases+=("sc_$n|--scene $s --duration $d --package-path $ERD/example-robot-data/robots")
done
ndiff=0; total=0
for c in "${cases[@]}"; do
  name=${c%%|*}; args=${c#*|}
  $A simulate $args --every 10 --out "$OUT/a/$name.csv" 2>"$OUT/a/$name.err"; ra=$?
  $B simulate $args --every 10 --out "$OUT/b/$name.csv" 2>"$OUT/b/$name.err"; rb=$?
  total=$((total+1))
  if [ $ra -ne 0 ] || [ $rb -ne 0 ]; then echo "RUNFAIL $name rc $ra $rb: $(tail -1 $OUT/a/$name.err) | $(tail -1 $OUT/b/$name.err)"; ndiff=$((ndiff+1)); continue; fi
  if ! cmp -s "$OUT/a/$name.csv" "$OUT/b/$name.csv"; then echo "DIFF $name"; ndiff=$((ndiff+1)); fi
done
echo "bitcmp: $ndiff of $total differ"
