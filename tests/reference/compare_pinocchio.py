#!/usr/bin/env python3
"""Cross-checks `phri-model inspect` against Pinocchio (an established rigid-body library).

usage: python3 tests/reference/compare_pinocchio.py [--bin target/release/phri-model]
           [--states N] [--write-fixture OUT.json] URDF [URDF ...]

Needs `pip install pin` (Pinocchio). For each URDF and N random states it compares M, C,
C q̇, Cᵀ q̇, g, tau (RNEA), the placement of every link and the Jacobian of a point on the
last link, and prints the worst norm-wise relative error of each term:
    err = max over states of ||ours - pin||_inf / max(||pin||_inf, 1e-12)
Exit code 1 when any term is above --tol (default 1e-9).

A URDF with mimic joints (e.g. the Panda's fingers) is refused by phri; pass it as
PATH:fix-mimic to have this script turn its mimic joints, and the joints they follow
when those only drive grippers, into fixed joints first.
"""
import argparse
import json
import subprocess
import sys
import tempfile
import xml.etree.ElementTree as ET

import numpy as np
import pinocchio as pin


def fix_mimic(path):
    tree = ET.parse(path)
    root = tree.getroot()
    for j in root.findall("joint"):
        if j.find("mimic") is not None or "finger" in j.get("name", ""):
            j.set("type", "fixed")
            for tag in ("mimic", "limit", "axis"):
                for e in j.findall(tag):
                    j.remove(e)
    out = tempfile.NamedTemporaryFile("w", suffix=".urdf", delete=False)
    tree.write(out.name)
    return out.name


def rel(a, b):
    a, b = np.asarray(a, float), np.asarray(b, float)
    return float(np.max(np.abs(a - b)) / max(np.max(np.abs(b)), 1e-12))


def pin_q(model, names, q):
    """Map phri's joint vector (by name) to Pinocchio's q (continuous joints are cos/sin)."""
    out = pin.neutral(model)
    for k, name in enumerate(names):
        jid = model.getJointId(name)
        j = model.joints[jid]
        if j.nq == 2:
            out[j.idx_q] = np.cos(q[k])
            out[j.idx_q + 1] = np.sin(q[k])
        else:
            out[j.idx_q] = q[k]
    return out


def pin_v(model, names, v):
    out = np.zeros(model.nv)
    for k, name in enumerate(names):
        out[model.joints[model.getJointId(name)].idx_v] = v[k]
    return out


def perm(model, names):
    return [model.joints[model.getJointId(n)].idx_v for n in names]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--bin", default="target/release/phri-model")
    ap.add_argument("--states", type=int, default=20)
    ap.add_argument("--tol", type=float, default=1e-9)
    ap.add_argument("--seed", type=int, default=7)
    ap.add_argument("--write-fixture")
    ap.add_argument("urdfs", nargs="+")
    args = ap.parse_args()
    rng = np.random.default_rng(args.seed)
    worst_all = 0.0
    fixtures = []
    for spec in args.urdfs:
        path = spec
        if spec.endswith(":fix-mimic"):
            path = fix_mimic(spec[: -len(":fix-mimic")])
        model = pin.buildModelFromUrdf(path)
        data = model.createData()
        probe = subprocess.run([args.bin, "inspect", path, "--q", "0"], capture_output=True, text=True)
        n = int(probe.stderr.split("expected ")[1].split(" ")[0]) if probe.returncode else 1
        worst = {}
        for s in range(args.states):
            q = rng.uniform(-2.5, 2.5, n)
            qd = rng.uniform(-2.0, 2.0, n)
            qdd = rng.uniform(-5.0, 5.0, n)
            cmd = [args.bin, "inspect", path, "--q", ",".join(map(repr, q.tolist())), "--qd", ",".join(map(repr, qd.tolist())), "--qdd", ",".join(map(repr, qdd.tolist()))]
            first = json.loads(subprocess.run(cmd, capture_output=True, text=True, check=True).stdout)
            names = first["joints"]
            # a link on the deepest joint, so that the Jacobian has many non-zero columns
            bodies = [f for f in model.frames if f.type == pin.BODY and f.name in first["fk"]]
            last_link = max(bodies, key=lambda f: (f.parentJoint, f.name)).name
            point = rng.uniform(-0.1, 0.1, 3)
            cmd += ["--point", f"{last_link}:{','.join(map(repr, point.tolist()))}"]
            ours = json.loads(subprocess.run(cmd, capture_output=True, text=True, check=True).stdout)
            pq, pv, pa = pin_q(model, names, q), pin_v(model, names, qd), pin_v(model, names, qdd)
            P = perm(model, names)
            M = pin.crba(model, data, pq)
            M = np.triu(M) + np.triu(M, 1).T
            g = pin.computeGeneralizedGravity(model, data, pq)
            tau = pin.rnea(model, data, pq, pv, pa)
            C = pin.computeCoriolisMatrix(model, data, pq, pv)
            c_qd = pin.nonLinearEffects(model, data, pq, pv) - g
            ref = {
                "M": M[np.ix_(P, P)], "C": C[np.ix_(P, P)], "C_qd": c_qd[P], "Ct_qd": (C.T @ pv)[P],
                "g": g[P], "tau": tau[P],
            }
            pin.forwardKinematics(model, data, pq)
            pin.updateFramePlacements(model, data)
            fk_err = 0.0
            for link, T in ours["fk"].items():
                fid = model.getFrameId(link, pin.BODY)
                fk_err = max(fk_err, rel(T, data.oMf[fid].homogeneous))
            fid = model.getFrameId(last_link, pin.BODY)
            pin.computeJointJacobians(model, data, pq)
            J = pin.getFrameJacobian(model, data, fid, pin.LOCAL_WORLD_ALIGNED)
            Rp = data.oMf[fid].rotation @ point
            J = J.copy()
            J[:3, :] -= pin.skew(Rp) @ J[3:, :]
            ref["jacobian"] = J[:, P]
            errs = {k: rel(ours[k], v) for k, v in ref.items()}
            errs["fk"] = fk_err
            for k, e in errs.items():
                worst[k] = max(worst.get(k, 0.0), e)
            if args.write_fixture:
                fixtures.append({"urdf": spec, "q": q.tolist(), "qd": qd.tolist(), "qdd": qdd.tolist(),
                                 "point_link": last_link, "point": point.tolist(), "joints": names,
                                 **{k: np.asarray(v).tolist() for k, v in ref.items()}})
        line = " ".join(f"{k}={v:.1e}" for k, v in sorted(worst.items()))
        print(f"{spec}: dof={n} states={args.states} worst relative error: {line}")
        worst_all = max(worst_all, max(worst.values()))
    if args.write_fixture:
        with open(args.write_fixture, "w") as f:
            json.dump({"generator": f"pinocchio {pin.__version__}", "cases": fixtures}, f)
    print(f"worst over all: {worst_all:.2e} (tolerance {args.tol:g})")
    return 0 if worst_all <= args.tol else 1


if __name__ == "__main__":
    sys.exit(main())
