#!/usr/bin/env python3
"""Runs `urdyn eval` on the committed fixtures and prints the worst error per quantity.

    python3 tests/oracle/check_eval.py [--urdyn BIN] [--v2] [--tol 1e-10] [FIXTURE...]

Default: the derivative fixtures (deriv_states.json against deriv_expected.json, contract
v3); with --v2 the v2 fixtures (states.json against expected.json). Every number is
compared relative to max(1, max|ref|) over its array (a vector, a matrix, a scalar),
named by its path with link names folded ("frames.*.jacobian_dot"). The forward-dynamics
derivatives (dqdd_*) of an ill-conditioned H may differ by up to ten times Pinocchio's own
ABA-vs-CRBA disagreement on that state (deriv_meta.json's "aba_routes"), when that is above
the tolerance. Exit status 1 if any quantity fails. Needs numpy only.
"""

import argparse
import json
import subprocess
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
FIX = ROOT / "tests" / "fixtures"


def leaves(want, got, path, out):
    """(path, ref array, got array) for every numeric leaf of want; a missing key is a
    leaf with got None."""
    if isinstance(want, dict):
        for k, w in want.items():
            sub = path + [k]
            if not isinstance(got, dict) or k not in got:
                out.append((".".join(sub), None, None))
                continue
            leaves(w, got[k], sub, out)
    elif isinstance(want, (int, float)) or (isinstance(want, list) and want and not isinstance(want[0], dict)):
        out.append((".".join(path), np.array(want, dtype=float), np.array(got, dtype=float)))
    elif isinstance(want, list) and want == [] and got != []:
        out.append((".".join(path), None, None))


def fold(path, res):
    parts = path.split(".")
    for key in ("frames", "link_poses", "tau", "qdd", "bias"):
        if parts and parts[0] == key and len(parts) > 1:
            return key + ".*" + ("." + ".".join(parts[2:]) if len(parts) > 2 else "")
    return path


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--urdyn", default=str(ROOT / "target" / "release" / "urdyn"))
    ap.add_argument("--v2", action="store_true")
    ap.add_argument("--tol", type=float, default=1e-10)
    ap.add_argument("fixtures", nargs="*")
    args = ap.parse_args()
    if not Path(args.urdyn).is_file():
        sys.exit(f"check_eval.py: --urdyn {args.urdyn}: no such file (cargo build --release --bin urdyn)")
    st_name, ex_name = ("states.json", "expected.json") if args.v2 else ("deriv_states.json", "deriv_expected.json")
    dirs = [FIX / f for f in args.fixtures] if args.fixtures else sorted(
        d for d in FIX.iterdir() if (d / ex_name).is_file())
    failed = False
    for d in dirs:
        meta = json.loads((d / "meta.json").read_text())
        dmeta = json.loads((d / "deriv_meta.json").read_text()) if (d / "deriv_meta.json").is_file() else None
        cmd = [args.urdyn, "eval", str(ROOT / meta["urdf"]), "--states", str(d / st_name)]
        if meta["floating_base"]:
            cmd.append("--floating-base")
        p = subprocess.run(cmd, capture_output=True, text=True)
        if p.returncode != 0:
            print(f"{d.name:22s} FAIL: urdyn eval exit {p.returncode}: {p.stderr.strip()[:200]}")
            failed = True
            continue
        got = json.loads(p.stdout)
        want = json.loads((d / ex_name).read_text())
        worst = {}
        bad = []
        if got.get("dof_names") != want["dof_names"]:
            bad.append("dof_names differ")
        for i, (w, g) in enumerate(zip(want["results"], got["results"])):
            floor = args.tol
            if dmeta and not args.v2 and dmeta["states"][i]["aba_routes"] is not None:
                floor = max(args.tol, 10.0 * dmeta["states"][i]["aba_routes"])
            out = []
            leaves(w, g, [], out)
            for path, ref, val in out:
                key = fold(path, w)
                if ref is None or val is None or ref.shape != val.shape:
                    bad.append(f"state {i}: {path} missing or misshapen")
                    continue
                e = float(np.max(np.abs(val - ref))) / max(1.0, float(np.max(np.abs(ref)))) if ref.size else 0.0
                tol = floor if key.startswith("derivatives.dqdd") else args.tol
                worst[key] = max(worst.get(key, 0.0), e)
                if not e <= tol:
                    bad.append(f"state {i}: {path} {e:.1e} > {tol:.0e}")
        if len(got["results"]) != len(want["results"]):
            bad.append(f"{len(got['results'])} results, {len(want['results'])} expected")
        failed |= bool(bad)
        top = sorted(worst.items(), key=lambda kv: -kv[1])[:4]
        print(f"{d.name:22s} {'FAIL' if bad else 'ok  '} worst: " + ", ".join(f"{k} {v:.1e}" for k, v in top))
        for b in bad[:8]:
            print(f"{'':22s}   {b}")
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
