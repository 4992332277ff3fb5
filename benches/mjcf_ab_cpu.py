#!/usr/bin/env python3
"""A/B of two urdyn binaries by process CPU time on MuJoCo's models (a loaded machine's
check: the stepping loop's wall time swings with the other jobs, the CPU time much less).

    python benches/mjcf_ab_cpu.py BASE_BIN NEW_BIN N MODEL[,MODEL...] [DURATION]

Runs `BIN simulate tests/fixtures/mjcf/MODEL.xml --no-sleep --integrator euler --duration
DURATION --every 1000000000` N times per binary, alternating which goes first each round;
prints per model the median and best CPU time (user + system of the child, getrusage) and
loop wall time (urdyn's summary line) of each, and new / base. The CPU time includes the
process start and the import (the same work in both; use a long DURATION, e.g. 20 s, to
make the step dominate).
"""
import os
import re
import resource
import statistics
import subprocess
import sys

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def main():
    base, new, n, models = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4].split(",")
    dur = sys.argv[5] if len(sys.argv) > 5 else "3"
    bins = {"base": base, "new": new}
    for m in models:
        cpu = {k: [] for k in bins}
        wall = {k: [] for k in bins}
        for i in range(n):
            for k in (list(bins) if i % 2 == 0 else list(bins)[::-1]):
                r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
                p = subprocess.run(
                    [bins[k], "simulate", os.path.join(REPO, "tests", "fixtures", "mjcf", m + ".xml"),
                     "--no-sleep", "--integrator", "euler", "--duration", dur,
                     "--every", "1000000000", "--out", os.devnull],
                    capture_output=True, text=True)
                r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
                cpu[k].append(r1.ru_utime - r0.ru_utime + r1.ru_stime - r0.ru_stime)
                w = re.search(r"in ([0-9.]+) s wall", p.stderr)
                wall[k].append(float(w.group(1)) if w else float("nan"))
        med = {k: statistics.median(cpu[k]) for k in bins}
        wmed = {k: statistics.median(wall[k]) for k in bins}
        print(f"{m}: CPU s median base {med['base']:.4f} new {med['new']:.4f} "
              f"new/base {med['new'] / med['base']:.3f} (best {min(cpu['base']):.4f} / "
              f"{min(cpu['new']):.4f} = {min(cpu['new']) / min(cpu['base']):.3f}); loop wall median "
              f"{wmed['base']:.4f} / {wmed['new']:.4f} = {wmed['new'] / wmed['base']:.3f}")


if __name__ == "__main__":
    main()
