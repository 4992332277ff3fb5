#!/usr/bin/env python3
"""Projected Gauss–Seidel against the primal Newton solver, same scenes, one run.

Usage: cargo build --release --features tools --example prof_lamp && python3 benches/solver_compare.py [--share DIR] [--rounds 3]

Each scene is examples/prof_lamp: the README's lamp drop (0.5 m, 10° about x), or a
robot of example-robot-data with a floating base, joints at 0, its lowest collision
point 0.3 m up (LAMP=urdf TILT=0), dt = 1 ms, 3 s, default options but the solver
(SOLVER=pgs|newton). The two solvers run interleaved, --rounds times; a row gives the
fastest run's µs per step (prof_lamp's fastest of 3 repeats, in-process, no output),
the mean solver iterations per step (PGS sweeps; Newton steps), and the state one
second after the 3 s: penetration and the largest velocity left (a resting robot
has ~0) and the energy. Writes benches/solver_compare.md.
"""
import argparse
import os
import re
import subprocess
import sysconfig
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
ROBOTS = {
    "lamp": None,
    "go2": "go2_description/urdf/go2.urdf",
    "solo12": "solo_description/robots/solo12.urdf",
    "a1": "a1_description/urdf/a1.urdf",
    "anymal": "anymal_c_simple_description/urdf/anymal.urdf",
    "talos_reduced": "talos_data/robots/talos_reduced.urdf",
    "g1": "g1_description/urdf/g1_29dof_rev_1_0.urdf",
}


def run(robot, rel, share, solver):
    env = dict(os.environ, SOLVER=solver)
    if rel:
        env.update(LAMP=os.path.join(share, "example-robot-data", "robots", rel), PKG=share, TILT="0")
    out = subprocess.run([os.path.join(ROOT, "target/release/examples/prof_lamp"), "3", "1e-6", "3"],
                         env=env, cwd=ROOT, capture_output=True, text=True, timeout=900)
    if out.returncode != 0:
        m = re.search(r"step: (\w+ \{[^}]*\})", out.stderr)
        return {"us": float("inf"), "failed": m.group(1) if m else out.stderr.strip()[-200:]}
    t = out.stdout
    def g(pat):
        return float(re.search(pat, t).group(1))
    return {"us": g(r"([0-9.]+) us/step"), "iters": g(r"mean sweeps/step ([0-9.]+)"),
            "pen": g(r"penetration ([0-9.e+-]+) m"), "vmax": g(r"max \|v\| ([0-9.e+-]+)"),
            "energy": g(r"energy ([0-9.e+-]+) J")}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--share", default=os.path.join(sysconfig.get_paths()["purelib"], "cmeel.prefix", "share"),
                    help="the folder holding example-robot-data/ (default: this Python's pip install)")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--md", default=os.path.join(HERE, "solver_compare.md"))
    a = ap.parse_args()
    best = {}
    for _ in range(a.rounds):
        for robot, rel in ROBOTS.items():
            for solver in ("pgs", "newton"):
                r = run(robot, rel, a.share, solver)
                k = (robot, solver)
                if k not in best or r["us"] < best[k]["us"] or "failed" in r:
                    best[k] = r
                print(robot, solver, r, flush=True)
    lines = ["# Constraint solver: projected Gauss–Seidel against primal Newton (benches/solver_compare.py)", "",
             f"Measured {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}, load average "
             f"{os.getloadavg()[0]:.1f}, {a.rounds} interleaved rounds; scenes in the script's docstring.", "",
             "| scene | PGS µs/step | Newton µs/step | Newton / PGS | PGS sweeps/step | Newton steps/step | "
             "PGS rest pen (m) / max |v| | Newton rest pen (m) / max |v| |",
             "|---|---|---|---|---|---|---|---|"]
    for robot in ROBOTS:
        p, n = best[(robot, "pgs")], best[(robot, "newton")]
        if "failed" in p or "failed" in n:
            bad = p if "failed" in p else n
            lines.append(f"| {robot} | {p.get('us', 0):.2f} | failed | – | {p.get('iters', 0):.2f} | – | "
                         f"{p.get('pen', 0):.1e} / {p.get('vmax', 0):.1e} | {bad['failed']} |")
            continue
        lines.append(f"| {robot} | {p['us']:.2f} | {n['us']:.2f} | {n['us'] / p['us']:.2f} | {p['iters']:.2f} | "
                     f"{n['iters']:.2f} | {p['pen']:.1e} / {p['vmax']:.1e} | {n['pen']:.1e} / {n['vmax']:.1e} |")
    with open(a.md, "w") as f:
        f.write("\n".join(lines) + "\n")
    print("wrote", a.md)


if __name__ == "__main__":
    main()
