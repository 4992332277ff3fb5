#!/usr/bin/env python3
"""Cost per degree of freedom of each joint kind (issue 28: "the new joint kinds no slower per
degree of freedom than a free base is today").

Writes chains of N links (default 8) in a temporary folder, every joint of one kind:
revolute (1 DoF each), spherical (3), planar (3) and floating (6: the free joint a free base
uses, here at every link), and times them with `urdyn bench --json`, back to back, in
interleaved rounds. Reports the median ns per call divided by nv, each kind's ns/DoF as a
ratio to the floating chain's (≤ 1: no slower per DoF than the free joint), and the same ratio
per body (per joint): a joint's fixed cost per body (its placement, spatial products) is shared
by six DoF in a free joint and by three in a spherical or planar one, so per DoF a 3-DoF joint
pays about twice the free joint's share of it even when each joint costs the same.

    python benches/joint_kinds.py --urdyn target/release/urdyn [--links 8] [--rounds 3] [--md OUT]
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time

KINDS = {"revolute": 1, "spherical": 3, "planar": 3, "floating": 6}
ALGOS = ["rnea", "crba", "aba", "fd", "jacobians", "rnea-derivatives", "aba-derivatives"]


def chain_urdf(kind, links):
    """A chain of `links` bodies 0.3 m apart along x, each a 1 kg box-like inertia off its
    joint, every joint of `kind` (a revolute/planar axis alternates between y and z)."""
    out = [f'<robot name="{kind}_chain">', '<link name="base"/>']
    for i in range(links):
        out.append(
            f'<link name="l{i}"><inertial><origin xyz="0.15 0.01 0.02" rpy="0.1 0.2 0.3"/>'
            f'<mass value="1"/><inertia ixx="0.01" iyy="0.02" izz="0.03" ixy="0.001" '
            f'ixz="0" iyz="0.002"/></inertial></link>'
        )
        parent = "base" if i == 0 else f"l{i - 1}"
        xyz = "0 0 0" if i == 0 else "0.3 0 0"
        axis = "0 1 0" if i % 2 == 0 else "0 0 1"
        limit = (
            '<limit lower="-3" upper="3" effort="100" velocity="10"/>' if kind == "revolute" else ""
        )
        axis_el = f'<axis xyz="{axis}"/>' if kind in ("revolute", "planar") else ""
        out.append(
            f'<joint name="j{i}" type="{kind}"><parent link="{parent}"/><child link="l{i}"/>'
            f'<origin xyz="{xyz}"/>{axis_el}{limit}</joint>'
        )
    out.append("</robot>")
    return "\n".join(out)


def bench(urdyn, path):
    cmd = [urdyn, "bench", path, "--json", "--samples", "200", "--budget", "0.6"]
    for a in ALGOS:
        cmd += ["--algo", a]
    r = subprocess.run(cmd, capture_output=True, text=True, check=True)
    return json.loads(r.stdout)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--urdyn", default="target/release/urdyn")
    ap.add_argument("--links", type=int, default=8)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--md", help="write the Markdown table here")
    a = ap.parse_args()
    tmp = tempfile.mkdtemp(prefix="urdyn_kinds_")
    paths = {}
    for k in KINDS:
        paths[k] = os.path.join(tmp, f"{k}_chain.urdf")
        with open(paths[k], "w") as f:
            f.write(chain_urdf(k, a.links))
    per_dof = {k: {al: [] for al in ALGOS} for k in KINDS}
    nv = {}
    load0 = os.getloadavg()[0]
    for _ in range(a.rounds):
        for k in KINDS:
            j = bench(a.urdyn, paths[k])
            nv[k] = j["nv"]
            assert nv[k] == KINDS[k] * a.links, (k, nv[k])
            for al in ALGOS:
                per_dof[k][al].append(j["results"][al]["median_ns"] / nv[k])
    load1 = os.getloadavg()[0]
    med = {k: {al: statistics.median(per_dof[k][al]) for al in ALGOS} for k in KINDS}
    lines = [
        f"`python benches/joint_kinds.py --links {a.links} --rounds {a.rounds}` on "
        f"{time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}, load average {load0:.1f} → "
        f"{load1:.1f}. Chains of {a.links} links, every joint of one kind; median ns per call "
        "÷ nv (median over rounds); in brackets the ratio to the floating chain's ns/DoF "
        "(≤ 1: no slower per DoF than the free joint).",
        "",
        "| kind (nv) | " + " | ".join(ALGOS) + " |",
        "|---|" + "---|" * len(ALGOS),
    ]
    worst = 0.0
    worst_body = 0.0
    body_rows = []
    for k in KINDS:
        cells = []
        bcells = []
        for al in ALGOS:
            r = med[k][al] / med["floating"][al]
            rb = r * KINDS[k] / KINDS["floating"]
            if k in ("spherical", "planar"):
                worst = max(worst, r)
                worst_body = max(worst_body, rb)
            cells.append(f"{med[k][al]:.1f} ({r:.2f})")
            bcells.append(f"{med[k][al] * KINDS[k]:.0f} ({rb:.2f})")
        lines.append(f"| {k} ({nv[k]}) | " + " | ".join(cells) + " |")
        body_rows.append(f"| {k} ({nv[k]}) | " + " | ".join(bcells) + " |")
    lines += [
        "",
        "Per body (ns per call ÷ links; in brackets the ratio to the floating chain's):",
        "",
        "| kind (nv) | " + " | ".join(ALGOS) + " |",
        "|---|" + "---|" * len(ALGOS),
    ] + body_rows
    lines += [
        "",
        f"Worst spherical/planar ratio to the free joint: per DoF {worst:.2f}, "
        f"per body {worst_body:.2f}.",
    ]
    text = "\n".join(lines) + "\n"
    print(text)
    if a.md:
        with open(a.md, "w") as f:
            f.write(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
