"""Why kryflex's smallest tied model of Galileo at 0 deg, elastic target 1e-3, keeps 3 elastic dofs (6 states) where
SOR-IRKA meets it with 2 (4 states): the tied candidates the search measures, and whether any 2-dof elastic subspace of
the richest tied candidate's span meets the target, under the peers bench's own error (bench.py).

    .venv/bin/python benchmarks/peers/galileo_trace.py [--target 1e-3]

Every reduced model here is a Galerkin projection of kryflex's richest tied model (the most accurate candidate at a
target none meets, reassembled at 0 deg: its M, K, G, H in independent coordinates), which is itself a Galerkin
projection of the full order: so a subspace of its coordinates
is a subspace of what kryflex builds. The rigid-body and mechanism modes are always kept. Subspaces tried:
- pairs of the richest model's flexible modes (modal truncation within its span), with and without K^+ G (the static
  moment exact);
- span{K^+ G (elastic part), v}: v optimized (Nelder-Mead from every mode) for the bench's error;
- any 2 directions, optimized the same way (static moment free);
- the full order's own 21 flexible dofs: the best pair of modes, and span{K^+ G, v} with v optimized;
- SOR-IRKA's r = 2 model (pyMOR, if installed): its own error and static gain, and the Galerkin models on its V and on
  its W alone (SOR-IRKA projects two-sided, V != W).
"""
import argparse
import os
import sys

import numpy as np
import scipy.linalg as sl
import scipy.optimize as so

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import bench  # noqa: E402


def frf(M, K, beta, G, H, freqs):
    """modal form of the small Galerkin model: with C = beta K the modes of (K, M) diagonalize it"""
    lam, X = sl.eigh(K, M)
    w = 2 * np.pi * np.asarray(freqs)
    d = 1.0 / (lam[None, :] * (1 + 1j * w[:, None] * beta) - w[:, None] ** 2)
    return np.einsum("tk,fk,ka->fta", H @ X, d, X.T @ G)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--target", type=float, default=1e-3)
    args = ap.parse_args()
    scene_path = os.path.join(bench.ROOT, "meshes", "galileo", "galileo.yaml")
    M, K, G, H, PhiR, beta, freqs, Ge, He = bench.elastic_setup(bench.ref.load_scene(scene_path), 0.0)
    nr = PhiR.shape[1]
    T_el = bench.direct_response(M, K, beta, Ge, He, freqs)
    Md, Kd = M.toarray(), K.toarray()

    def err_full(V):
        """the bench's elastic error of the Galerkin model on span V (full-order coordinates, elastic directions)"""
        Q = sl.orth(V - PhiR @ (PhiR.T @ (Md @ V)))
        return bench.elastic_error(T_el, frf(Q.T @ Md @ Q, Q.T @ Kd @ Q, beta, Q.T @ Ge, He @ Q, freqs), T_el)

    # 1. the tied search at the target, its table
    import kryflex
    spec = bench.kryflex_spec(scene_path, 0.0, beta, args.target)
    red = kryflex.Reducer(kryflex.scene_from_dict(spec), quiet=True, shared_directions="true")
    out = red.reduce()
    tab = np.asarray(red.result(-1, "search_table")).T   # 8 x ncand: one column per candidate
    print("tied search at %g: %d candidates (family, moments c, kept clusters, expansion angles, size = body dofs - "
          "ties, system dofs, error, variant)" % (args.target, len(tab)))
    for row in tab:
        print("  c=%d kept=%3d size=%3d sysdofs=%3d (elastic %d) error %.3g %s" % (
            row[1], row[2], row[4], row[5], row[5] - nr, row[6], "passes" if row[6] <= args.target else ""))
    s = out.model.at([0.0])
    print("chosen: %d dofs, bench error %.3g" % (s.dofs, bench.elastic_error(T_el + 0, s.elastic_frf(freqs), T_el)))

    # 2. the richest tied candidate: a target no candidate meets, so the most accurate (every moment, the whole basis)
    spec_rich = bench.kryflex_spec(scene_path, 0.0, beta, 1e-12)    # no candidate meets it: the most accurate kept
    red2 = kryflex.Reducer(kryflex.scene_from_dict(spec_rich), quiet=True, shared_directions="true")
    rich = red2.reduce().model.at([0.0])
    n = rich.dofs
    Mr, Kr, Gr, Hr = rich.M, rich.K, rich.B, rich.C
    # in its reduced coordinates: a Galerkin model of this Galerkin model is one of the full order on part of its span
    lr, Xr = sl.eigh(Kr, Mr)
    rig = lr < 1e-9 * lr.max()
    R_r = Xr[:, rig]
    F_r = Xr[:, ~rig]
    print("richest tied candidate (the most accurate at target 1e-12): %d dofs, %d rigid, %d flexible; "
          "frequencies %s Hz" % (
        n, rig.sum(), (~rig).sum(), np.array2string(np.sqrt(lr[~rig]) / 2 / np.pi, precision=3)))
    Ger = Gr - Mr @ (R_r @ (R_r.T @ Gr))
    Her = Hr - (Hr @ R_r) @ (R_r.T @ Mr)

    def err_red(V):
        Q = V - R_r @ (R_r.T @ (Mr @ V))
        Q = sl.orth(Q)
        return bench.elastic_error(T_el, frf(Q.T @ Mr @ Q, Q.T @ Kr @ Q, beta, Q.T @ Ger, Her @ Q, freqs), T_el)

    print("  its own bench error (all %d flexible): %.3g" % (F_r.shape[1], err_red(F_r)))
    ks = np.linalg.solve(Kr + Mr @ R_r @ R_r.T @ Mr, Ger)     # K^+ G on the flexible subspace
    ks = (ks - R_r @ (R_r.T @ (Mr @ ks)))[:, 0]
    nf = F_r.shape[1]
    best = (np.inf, None)
    for i in range(nf):
        for j in range(i + 1, nf):
            e = err_red(F_r[:, [i, j]])
            if e < best[0]:
                best = (e, (i, j))
    print("  best pair of its modes: %s, error %.3g" % (best[1], best[0]))
    bs = (np.inf, None)
    for i in range(nf):
        e = err_red(np.column_stack([ks, F_r[:, i]]))
        if e < bs[0]:
            bs = (e, i)
    print("  best K^+G + one mode: mode %s, error %.3g" % (bs[1], bs[0]))

    def opt(fixed, starts, k):
        best = (np.inf, None)
        for x0 in starts:
            def f(x):
                V = x.reshape(nf, k)
                return np.log10(err_red(np.column_stack([fixed, F_r @ V]) if fixed is not None else F_r @ V))
            res = so.minimize(f, x0.ravel(), method="Nelder-Mead",
                              options={"maxiter": 4000, "xatol": 1e-6, "fatol": 1e-5})
            if res.fun < best[0]:
                best = (res.fun, res.x)
        return 10 ** best[0], best[1]

    e1, _ = opt(ks[:, None], [np.eye(nf)[:, [i]] for i in range(nf)], 1)
    print("  span{K^+G, v}, v optimized over the span: error %.3g" % e1)
    e2, _ = opt(None, [np.eye(nf)[:, [best[1][0], best[1][1]]]] + [np.eye(nf)[:, [0, i]] for i in range(1, nf)], 2)
    print("  any 2 directions optimized over the span: error %.3g" % e2)

    # 3. the same questions on the full order's own span (28 dofs): is the limit kryflex's span or Galerkin itself?
    lf, Xf = sl.eigh(Kd, Md)
    Ff = Xf[:, nr:]
    bp = min((err_full(Ff[:, [i, j]]), (i, j)) for i in range(6) for j in range(i + 1, 8))
    print("full order: best pair of its first 8 modes %s error %.3g" % (bp[1], bp[0]))
    kf = np.linalg.solve(Kd + Md @ PhiR @ PhiR.T @ Md, Ge)[:, 0]
    nff = Ff.shape[1]
    bb = (np.inf, None)
    for i in range(nff):
        res = so.minimize(lambda x: np.log10(err_full(np.column_stack([kf, Ff @ x]))), np.eye(nff)[i],
                          method="Nelder-Mead", options={"maxiter": 3000, "xatol": 1e-6, "fatol": 1e-5})
        bb = min(bb, (10 ** res.fun, i))
    print("full order: span{K^+G, v}, v optimized over all %d flexible dofs (Nelder-Mead from each mode): %.3g" % (
        nff, bb[0]))

    try:
        from pymor.reductors.sor_irka import SORIRKAReductor
        som = bench.pymor_model(M, K, beta, Ge, He)
        rd = SORIRKAReductor(som)
        rom = rd.reduce(2)
        Tr = rom.transfer_function.freq_resp(2 * np.pi * freqs)
        V, W = rd.V.to_numpy(), rd.W.to_numpy()
        V, W = (V if V.shape[0] == M.shape[0] else V.T), (W if W.shape[0] == M.shape[0] else W.T)
        L0 = (He @ np.linalg.solve(Kd + Md @ PhiR @ PhiR.T @ Md, Ge)).item()
        L0r = rom.transfer_function.eval_tf(0).real.item()
        print("SOR-IRKA r=2: its elastic static gain %.6g against the full order's %.6g (relative error %.2g)" % (
            L0r, L0, abs(L0r - L0) / abs(L0)))
        VW = V.T @ W
        print("SOR-IRKA r=2: its own model's bench error %.3g; Galerkin on its V %.3g, on its W %.3g, V^T W "
              "offdiag/diag %.2g" % (bench.elastic_error(T_el, Tr, T_el), err_full(V), err_full(W),
                                     np.abs(VW - np.diag(np.diag(VW))).max() / np.abs(np.diag(VW)).max()))
    except ImportError as e:
        print("pyMOR not installed: SOR-IRKA check skipped (%s)" % e)


if __name__ == "__main__":
    main()
