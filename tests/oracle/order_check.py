#!/usr/bin/env python3
"""Is urdyn's degree-of-freedom order Pinocchio's, on every example-robot-data robot?

For every URDF of example-robot-data (robots/*/robots/*.urdf and robots/*/urdf/*.urdf),
with a fixed and with a floating base, this
- builds pin.buildModelFromUrdf(URDF[, JointModelFreeFlyer()]) and takes its joint order
  (model.names, the free flyer left out), mimic joints excluded as urdyn reduces them;
- draws two random Pinocchio states (q within the limits, continuous joints as (cos, sin),
  base pose and body-frame velocities; v, a in [-1, 1]) as a Pinocchio user holds them: one
  vector each in Pinocchio's order;
- hands them to `urdyn eval` *by position*: the k-th reduced Pinocchio coordinate goes to
  urdyn's k-th `dof_names` entry (continuous joints as the angle atan2(sin, cos), the
  base block as given) and reads urdyn's `tau` back by position, with no reordering;
- compares `dof_names` with Pinocchio's order and that tau with pin.rnea (reduced by G for
  mimic models: tau = Gᵀ rnea(q_full, G v, G a)), relative to max(1, max|tau_pin|).
Writes docs/pinocchio_order.md (or the path given by --output).

    python tests/oracle/order_check.py [--urdyn target/release/urdyn] [--output FILE]

Pinocchio's dynamics are computed on a copy of the URDF with normalised axes and no
<mimic> tags (make_fixtures.oracle_copy: the joint order is the same, asserted).
"""

import argparse
import json
import xml.etree.ElementTree as ET
import math
import subprocess
import sys
import tempfile
import zlib
from pathlib import Path

import numpy as np
import pinocchio as pin

sys.path.insert(0, str(Path(__file__).resolve().parent))
import make_fixtures as mf  # noqa: E402

ROOT = mf.ROOT
TOL = 1e-10
N_STATES = 2


def urdfs():
    out = sorted(list(mf.ERD.glob("*/robots/*.urdf")) + list(mf.ERD.glob("*/urdf/*.urdf")))
    return out


def build(path, floating):
    if floating:
        return pin.buildModelFromUrdf(str(path), pin.JointModelFreeFlyer())
    return pin.buildModelFromUrdf(str(path))


def pin_joints(model, floating):
    first = 2 if floating else 1
    return [(model.names[i], model.joints[i]) for i in range(first, model.njoints)]


def urdyn_eval(exe, urdf, floating, states, tmp):
    sp = Path(tmp) / "states.json"
    sp.write_text(json.dumps({"gravity": [0.0, 0.0, -9.81], "states": states}))
    cmd = [exe, "eval", str(urdf), "--states", str(sp)] + (["--floating-base"] if floating else [])
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        return None, p.stderr.strip().splitlines()[-1] if p.stderr.strip() else f"exit {p.returncode}"
    return json.loads(p.stdout), None


def repaired_copy(urdf, tmp, tag, drop_mimic=(), massless=False):
    """A copy of the URDF, in the same folder order (same tree, same joint order), with the
    <mimic> tags of the joints in drop_mimic removed and, with massless, every link without
    mass given 1 g (inertia 1e-6 kg m²)."""
    tree = ET.parse(urdf)
    for j in tree.getroot().findall("joint"):
        if j.get("name") in drop_mimic:
            for m in j.findall("mimic"):
                j.remove(m)
    if massless:
        for l in tree.getroot().findall("link"):
            inert = l.find("inertial")
            mass = inert.find("mass") if inert is not None else None
            if mass is not None and float(mass.get("value", "0")) > 0.0:
                continue
            if inert is not None:
                l.remove(inert)
            inert = ET.SubElement(l, "inertial")
            ET.SubElement(inert, "mass", value="0.001")
            ET.SubElement(inert, "inertia", ixx="1e-6", ixy="0", ixz="0", iyy="1e-6", iyz="0", izz="1e-6")
    out = Path(tmp) / f"{tag}.urdf"
    tree.write(out)
    return out


def check(exe, urdf, floating, tmp):
    """One (robot, base) row; a URDF that one engine refuses is compared on a repaired copy
    when the repair cannot change the order (the row's note says which)."""
    rel = urdf.relative_to(mf.ERD)
    base = "floating" if floating else "fixed"
    try:
        tree, links, joints, root = mf.parse_urdf(urdf)
    except Exception as e:  # noqa: BLE001 - reported in the table
        err = urdyn_eval(exe, urdf, floating, [], tmp)[1]
        return {"robot": str(rel), "base": base,
                "note": f"not a robot ({str(e).split(': ')[-1]}): nothing to compare; urdyn: `{err}`"}
    notes = []
    bad = [n for n, j in joints.items() if j["mimic"] is not None
           and (j["mimic"][0] not in joints or joints[j["mimic"][0]]["type"] not in mf.MOVABLE)]
    if bad:
        err = urdyn_eval(exe, urdf, floating, [], tmp)[1]
        notes.append(f"mimic joints naming a missing leader ({', '.join(bad[:3])}{', ...' if len(bad) > 3 else ''}): "
                     f"urdyn refuses it as the contract says (`{err}`), Pinocchio (mimic=False) ignores the tag; "
                     "compared on a copy without those tags")
        urdf = repaired_copy(urdf, tmp, "nomimic", drop_mimic=set(bad))
    row = check_one(exe, urdf, floating, tmp, rel, base)
    if row.get("note", "").startswith("urdyn eval:") and "massless" in row["note"]:
        notes.append(f"{row['note']} (the contract's singular-H error); compared on a copy whose "
                     "massless links weigh 1 g")
        row = check_one(exe, repaired_copy(urdf, tmp, "massive", massless=True), floating, tmp, rel, base)
    if notes:
        row["note"] = "; ".join(notes + ([row["note"]] if "note" in row else []))
        row["repaired"] = True
    return row


def check_one(exe, urdf, floating, tmp, rel, base):
    row = {"robot": str(rel), "base": base}
    tree, links, joints, root = mf.parse_urdf(urdf)
    mimic = mf.resolve_mimic(joints)
    try:
        model_o = build(urdf, floating)
    except Exception as e:  # noqa: BLE001
        row["note"] = f"Pinocchio cannot load it: {str(e).splitlines()[0][:80]}"
        return row
    clean = Path(tmp) / "clean.urdf"
    mf.oracle_copy(tree, str(clean))
    model = build(clean, floating)
    names = [n for n, _ in pin_joints(model, floating)]
    assert names == [n for n, _ in pin_joints(model_o, floating)], "oracle copy changed the order"
    data = model.createData()
    nb = 6 if floating else 0
    unsupported = [n for n, jm in pin_joints(model, floating) if jm.nv != 1]
    if unsupported:
        row["note"] = f"joints of more than one DoF: {unsupported[:3]}"
        return row
    pin_dofs = [n for n in names if n not in mimic]
    nv = nb + len(pin_dofs)
    row["nv"] = nv
    row["mimic"] = len(names) - len(pin_dofs)

    # urdyn's order, from an eval of no state
    out, err = urdyn_eval(exe, urdf, floating, [], tmp)
    if out is None:
        row["note"] = f"urdyn eval: {err}"
        return row
    dof_names = out["dof_names"]
    row["order_equal"] = dof_names == pin_dofs
    if not row["order_equal"]:
        k = next((i for i, (a, b) in enumerate(zip(dof_names, pin_dofs)) if a != b),
                 min(len(dof_names), len(pin_dofs)))
        row["note"] = (f"first difference at {k}: urdyn {dof_names[k:k + 2]} vs Pinocchio "
                       f"{pin_dofs[k:k + 2]}" if len(dof_names) == len(pin_dofs)
                       else f"urdyn {len(dof_names)} DoF, Pinocchio {len(pin_dofs)}")

    # G: all Pinocchio joint coordinates w.r.t. the reduced ones (Pinocchio's order)
    col = {n: nb + k for k, n in enumerate(pin_dofs)}
    G = np.zeros((model.nv, nv))
    G[:nb, :nb] = np.eye(nb)
    for n, jm in pin_joints(model, floating):
        leader, mult, _ = mimic.get(n, (n, 1.0, 0.0))
        G[jm.idx_v, col[leader]] = mult

    rng = np.random.default_rng(zlib.crc32(f"{rel}:{floating}".encode()))
    states, pin_taus, pin_states = [], [], []
    for _ in range(N_STATES):
        # a Pinocchio user's reduced vectors: angles (continuous joints as (cos, sin) below)
        qr = np.zeros(len(pin_dofs))
        for k, n in enumerate(pin_dofs):
            j = joints[n]
            lo, hi = j["lower"], j["upper"]
            if j["type"] == "continuous" or lo is None or hi is None or not lo < hi:
                lo, hi = -math.pi, math.pi
            qr[k] = rng.uniform(lo, hi)
        vr, ar = rng.uniform(-1, 1, nv), rng.uniform(-1, 1, nv)
        q = pin.neutral(model)
        if floating:
            q[0:3] = rng.uniform(-1, 1, 3)
            q[3:7] = mf.rand_unit_quat(rng)
        for n, jm in pin_joints(model, floating):
            leader, mult, off = mimic.get(n, (n, 1.0, 0.0))
            val = mult * qr[pin_dofs.index(leader)] + off
            if jm.nq == 2:
                q[jm.idx_q], q[jm.idx_q + 1] = math.cos(val), math.sin(val)
            else:
                q[jm.idx_q] = val
        tau_pin = G.T @ pin.rnea(model, data, q, G @ vr, G @ ar)
        pin_taus.append(tau_pin)
        pin_states.append((q, G @ vr, G @ ar))
        # urdyn by position: the k-th coordinate to dof_names[k]; continuous joints from
        # Pinocchio's (cos, sin) as the angle atan2(sin, cos)
        qk = []
        for k, n in enumerate(pin_dofs):
            jm = model.joints[model.getJointId(n)]
            qk.append(math.atan2(q[jm.idx_q + 1], q[jm.idx_q]) if jm.nq == 2 else float(q[jm.idx_q]))
        st = {"q": {n: qk[k] for k, n in enumerate(dof_names[:len(pin_dofs)])},
              "v": {n: float(vr[nb + k]) for k, n in enumerate(dof_names[:len(pin_dofs)])},
              "a": {n: float(ar[nb + k]) for k, n in enumerate(dof_names[:len(pin_dofs)])}}
        if floating:
            st["base"] = {"position": [float(x) for x in q[0:3]],
                          "orientation_xyzw": [float(x) for x in q[3:7]],
                          "linear_velocity": [float(x) for x in vr[0:3]],
                          "angular_velocity": [float(x) for x in vr[3:6]],
                          "linear_acceleration": [float(x) for x in ar[0:3]],
                          "angular_acceleration": [float(x) for x in ar[3:6]]}
        states.append(st)
    if len(dof_names) != len(pin_dofs):
        return row
    out, err = urdyn_eval(exe, urdf, floating, states, tmp)
    if out is None:
        row["note"] = f"urdyn eval: {err}"
        return row
    worst, explained = 0.0, True
    err = lambda tu, tp: float(np.max(np.abs(tu - tp))) / max(1.0, float(np.max(np.abs(tp))))
    for res, tp, (q, v, a) in zip(out["results"], pin_taus, pin_states):
        tu = np.array(([*res["base"]["force"], *res["base"]["torque"]] if floating else [])
                      + [res["tau"][n] for n in dof_names])
        if not tp.size:
            continue
        e = err(tu, tp)
        worst = max(worst, e)
        if e > TOL:
            explained = explained and one_ulp_explains(model, data, G, q, v, a, tu, err)
    row["tau_err"] = worst
    if worst > TOL and "note" not in row:
        row["note"] = "tau differs"
        if explained and row.get("order_equal"):
            row["note"] += (": explained by urdyn reading some joint angles of the JSON 1 ulp off "
                            "(moving Pinocchio's q by 1 ulp on those joints brings tau within "
                            f"{TOL:g}); the angles here are ~1e15 rad (limits ±1e16), where 1 ulp is "
                            "1 rad. serde_json's default float parser is not correctly rounded "
                            "(feature `float_roundtrip` is)")
    return row


def one_ulp_explains(model, data, G, q, v, a, tu, err):
    """Greedy search over ±1 ulp of each 1-coordinate joint's q: does some such q give
    Pinocchio urdyn's tau (within TOL)?"""
    q = q.copy()
    best = err(tu, G.T @ pin.rnea(model, data, q, v, a))
    idx = [jm.idx_q for i, jm in enumerate(model.joints) if i > 0 and jm.nq == 1]
    for _ in range(2):
        for i in idx:
            for direction in (np.inf, -np.inf):
                trial = q.copy()
                trial[i] = np.nextafter(q[i], direction)
                e = err(tu, G.T @ pin.rnea(model, data, trial, v, a))
                if e < best:
                    best, q = e, trial
    return best <= TOL


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--urdyn", default=str(ROOT / "target" / "release" / "urdyn"))
    ap.add_argument("--output", default=str(ROOT / "docs" / "pinocchio_order.md"))
    args = ap.parse_args()
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for u in urdfs():
            for floating in (False, True):
                try:
                    r = check(args.urdyn, u, floating, tmp)
                except Exception as e:  # noqa: BLE001 - reported in the table
                    r = {"robot": str(u.relative_to(mf.ERD)), "base": "floating" if floating else "fixed",
                         "note": f"check failed: {type(e).__name__}: {str(e)[:100]}"}
                rows.append(r)
                print(f"{r['robot']:58s} {r['base']:8s} nv={r.get('nv', '-')!s:>3s} "
                      f"order={r.get('order_equal', '-')!s:5s} tau={r.get('tau_err', float('nan')):.1e} "
                      f"{r.get('note', '')}", flush=True)
    ok = [r for r in rows if r.get("order_equal") and r.get("tau_err", 1.0) <= TOL]
    bad = [r for r in rows if r not in ok]
    same_order = [r for r in rows if r.get("order_equal")]
    noted = [r for r in rows if "note" in r]
    prefix = str(mf.ERD) + "/"
    for r in noted:
        r["note"] = r["note"].replace(prefix, "")
    lines = [
        "# urdyn's degree-of-freedom order against Pinocchio's",
        "",
        "Generated by `tests/oracle/order_check.py` (Pinocchio "
        f"{pin.__version__}, example-robot-data {mf.ERD_VERSION}): every URDF of example-robot-data "
        "(`robots/*/robots/*.urdf`, `robots/*/urdf/*.urdf`), fixed and floating base, two random "
        "states each. *Order equal*: `urdyn eval`'s `dof_names` is `pin.buildModelFromUrdf`'s joint "
        "order (free flyer and mimic joints left out). *Max rel tau error*: a Pinocchio user's "
        "vectors q, v, a (Pinocchio's order; continuous joints' (cos, sin) given to urdyn as the "
        "angle atan2(sin, cos)) handed to urdyn by position, urdyn's tau read back by position "
        "(base wrench first), against `pin.rnea` (Gᵀ rnea(q_full, G v, G a) with mimic joints), "
        "relative to max(1, max|tau|), with no reordering anywhere.",
        "",
        f"Result: {len(same_order)} of {len(rows)} (robot, base) pairs compared have the same "
        f"order; {len(ok)} of them also tau within {TOL:g} "
        f"({sum(1 for r in ok if r.get('repaired'))} on a repaired copy, see the notes); "
        f"{len(bad)} pairs are not both (the notes give the reason).",
        "",
        "| robot | base | nv | mimic | order equal | max rel tau error |",
        "|---|---|---:|---:|---|---:|",
    ]
    for r in rows:
        te = f"{r['tau_err']:.1e}" if "tau_err" in r else "—"
        oe = {True: "yes", False: "**no**"}.get(r.get("order_equal"), "—")
        lines.append(f"| {r['robot']} | {r['base']} | {r.get('nv', '—')} | {r.get('mimic', '—')} | {oe} | {te} |")
    if noted:
        lines += ["", "## Notes", ""]
        for r in noted:
            lines.append(f"- {r['robot']} ({r['base']}): {r['note']}")
    Path(args.output).write_text("\n".join(lines) + "\n")
    print(f"{len(ok)}/{len(rows)} equal; wrote {args.output}")


if __name__ == "__main__":
    main()
