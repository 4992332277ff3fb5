#!/usr/bin/env python3
"""A/B of two urdyn binaries on the ground-only drops of benches/sim_compare.py.

    python benches/ab_drop.py OLD_BIN NEW_BIN [REPEATS]

Drops the same example-robot-data robots (floating base, 0.3 m above the ground, 3 s at
1 ms, joints at 0) with each binary, interleaved (A, B, A, B, ...), and prints the median
steps/s of each and B/A: a profile or code change measured against the binary before it
on the same machine in one run. example-robot-data is found in this Python's
site-packages (pip install example-robot-data) or at $ERD.
"""
import os, statistics, subprocess, sys, sysconfig

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from robots_sweep import SUMMARY  # noqa: E402  (urdyn's summary line)
A, B = sys.argv[1], sys.argv[2]
reps = int(sys.argv[3]) if len(sys.argv) > 3 else 7
ERD = os.environ.get("ERD") or os.path.join(
    sysconfig.get_paths()["purelib"], "cmeel.prefix", "share", "example-robot-data", "robots")
robots = {"solo12": "solo_description/robots/solo12.urdf", "a1": "a1_description/urdf/a1.urdf",
          "anymal_b": "anymal_b_simple_description/robots/anymal.urdf",
          "talos_reduced": "talos_data/robots/talos_reduced.urdf", "go2": "go2_description/urdf/go2.urdf"}
def sps(b, urdf):
    p = subprocess.run([b, "simulate", f"{ERD}/{urdf}", "--floating-base", "--above-ground", "0.3",
                        "--duration", "3", "--package-path", ERD + "/..", "--out", "/tmp/ab.csv"],
                       capture_output=True, text=True)
    m = SUMMARY.search(p.stderr)
    return int(m.group(1)) / float(m.group(3))
for name, urdf in robots.items():
    a, b = [], []
    for _ in range(reps):
        a.append(sps(A, urdf)); b.append(sps(B, urdf))
    ma, mb = statistics.median(a), statistics.median(b)
    print(f"{name:14s} A {ma:9.0f}  B {mb:9.0f}  B/A {mb/ma:5.2f}")
