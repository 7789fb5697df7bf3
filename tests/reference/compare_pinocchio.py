#!/usr/bin/env python3
"""Cross-checks `phri-model inspect` against Pinocchio (an established rigid-body library).

usage: python3 tests/reference/compare_pinocchio.py [--bin target/release/phri-model]
           [--states N] [--write-fixture OUT.json] URDF[@N] [URDF[@N] ...]

Needs `pip install pin` (Pinocchio >= 3.4 for mimic joints; the fixture was written with
4.1). For each URDF and N random states (`URDF@N` overrides --states for that file) it
compares M, C, C q̇, Cᵀ q̇, g, tau (RNEA), the placement of every link and the Jacobian of
a point on the last link, and prints the worst norm-wise relative error of each term:
    err = max over states of ||ours - pin||_inf / max(||pin||_inf, 1e-12)
Exit code 1 when any term is above --tol (default 1e-9).

Mimic joints (e.g. the Panda's second finger) are loaded with Pinocchio's own support,
`buildModelFromUrdf(path, mimic=True)`: the model has one degree of freedom per actuated
joint and each mimic joint follows its leader (q = multiplier q_leader + offset). Every
term comes from that model except C: Pinocchio 4.1's computeCoriolisMatrix is not
consistent on a model with mimic joints (on the Panda, C q̇ differs from
nonLinearEffects - g and Ṁ from C + Cᵀ by about 1e-3, and C from Gᵀ C_full G by up to
20 % of its largest entry), so the reference C is Gᵀ C_full G, C_full
from the same URDF loaded without mimic support (the mimic joint free) and G the map from
the actuated joints' velocities to all of them (built from Pinocchio's mimic model). The
script prints how far Pinocchio's own C is from it, and checks that the reference C is
consistent with Pinocchio's M (Ṁ = C + Cᵀ, by central differences) and its RNEA (C q̇).
"""
import argparse
import json
import subprocess
import sys

import numpy as np
import pinocchio as pin


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


class Full:
    """The URDF loaded without mimic support (every mimic joint free) and the constant map
    G from the mimic model's velocities to the full model's: v_full = G v, q_full = G q + o."""

    def __init__(self, path, reduced):
        self.model = pin.buildModelFromUrdf(path)
        self.data = self.model.createData()
        self.G = np.zeros((self.model.nv, reduced.nv))
        self.o = np.zeros(self.model.nq)
        for jid in range(1, self.model.njoints):
            jf = self.model.joints[jid]
            jr = reduced.joints[reduced.getJointId(self.model.names[jid])]
            if jf.nv != 1 or jf.nq != 1:
                raise SystemExit(f"{path}: joint {self.model.names[jid]}: only 1-DOF joints (no continuous) beside mimic joints")
            if jr.shortname() == "JointModelMimic":
                m = jr.extract()
                self.G[jf.idx_v, jr.idx_v] = m.scaling
                self.o[jf.idx_q] = m.offset
            else:
                self.G[jf.idx_v, jr.idx_v] = 1.0

    def coriolis(self, q, v):
        """Gᵀ C_full(G q + o, G v) G."""
        C = pin.computeCoriolisMatrix(self.model, self.data, self.G @ q + self.o, self.G @ v)
        return self.G.T @ C @ self.G


def mass_matrix(model, data, q):
    M = pin.crba(model, data, q)
    return np.triu(M) + np.triu(M, 1).T


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
        path, _, states = spec.partition("@")
        states = int(states) if states else args.states
        model = pin.buildModelFromUrdf(path, mimic=True)
        data = model.createData()
        mimic = any(model.joints[j].shortname() == "JointModelMimic" for j in range(1, model.njoints))
        full = Full(path, model) if mimic else None
        probe = subprocess.run([args.bin, "inspect", path, "--q", "0"], capture_output=True, text=True)
        n = int(probe.stderr.split("expected ")[1].split(" ")[0]) if probe.returncode else 1
        if n != model.nv:
            raise SystemExit(f"{path}: phri has {n} degrees of freedom, Pinocchio {model.nv}")
        worst = {}
        pin_c_gap = 0.0
        for s in range(states):
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
            M = mass_matrix(model, data, pq)
            g = pin.computeGeneralizedGravity(model, data, pq)
            tau = pin.rnea(model, data, pq, pv, pa)
            c_qd = pin.nonLinearEffects(model, data, pq, pv) - g
            C = pin.computeCoriolisMatrix(model, data, pq, pv).copy()
            if full is not None:
                pin_c_gap = max(pin_c_gap, rel(C, full.coriolis(pq, pv)))
                C = full.coriolis(pq, pv)
                # the reference C must be consistent with Pinocchio's M and RNEA
                h = 1e-6
                Mdot = (mass_matrix(model, data, pq + h * pv) - mass_matrix(model, data, pq - h * pv)) / (2 * h)
                assert rel(C @ pv, c_qd) < 1e-12, "reference C q̇ is not Pinocchio's RNEA bias"
                assert np.max(np.abs(Mdot - C - C.T)) < 1e-6 * (1 + np.max(np.abs(Mdot))), "reference C: Ṁ ≠ C + Cᵀ"
            ref = {
                "M": M[np.ix_(P, P)], "C": C[np.ix_(P, P)], "C_qd": c_qd[P], "Ct_qd": (C.T @ pv)[P],
                "g": g[P], "tau": tau[P],
            }
            pin.forwardKinematics(model, data, pq)
            pin.updateFramePlacements(model, data)
            fk = {link: data.oMf[model.getFrameId(link, pin.BODY)].homogeneous.copy() for link in ours["fk"]}
            fid = model.getFrameId(last_link, pin.BODY)
            pin.computeJointJacobians(model, data, pq)
            J = pin.getFrameJacobian(model, data, fid, pin.LOCAL_WORLD_ALIGNED)
            Rp = data.oMf[fid].rotation @ point
            J = J.copy()
            J[:3, :] -= pin.skew(Rp) @ J[3:, :]
            ref["jacobian"] = J[:, P]
            errs = {k: rel(ours[k], v) for k, v in ref.items()}
            errs["fk"] = max(rel(ours["fk"][link], T) for link, T in fk.items())
            for k, e in errs.items():
                worst[k] = max(worst.get(k, 0.0), e)
            if args.write_fixture:
                fixtures.append({"urdf": spec.partition("@")[0], "q": q.tolist(), "qd": qd.tolist(), "qdd": qdd.tolist(),
                                 "point_link": last_link, "point": point.tolist(), "joints": names,
                                 **{k: np.asarray(v).tolist() for k, v in ref.items()},
                                 "fk": {link: T.tolist() for link, T in fk.items()}})
        line = " ".join(f"{k}={v:.1e}" for k, v in sorted(worst.items()))
        print(f"{path}: dof={n} states={states} worst relative error: {line}")
        if full is not None:
            print(f"{path}: mimic joints; Pinocchio's own computeCoriolisMatrix differs from Gᵀ C_full G by up to {pin_c_gap:.1e} (not compared)")
        worst_all = max(worst_all, max(worst.values()))
    if args.write_fixture:
        with open(args.write_fixture, "w") as f:
            json.dump({"generator": f"pinocchio {pin.__version__}", "cases": fixtures}, f)
    print(f"worst over all: {worst_all:.2e} (tolerance {args.tol:g})")
    return 0 if worst_all <= args.tol else 1


if __name__ == "__main__":
    sys.exit(main())
