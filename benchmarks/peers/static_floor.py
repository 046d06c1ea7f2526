"""The size floor of a reduced model whose elastic static gain L0_el is exact, computed from the scene with NumPy/SciPy
alone (none of kryflex's C).

    .venv/bin/python benchmarks/peers/static_floor.py [--refine 0.5 | --scene meshes/galileo/galileo.yaml]
        [--angles 0 ...] [--midpoints] [--rtol 1e-10]

Why there is a floor. A reduced second-order model with n_el elastic dofs has the elastic static gain
L0_el,r = H_r K_r^+ G_r, and K_r^+ on its elastic subspace has rank at most n_el, so rank(L0_el,r) <= n_el. A model
whose L0_el equals the full order's then has n_el >= rank(L0_el), i.e. at least 2 rank(L0_el) first-order elastic
states; "exact to rtol" (relative Frobenius norm, as kryflex's static_gain_error) needs, by Eckart-Young, at least
r(rtol) = the fewest singular values whose tail sqrt(sum_{i>r} s_i^2) is <= rtol ||L0_el||_F. A model exact at
several angles needs the largest of them. This holds for any reduced model, body-wise or not.

The body-wise form (kryflex's compression) keeps each body's share of the static elastic response exactly, N_b K^+ G
at every configuration, beside its 6 rigid motions: body b then spends rank_b elastic directions on it, the rank of
its static displacements with its own rigid motions taken out (Euclidean SVD, relative --body-rtol, the compression's
own orthonormalization tolerance 1e-8). With the system's rigid and mechanism modes made of the bodies' rigid
motions, the system's elastic dofs are sum_b (elastic directions of b), so that construction costs at least
2 sum_b rank_b first-order states. That is the cost of the construction, not a bound on every model.

- Full order at each angle as bench.py builds it (the ties eliminated, sparse), the elastic inputs and outputs made
  M-orthogonal to the geometric rigid and mechanism modes R (bench.rigid_modes).
- K^+ G_el: sparse LU of K + s M (s = 1e-2 lambda_1), refined: x <- x + (K + s M)^-1 (G_el - K x), with R's part taken
  out of x each step (the error falls by s / (lambda_1 + s) per step).
"""
import argparse
import os
import subprocess
import sys
import tempfile

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import bench  # noqa: E402
from bench import ref  # noqa: E402

REFINE_STEPS = 12


def tied(scene, angle):
    """M, K, G, H after the ties, T (full <- kept dofs) and the M-orthonormal geometric rigid modes R."""
    Mb = sp.block_diag([b.M for b in scene.bodies]).tocsc()
    Kb = sp.block_diag([b.K for b in scene.bodies]).tocsc()
    G, H = ref.body_io(scene)
    C = ref.constraint_matrix(scene, [angle])
    child = []
    for j in scene.joints:
        c = scene.body_index(j["child"])
        child += list(scene.offsets[c] + ref.interface_dofs(scene.bodies[c], j["child_interface"]))
    T, indep = bench.eliminate_ties(C, child)
    M = (T.T @ Mb @ T).tocsc()
    K = (T.T @ Kb @ T).tocsc()
    M, K = 0.5 * (M + M.T), 0.5 * (K + K.T)
    return M, K, T.T @ G, H @ T, T, bench.rigid_modes(scene, angle, C, indep, M, K)


def static_elastic(M, K, Ge, R):
    """x = K^+ Ge on the flexible subspace (R^T M x = 0), by a refined shifted solve."""
    nr = R.shape[1]
    lam = spla.eigsh(K, k=nr + 1, M=M, sigma=-1.0, which="LM", return_eigenvectors=False)
    s = 1e-2 * np.sort(lam)[nr]
    lu = spla.splu((K + s * M).tocsc())
    x = np.zeros_like(Ge)
    for _ in range(REFINE_STEPS):
        x = x + lu.solve(Ge - K @ x)
        x = x - R @ (R.T @ (M @ x))
    res = np.linalg.norm(Ge - K @ x) / np.linalg.norm(Ge)
    return x, res


def floor_rank(sv, rtol):
    """The fewest singular values whose tail is within rtol of the whole (relative Frobenius)."""
    total = np.sqrt(np.sum(sv ** 2))
    for r in range(len(sv) + 1):
        if np.sqrt(np.sum(sv[r:] ** 2)) <= rtol * total:
            return r
    return len(sv)


def body_ranks(scene, T, x, body_rtol):
    """Each body's share of the static displacement (full dofs), its own rigid motions taken out: rank, sv."""
    xf = T @ x
    out = []
    for b, body in enumerate(scene.bodies):
        o = scene.offsets[b]
        xb = xf[o:o + body.n]
        Rb = ref.body_rigid_modes(scene, b)
        Mb = body.M
        MR = Mb @ Rb
        xb = xb - Rb @ np.linalg.solve(Rb.T @ MR, MR.T @ xb)
        sv = np.linalg.svd(xb, compute_uv=False)
        out.append((body.name, int(np.sum(sv > body_rtol * sv[0])) if sv.size and sv[0] > 0 else 0, sv))
    return out


def at_angle(scene, angle, rtol, body_rtol):
    M, K, G, H, T, R = tied(scene, angle)
    Ge = G - M @ (R @ (R.T @ G))
    He = H - (H @ R) @ (R.T @ M)
    x, res = static_elastic(M, K, Ge, R)
    L0 = He @ x
    sv = np.linalg.svd(L0, compute_uv=False)
    return {"L0_sv": sv, "rank": floor_rank(sv, rtol), "residual": res, "shape": L0.shape,
            "bodies": body_ranks(scene, T, x, body_rtol), "x": x, "T": T}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--refine", type=float, default=0.5)
    ap.add_argument("--scene", help="a scene file instead of the generated solid spacecraft")
    ap.add_argument("--angles", type=float, nargs="+", default=[0.0])
    ap.add_argument("--midpoints", action="store_true", help="also every midpoint between consecutive angles")
    ap.add_argument("--rtol", type=float, default=1e-10, help="L0_el exact to this (relative Frobenius)")
    ap.add_argument("--body-rtol", type=float, default=1e-8, help="the body-wise ranks' relative SVD tolerance")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        if args.scene:
            path = os.path.abspath(args.scene)
        else:
            subprocess.run([sys.executable, os.path.join(bench.ROOT, "meshes", "solid", "generate.py"), "--refine",
                            str(args.refine), "-o", folder], check=True, capture_output=True)
            path = os.path.join(folder, "spacecraft.yaml")
        scene = ref.load_scene(path)
        angles = list(args.angles)
        if args.midpoints:
            angles = sorted(set(angles) | {0.5 * (a + b) for a, b in zip(args.angles, args.angles[1:])})
        print("static floor, %s, %d dofs before the ties, rtol %g (L0_el), body rtol %g"
              % (args.scene or "solid spacecraft --refine %g" % args.refine, sum(b.n for b in scene.bodies),
                 args.rtol, args.body_rtol))
        system, per_body = 0, {}
        cols = {b.name: [] for b in scene.bodies}
        for a in angles:
            r = at_angle(scene, a, args.rtol, args.body_rtol)
            system = max(system, r["rank"])
            print("%7.2f deg: L0_el %dx%d, singular values %s, rank %d (K x = G residual %.1e); bodies %s"
                  % (a, r["shape"][0], r["shape"][1], " ".join("%.3g" % s for s in r["L0_sv"]), r["rank"],
                     r["residual"], ", ".join("%s %d" % (n, k) for n, k, _ in r["bodies"])))
            xf = r["T"] @ r["x"]
            for b, body in enumerate(scene.bodies):
                cols[body.name].append(xf[scene.offsets[b]:scene.offsets[b] + body.n])
        for b, body in enumerate(scene.bodies):     # every angle's share together: the multi-angle construction's
            Xb = np.hstack(cols[body.name])
            Rb = ref.body_rigid_modes(scene, b)
            MR = body.M @ Rb
            Xb = Xb - Rb @ np.linalg.solve(Rb.T @ MR, MR.T @ Xb)
            sv = np.linalg.svd(Xb / np.maximum(np.linalg.norm(Xb, axis=0), 1e-300), compute_uv=False)
            per_body[body.name] = int(np.sum(sv > args.body_rtol * sv[0])) if sv.size and sv[0] > 0 else 0
        nb = sum(per_body.values())
        print("floor, any model with L0_el exact at these angles: %d elastic dofs, %d first-order elastic states"
              % (system, 2 * system))
        print("body-wise static columns kept (all angles together): %s; %d elastic dofs, %d first-order states"
              % (", ".join("%s %d" % kv for kv in per_body.items()), nb, 2 * nb))


if __name__ == "__main__":
    main()
