#!/usr/bin/env python3
"""Interleaved before/after timing of two urdyn binaries (and Pinocchio), in one run:

    python3 benches/derivatives_ab.py ROUNDS BIN_A BIN_B [--pin] CASE...

CASE is one of the names in CASES (e.g. solo12.abad, talos.cd, hopper.aba). In each round
every case is timed by Pinocchio (with --pin), then by BIN_A and BIN_B in alternating order
(`urdyn bench ... --json --samples 200`); printed per case: the medians of each side's
median ns, the median and range of the per-round ratios B/A, and with --pin A/Pinocchio and
B/Pinocchio. With --min, each run's minimum sample (min_ns, both sides) replaces its
median (steadier while other jobs load the machine: preempted ~50 µs batches land in the
upper tail). Used for the round-4 before/after tables of benches/derivatives_results.md
and benches/constraint_results.md (BIN_A: main's build, BIN_B: the branch's)."""
import json
import os
import statistics
import subprocess
import sys

W = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
# example-robot-data's robots/ folder (g1)
ERD = "/work/venv/lib/python3.11/site-packages/cmeel.prefix/share/example-robot-data/robots"
F = W + "/tests/fixtures/mjcf/gymnasium"
CASES = {
 "ur5.abad": (W+"/assets/robots/ur5.urdf", "", "aba-derivatives"),
 "solo12.abad": (W+"/assets/robots/solo12.urdf", "--floating-base", "aba-derivatives"),
 "talos.abad": (W+"/assets/robots/talos_reduced.urdf", "--floating-base", "aba-derivatives"),
 "g1.abad": (ERD+"/g1_description/urdf/g1_29dof_rev_1_0.urdf", "--floating-base", "aba-derivatives"),
 "chain100.abad": (W+"/assets/synthetic/chain_100.urdf", "", "aba-derivatives"),
 "talos.cd": (W+"/assets/robots/talos_reduced.urdf", "--floating-base --hold6 left_sole_link --hold6 right_sole_link", "constraint-dynamics"),
 "solo12.cd": (W+"/assets/robots/solo12.urdf", "--floating-base --hold FL_FOOT --hold FR_FOOT --hold HL_FOOT --hold HR_FOOT", "constraint-dynamics"),
 "talos.cdd": (W+"/assets/robots/talos_reduced.urdf", "--floating-base --hold6 left_sole_link --hold6 right_sole_link", "constraint-dynamics-derivatives"),
 "solo12.cdd": (W+"/assets/robots/solo12.urdf", "--floating-base --hold FL_FOOT --hold FR_FOOT --hold HL_FOOT --hold HR_FOOT", "constraint-dynamics-derivatives"),
 "talos.fdcrba": (W+"/assets/robots/talos_reduced.urdf", "--floating-base", "fd-crba"),
}
for m in ["ant", "humanoid", "half_cheetah", "walker2d", "hopper"]:
    CASES[m + ".aba"] = (F + "/" + m + ".xml", "", "aba")
    CASES[m + ".rnea"] = (F + "/" + m + ".xml", "", "rnea")
PINMODEL = {"talos": "talos_data/robots/talos_reduced.urdf", "solo12": "solo_description/robots/solo12.urdf"}

def run(cmd):
    p = subprocess.run(cmd, shell=True, capture_output=True, text=True)
    try:
        js = json.loads(p.stdout.strip().splitlines()[-1])
    except Exception:
        return None
    res = js.get("results", js)
    return res
KEY = "min_ns" if "--min" in sys.argv else "median_ns"
def timing(bin_, case, samples):
    model, flags, algo = CASES[case]
    r = run(f"{bin_} bench {model} {flags} --algo {algo} --json --samples {samples}")
    return r[algo][KEY] if r and algo in r else float("nan")
def pin(case, samples):
    model, flags, algo = CASES[case]
    base = case.split(".")[0]
    if algo in ("constraint-dynamics", "constraint-dynamics-derivatives") and base in PINMODEL:
        model = PINMODEL[base]
    r = run(f"/work/shared/tools/pinocchio-bench/run {model} {flags} --native --algo {algo} --json --samples {samples}")
    return r[algo][KEY] if r and algo in r else float("nan")

args = sys.argv[1:]
rounds = int(args[0]); bins = args[1:3]; rest = args[3:]
usepin = "--pin" in rest
samples = 200
cases = [c for c in rest if c in CASES]
data = {c: {b: [] for b in bins + ["pin"]} for c in cases}
for r in range(rounds):
    for c in cases:
        if usepin:
            data[c]["pin"].append(pin(c, samples))
        order = bins if r % 2 == 0 else bins[::-1]
        for b in order:
            data[c][b].append(timing(b, c, samples))
with open("/proc/loadavg") as f:
    load = f.read().split()[:3]
print("load", load, "per-run statistic:", KEY)
for c in cases:
    d = data[c]
    a, b = d[bins[0]], d[bins[1]]
    ratios = [y / x for x, y in zip(a, b)]
    line = f"{c:16s} A {statistics.median(a):9.0f} B {statistics.median(b):9.0f}  B/A med {statistics.median(ratios):.3f} [{min(ratios):.3f}-{max(ratios):.3f}] minA {min(a):.0f} minB {min(b):.0f}"
    if usepin:
        p = d["pin"]
        ra = [x / y for x, y in zip(a, p)]; rb = [x / y for x, y in zip(b, p)]
        line += f" | pin {statistics.median(p):.0f} A/pin {statistics.median(ra):.3f} B/pin {statistics.median(rb):.3f} [{min(rb):.3f}-{max(rb):.3f}]"
        # the ratio of the fastest runs over all rounds: on this machine a run lands in a
        # fast or a ~1.4x slower mode (the whole run, either side, any core, ASLR or not:
        # 1/3 of ur5's runs at load 0.3), so per-round ratios spread with the modes drawn
        line += f" | min/min A/pin {min(a) / min(p):.3f} B/pin {min(b) / min(p):.3f}"
    print(line, flush=True)
