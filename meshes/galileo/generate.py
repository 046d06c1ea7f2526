#!/usr/bin/python3
"""Builds the 28-dof Galileo-like model of Lee's paper (Table 1, Fig. 2) and writes it next to this script.

    /usr/bin/python3 meshes/galileo/generate.py [--out DIR] [--fit fit.json]

The paper: A. Y. Lee, "A Krylov Model Reduction Methodology for Articulated, Multi-Flexible Body Structures", Jet
Propulsion Laboratory (JPL). It gives the model's frequencies (Table 1), not its matrices. The model is built in
two layers:

1. A stick model (build_stator, build_rotor; the tables below): stator (despun section, 12 dofs): two 6-dof nodes,
   the spin bearing (node 1) and point A (node 2), on one stubby beam; rotor (spun section, 21 dofs): a 6-dof hub
   on the bearing (node 101) and five 3-dof appendage tips on beams whose tip rotations are condensed out
   (magnetometer boom, two RTG booms, high-gain antenna, lower module). Mass lumped at the nodes. It gives the
   geometry, the lumped-mass layout and the starting masses; meshes/stress.py builds its stress scenes from it.
2. The fitted model (fitted_bodies, from fit.json written by fit.py): the stick masses times fitted factors, and
   K = M Phi Lambda Phi^T M with Lambda Table 1's component frequencies and Phi fitted mode shapes, fitted to
   the system frequencies of Tables 1 (0 deg) and 4 (60 deg) and the moments of Table 5 (README.md: the fit and
   its residuals). These are the committed body files.

The script checks that each body is free-free (M positive definite, exactly 6 zero eigenvalues of K),
prints component and system (alpha = 0) frequencies beside the paper's and writes:
    stator_M.mtx stator_K.mtx rotor_M.mtx rotor_K.mtx stator_nodes.txt rotor_nodes.txt galileo.yaml
"""
import argparse
import functools
import os
import sys

import numpy as np
import scipy.linalg as sl

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))
import frames  # noqa: E402  (meshes/frames.py: beam element and writers)

# ------------------------------------------------------------------ design (SI units: kg, m, N)
# Node inertia tensors are about the node, in the body frame.  The stator is a stub along -z whose lateral
# inertia is lopsided (about x it is twice that about y: a platform reaching out along y), and the rotor's
# booms stick out sideways and slightly up (products of inertia).  So turning the rotor changes both the
# system frequencies and what the stator's point A feels: the input-to-output map depends on the clock angle.
# Stiffnesses (and the inertias at point A) are the values of a one-off least-squares fit of the free-free
# frequencies to Table 1 (README.md), rounded to 4 digits; nothing is fitted at run time.

STATOR_NODES = [
    # id, name, position, mass, inertia tensor
    (1, "bearing", (0.0, 0.0, 0.0), 420.0, [[600.0, 0.0, 0.0], [0.0, 1500.0, 0.0], [0.0, 0.0, 260.0]]),
    (2, "A", (0.0, 0.0, -1.7), 640.0, [[8126.0, 0.0, 0.0], [0.0, 1551.0, 0.0], [0.0, 0.0, 300.0]]),
]
# stator beam, bearing -> A (along -z); ref = global x, so local y = global y and local z = global x
STATOR_BEAM = dict(EA=2.524e10, GJ=1.845e10, EIy=1.678e8, EIz=1.541e8, ref=(1.0, 0.0, 0.0))

ROTOR_HUB = (101, "hub", (0.0, 0.0, 0.0), 900.0, [[760.0, 0.0, 0.0], [0.0, 760.0, 0.0], [0.0, 0.0, 1100.0]])
ROTOR_APPENDAGES = [
    # id, name, tip position, tip mass, EA, EIy (bending in the local x-z plane), EIz (local x-y plane).
    # Local y is perpendicular to the beam and to global z (tangential for the radial booms; for the
    # two beams along z it is perpendicular to global x).  Tips are 3-dof: tip rotations condensed out.
    (102, "magnetometer_boom_tip", (-10.6, 1.2, 0.6), 16.0, 3.846e7, 1.467e5, 2324.0),
    (103, "rtg1", (2.1, 3.6, 0.3), 60.0, 5.120e7, 7.935e5, 3.410e5),
    (104, "rtg2", (2.3, -3.3, 0.35), 56.0, 5.004e7, 3.409e5, 6.040e5),
    (105, "high_gain_antenna", (0.0, 0.0, 2.9), 52.0, 2.608e10, 1.437e8, 1.434e8),
    (106, "lower_module", (0.0, 0.0, -1.1), 180.0, 3.729e10, 2.097e9, 2.097e9),
]

SCENE_ANGLES = [0, 15, 30, 45, 60, 72]


# ------------------------------------------------------------------ model

def node_mass(mass, inertia):
    m = np.zeros((6, 6))
    m[:3, :3] = mass * np.eye(3)
    m[3:, 3:] = np.asarray(inertia, float)
    return m


def beam_stiffness(x1, x2, EA, EIy, EIz, GJ=None, ref=None, pinned_end=False):
    """Global 12x12 beam stiffness; pinned_end condenses the end rotations out (9x9: hub 6 + tip 3)."""
    R, L = frames.beam_frames(np.asarray(x1)[None], np.asarray(x2)[None], None if ref is None else np.asarray(ref)[None])
    if GJ is None:
        GJ = EIy   # irrelevant when the end is pinned: condensation removes torsion entirely
    k = frames.to_global(frames.beam_local_stiffness(L, EA, GJ, EIy, EIz), R)
    return (frames.condense(k, [9, 10, 11]) if pinned_end else k)[0]


def build_stator(nodes=STATOR_NODES, beam=STATOR_BEAM):
    (_, _, x1, m1, j1), (_, _, x2, m2, j2) = nodes
    M = sl.block_diag(node_mass(m1, j1), node_mass(m2, j2))
    K = beam_stiffness(x1, x2, beam["EA"], beam["EIy"], beam["EIz"], beam["GJ"], beam["ref"])
    table = [(i, x, 6) for i, _, x, _, _ in nodes]
    return M, 0.5 * (K + K.T), table


def build_rotor(hub=ROTOR_HUB, appendages=ROTOR_APPENDAGES):
    hid, _, xh, mh, jh = hub
    n = 6 + 3 * len(appendages)
    M = np.zeros((n, n))
    K = np.zeros((n, n))
    M[:6, :6] = node_mass(mh, jh)
    table = [(hid, xh, 6)]
    for a, (aid, _, xt, mt, EA, EIy, EIz) in enumerate(appendages):
        tip = slice(6 + 3 * a, 9 + 3 * a)
        M[tip, tip] = mt * np.eye(3)
        k = beam_stiffness(xh, xt, EA, EIy, EIz, pinned_end=True)
        dofs = np.r_[0:6, tip]
        K[np.ix_(dofs, dofs)] += k
        table.append((aid, xt, 3))
    return M, 0.5 * (K + K.T), table


def free_free_frequencies(name, M, K, nrigid=6, rtol=1e-9):
    """Checks M > 0 and exactly nrigid zero eigenvalues of (K, M); returns all frequencies in Hz."""
    if np.linalg.eigvalsh(M).min() <= 0:
        raise SystemExit(f"{name}: mass matrix is not positive definite; give every dof a mass or inertia")
    lam = sl.eigh(K, M, eigvals_only=True)
    zero = np.abs(lam) <= rtol * lam.max()
    if zero.sum() != nrigid or lam.min() < -rtol * lam.max():
        raise SystemExit(f"{name}: expected exactly {nrigid} zero-frequency modes, found {zero.sum()} "
                         f"(eigenvalues {lam[:nrigid + 2]}); check the beam connectivity")
    lam[zero] = 0.0
    return np.sqrt(lam) / (2 * np.pi)


def system_frequencies_alpha0(Ms, Ks, Mr, Kr):
    """System at alpha = 0: bearing nodes share ux uy uz rx ry (dofs 0..4 of each body); rz is free."""
    ns = Ms.shape[0]
    C = np.zeros((5, ns + Kr.shape[0]))
    C[np.arange(5), np.arange(5)] = 1.0
    C[np.arange(5), ns + np.arange(5)] = -1.0
    P = sl.null_space(C)
    M = P.T @ sl.block_diag(Ms, Mr) @ P
    K = P.T @ sl.block_diag(Ks, Kr) @ P
    return free_free_frequencies("system (alpha = 0)", M, K, nrigid=7)


# ------------------------------------------------------------------ the fitted model (fit.py, fit.json)
# Lee's Table 1 (A. Y. Lee, "A Krylov Model Reduction Methodology for Articulated, Multi-Flexible Body Structures",
# Jet Propulsion Laboratory): free-free flexible frequencies of the rotor and the stator, and of the system at
# alpha = 0 (modes 8-28), in Hz, as published.
PAPER_ROTOR_HZ = [0.1221, 1.0579, 2.8638, 3.4223, 4.9894, 5.2217, 73.425, 75.821, 76.998, 116.50, 116.51,
                  994.70, 994.70, 2108.5, 2431.9]
PAPER_STATOR_HZ = [57.253, 57.455, 225.24, 225.31, 1217.7, 1404.7]
PAPER_SYSTEM_HZ = [0.1106, 1.0521, 1.9403, 2.3975, 2.8446, 3.4648, 4.9930, 5.4793, 6.8081, 9.2953, 56.060, 73.429,
                   75.823, 76.999, 144.69, 144.73, 712.64, 712.65, 1217.7, 1985.9, 2108.5]
FIT_FILE = os.path.join(HERE, "fit.json")

# The lumped masses the fit may scale (log factors, one per entry), in this order: each entry names the body, the
# dofs (0-based, in the body's dof order) that share one factor, and what they are.
MASS_PARAMETERS = [
    ("stator", (0, 1, 2), "bearing node mass"), ("stator", (3,), "bearing node Jxx"),
    ("stator", (4,), "bearing node Jyy"), ("stator", (5,), "bearing node Jzz"),
    ("stator", (6, 7, 8), "point A mass"), ("stator", (9,), "point A Jxx"), ("stator", (10,), "point A Jyy"),
    ("stator", (11,), "point A Jzz"),
    ("rotor", (0, 1, 2), "hub mass"), ("rotor", (3,), "hub Jxx"), ("rotor", (4,), "hub Jyy"),
    ("rotor", (5,), "hub Jzz"),
] + [("rotor", (6 + 3 * a, 7 + 3 * a, 8 + 3 * a), name + " mass") for a, (_, name, *_) in enumerate(ROTOR_APPENDAGES)]


def rigid_modes(table):
    """Rigid-body motions of a node table [(id, x, ndof)]: columns ux uy uz (translation) and rx ry rz (small
    rotation about the origin: u = theta x x, node rotations = theta)."""
    rows = []
    for _, x, ndof in table:
        x = np.asarray(x, float)
        block = np.zeros((ndof, 6))
        block[:3, :3] = np.eye(3)
        block[:3, 3:] = -np.array([[0.0, -x[2], x[1]], [x[2], 0.0, -x[0]], [-x[1], x[0], 0.0]])
        if ndof == 6:
            block[3:, 3:] = np.eye(3)
        rows.append(block)
    return np.vstack(rows)


def _m_orthonormal(V, M):
    """V's columns made M-orthonormal by the Cholesky factor of V^T M V (unique, smooth in M: no sign choices)."""
    L = np.linalg.cholesky(V.T @ M @ V)
    return sl.solve_triangular(L, V.T, lower=True).T


def flexible_basis(M, table):
    """A deterministic M-orthonormal basis of the complement of the rigid modes: the unit vectors of every dof but
    the first node's 6 (a rigid motion that keeps the first node still is zero, so they span a complement), with
    the rigid part removed, M-orthonormalized."""
    R = _m_orthonormal(rigid_modes(table), M)
    E = np.eye(M.shape[0])[:, 6:]
    return _m_orthonormal(E - R @ (R.T @ M @ E), M)


def skew(p, n):
    S = np.zeros((n, n))
    S[np.triu_indices(n, 1)] = p
    return S - S.T


def modal_stiffness(M, table, freqs_hz, rotation):
    """K = M Phi diag((2 pi f)^2) Phi^T M with Phi = flexible_basis(M) expm(skew(rotation)): free-free with exactly
    the rigid modes of the node geometry in its null space and exactly the flexible frequencies freqs_hz, whatever
    the rotation (which sets the mode shapes, among them how much each mode moves the interface)."""
    n = M.shape[0] - 6
    Phi = flexible_basis(M, table) @ sl.expm(skew(np.asarray(rotation, float), n))
    MP = M @ Phi
    K = (MP * (2 * np.pi * np.asarray(freqs_hz, float)) ** 2) @ MP.T
    return 0.5 * (K + K.T)


def n_rotation(body_dofs):
    n = body_dofs - 6
    return n * (n - 1) // 2


@functools.lru_cache(maxsize=1)
def _stick_masses():
    Ms, _, ts = build_stator()
    Mr, _, tr = build_rotor()
    return Ms, ts, Mr, tr


def fitted_masses(mass_params):
    """The stick model's mass matrices times the factors exp(mass_params) (MASS_PARAMETERS): (Ms, ts, Mr, tr)."""
    Ms, ts, Mr, tr = _stick_masses()
    Ms, Mr = Ms.copy(), Mr.copy()
    for (body, dofs, _), q in zip(MASS_PARAMETERS, mass_params):
        M = Ms if body == "stator" else Mr
        for d in dofs:
            M[d, d] *= np.exp(q)
    return Ms, ts, Mr, tr


def fitted_bodies(params):
    """The fitted stator and rotor from a parameter vector [mass log factors, stator rotation, rotor rotation]:
    ((Ms, Ks, table), (Mr, Kr, table)). Masses are the stick model's times the factors; stiffness by
    modal_stiffness with Table 1's component frequencies."""
    params = np.asarray(params, float)
    nm = len(MASS_PARAMETERS)
    Ms, ts, Mr, tr = fitted_masses(params[:nm])
    ns = n_rotation(Ms.shape[0])
    Ks = modal_stiffness(Ms, ts, PAPER_STATOR_HZ, params[nm:nm + ns])
    Kr = modal_stiffness(Mr, tr, PAPER_ROTOR_HZ, params[nm + ns:])
    return (Ms, Ks, ts), (Mr, Kr, tr)


def load_fit(path=FIT_FILE):
    """The parameter vector fit.py wrote (fit.json: mass log factors by name, then the rotations)."""
    import json
    with open(path) as f:
        fit = json.load(f)
    masses = [fit["mass_log_factors"][name] for _, _, name in MASS_PARAMETERS]
    return np.array(masses + fit["stator_rotation"] + fit["rotor_rotation"], float)


def build_bodies(path=FIT_FILE):
    """The committed Galileo-like bodies: fitted_bodies(load_fit(path))."""
    return fitted_bodies(load_fit(path))


# ------------------------------------------------------------------ files

def write_scene(out_dir):
    scene = f"""\
# Galileo-like 28-dof model of A. Y. Lee (JPL), "A Krylov Model Reduction Methodology for Articulated, Multi-Flexible
# Body Structures" (Table 1, Fig. 2), fitted to its Tables 1, 4 and 5 (meshes/galileo/fit.py); written by generate.py.
name: galileo
bodies:
  stator:
    mass: stator_M.mtx
    stiffness: stator_K.mtx
    nodes: stator_nodes.txt
    interfaces: {{bearing: 1}}
  rotor:
    mass: rotor_M.mtx
    stiffness: rotor_K.mtx
    nodes: rotor_nodes.txt
    interfaces: {{bearing: 101}}
joints:
  spin_bearing: {{type: revolute, parent: stator, parent_interface: bearing, child: rotor, child_interface: bearing, axis: [0, 0, 1]}}
inputs:
  # spin bearing actuator: +torque about z on the stator, -torque on the rotor
  bearing_torque:
    - {{body: stator, node: 1, dof: rz, weight: 1.0}}
    - {{body: rotor, node: 101, dof: rz, weight: -1.0}}
outputs:
  # rotation about Y at point A on the stator (not the bearing node)
  pointA_ry: [{{body: stator, node: 2, dof: ry}}]
angles: [{", ".join(str(a) for a in SCENE_ANGLES)}]
band: [0.01, 10.0]
damping: 0.0025
accuracy: 0.05
reduction: {{moments: 10, output_blocks: 1, importance: h2, keep_threshold: 0.1, reduction_angle: auto}}
# the paper's recipe: c = 10, its alpha_G rule; importance h2 stands for its MIC; Tables 2-3 keep MIC >= 0.1149 and
# drop 0.0820, so its threshold is 0.1 (kryflex's default 0.05)
# the report adds the paper's Tables 1-6 and Fig. 3 beside kryflex's (docs/guide/paper-example.md)
paper: lee
"""
    with open(os.path.join(out_dir, "galileo.yaml"), "w") as f:
        f.write(scene)


def write_body(out_dir, name, M, K, table, names):
    note = f"Galileo-like {name}, {M.shape[0]} dofs, SI units; generated by meshes/galileo/generate.py"
    frames.write_mtx_symmetric(os.path.join(out_dir, f"{name}_M.mtx"), M, note)
    frames.write_mtx_symmetric(os.path.join(out_dir, f"{name}_K.mtx"), K, note)
    ids = [i for i, _, _ in table]
    frames.write_nodes(os.path.join(out_dir, f"{name}_nodes.txt"), ids, [x for _, x, _ in table],
                       [d for _, _, d in table], note + "\nnodes: " + ", ".join(f"{i} {n}" for i, n in zip(ids, names)))


def print_residuals(path):
    """The fitted model against the paper, entry by entry, as Markdown (README.md's residual tables): fit.py's own
    evaluation (tests/python/test_galileo_fit.py measures the same on the written files independently)."""
    import fit
    prob = fit.Whole()
    x = load_fit(path)
    freqs, L, imps = prob.evaluate(x)
    print("| mode | 0°, paper | 0°, here | diff | 60°, paper | 60°, here | diff |")
    print("|---|---|---|---|---|---|---|")
    for m in range(len(prob.target)):
        a, b = freqs[0.0][m], freqs[60.0][m]
        print(f"| {m + 8} | {prob.target[m]:.5g} | {a:.5g} | {100 * (a / prob.target[m] - 1):+.2f} % | "
              f"{prob.target60[m]:.5g} | {b:.5g} | {100 * (b / prob.target60[m] - 1):+.2f} % |")
    print()
    print("| L^k | " + " | ".join(f"{a:g}°, paper / here" for a in fit.ANGLES) + " |")
    print("|---|" + "---|" * len(fit.ANGLES))
    for k in range(L.shape[0]):
        cells = []
        for j in range(len(fit.ANGLES)):
            paper, here, floor = fit.MOMENTS[k, j], L[k, j], fit.MOMENT_FLOOR[k, j]
            if abs(paper) <= floor:
                verdict = "met" if abs(here) <= floor else "missed"
            else:
                verdict = ("sign" if np.sign(here) != np.sign(paper) else
                           "met" if abs(here / paper - 1) <= fit.MOMENT_TOL else f"{100 * (here / paper - 1):+.0f} %")
            cells.append(f"{paper:.4g} / {here:.4g} ({verdict})")
        print(f"| {k} | " + " | ".join(cells) + " |")
    print()
    print("importance (h2, normalized) of modes 8-17, here / Tables 2-3's MIC:")
    for a, mic in ((0.0, fit.MIC_0), (60.0, fit.MIC_60)):
        print(f"  {a:g} deg: " + ", ".join(f"{v:.3f}/{w:.4f}" for v, w in zip(imps[a][:fit.LOW], mic)))
    ms, mr = prob.masses(x)
    print(f"masses: stator {ms:.0f} kg, rotor {mr:.0f} kg")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=HERE, help="output directory (default: next to this script)")
    ap.add_argument("--fit", default=FIT_FILE, help="the fitted parameters (default: fit.json next to this script)")
    ap.add_argument("--residuals", action="store_true",
                    help="also print the fit's residuals against Tables 1, 4 and 5 as Markdown tables (README.md)")
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)

    (Ms, Ks, stator_table), (Mr, Kr, rotor_table) = build_bodies(args.fit)
    fs = free_free_frequencies("stator", Ms, Ks)
    fr = free_free_frequencies("rotor", Mr, Kr)
    fsys = system_frequencies_alpha0(Ms, Ks, Mr, Kr)
    print(f"dofs: stator {Ms.shape[0]}, rotor {Mr.shape[0]}, system {len(fsys)}")
    print(f"{'mode':>4} {'rotor Hz':>10} {'stator Hz':>10} {'system Hz':>10} {'paper':>10}")
    paper = [0.0] * 7 + PAPER_SYSTEM_HZ
    for i in range(len(fsys)):
        cols = [f"{f[i]:10.4f}" if i < len(f) else " " * 10 for f in (fr, fs, fsys, paper)]
        print(f"{i + 1:4d} " + " ".join(cols))

    if args.residuals:
        print_residuals(args.fit)
    write_body(args.out, "stator", Ms, Ks, stator_table, [n[1] for n in STATOR_NODES])
    write_body(args.out, "rotor", Mr, Kr, rotor_table, [ROTOR_HUB[1]] + [a[1] for a in ROTOR_APPENDAGES])
    write_scene(args.out)
    print(f"wrote {args.out}/galileo.yaml and the stator/rotor matrices and node files")


if __name__ == "__main__":
    main()
