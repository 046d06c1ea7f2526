#!/usr/bin/python3
"""Single structures without joints, the models of docs/guide/real-models.md:

- a free-free plate-like grillage of beams in the xy plane (irregular spacing), written with only its out-of-plane
  dofs (uz, rx, ry per node: nodes 'c345', as a plate model exports them), 3 rigid-body modes:
  plate_M.mtx, plate_K.mtx (17 digits), plate_C.mtx (a stiffness-proportional damping matrix), plate_nodes.txt
  (read by plate.yaml), and plate.pch: the same plate as a Nastran DMIG punch (KAAX, MAAX, 8 significant digits as a
  punch writes them, with its GRID cards), also split as plate_dmig.pch + plate_grids.bdf and with a run's plate.f06
  (its bulk-data echo); a free beam with 6-dof nodes and a damping matrix (beam_free_*, read by beam_free.yaml);
- a cantilever beam (6 dofs per node, clamped end removed) as MORwiki-style MATLAB files: beam.mat (M, D, K, B, C)
  and damped.mat (M, E, K, B, Cp, Cv: a displacement and a velocity output).

Run: /usr/bin/python3 examples/single_structure/generate.py
"""
import os

import numpy as np
import scipy.io
import scipy.sparse as sp

HERE = os.path.dirname(os.path.abspath(__file__))


def beam_element(xa, xb, E=70e9, G=27e9, A=1e-3, Iy=4e-7, Iz=4e-7, rho=2700.0):
    """12 x 12 stiffness and consistent mass of a 3-D Euler-Bernoulli beam (global axes)."""
    xa, xb = np.asarray(xa, float), np.asarray(xb, float)
    L = np.linalg.norm(xb - xa)
    ex = (xb - xa) / L
    up = np.array([0.0, 0.0, 1.0]) if abs(ex[2]) < 0.9 else np.array([1.0, 0.0, 0.0])
    ez = up - (up @ ex) * ex
    ez /= np.linalg.norm(ez)
    ey = np.cross(ez, ex)
    J = Iy + Iz
    k, m = np.zeros((12, 12)), np.zeros((12, 12))
    for (i, j), s, inertia in (((0, 6), E * A / L, rho * A * L), ((3, 9), G * J / L, rho * J * L)):
        k[np.ix_([i, j], [i, j])] += s * np.array([[1, -1], [-1, 1]])
        m[np.ix_([i, j], [i, j])] += inertia / 6 * np.array([[2, 1], [1, 2]])
    for dofs, I, sg in (((1, 5, 7, 11), Iz, 1.0), ((2, 4, 8, 10), Iy, -1.0)):
        k[np.ix_(dofs, dofs)] += E * I / L**3 * np.array([[12, 6 * L * sg, -12, 6 * L * sg],
                                                          [6 * L * sg, 4 * L**2, -6 * L * sg, 2 * L**2],
                                                          [-12, -6 * L * sg, 12, -6 * L * sg],
                                                          [6 * L * sg, 2 * L**2, -6 * L * sg, 4 * L**2]])
        m[np.ix_(dofs, dofs)] += rho * A * L / 420 * np.array([[156, 22 * L * sg, 54, -13 * L * sg],
                                                               [22 * L * sg, 4 * L**2, 13 * L * sg, -3 * L**2],
                                                               [54, 13 * L * sg, 156, -22 * L * sg],
                                                               [-13 * L * sg, -3 * L**2, -22 * L * sg, 4 * L**2]])
    T = np.kron(np.eye(4), np.vstack([ex, ey, ez]))
    return T.T @ k @ T, T.T @ m @ T


def plate(nx=5, ny=4, hx=0.37, hy=0.43):
    """K, M on (uz, rx, ry) per node and the node rows (id, x, y, z, 'c345')."""
    pts = [(i * hx, j * hy, 0.0) for j in range(ny) for i in range(nx)]
    n = len(pts)
    K, M = np.zeros((6 * n, 6 * n)), np.zeros((6 * n, 6 * n))
    for j in range(ny):
        for i in range(nx):
            a = j * nx + i
            for b in ([a + 1] if i + 1 < nx else []) + ([a + nx] if j + 1 < ny else []):
                k, m = beam_element(pts[a], pts[b])
                idx = np.r_[6 * a:6 * a + 6, 6 * b:6 * b + 6]
                K[np.ix_(idx, idx)] += k
                M[np.ix_(idx, idx)] += m
    # beams in the xy plane: the out-of-plane dofs (uz rx ry) decouple exactly from the in-plane ones
    keep = np.array([6 * i + c for i in range(n) for c in (2, 3, 4)])
    nodes = [(i + 1, *p, "c345") for i, p in enumerate(pts)]
    return K[np.ix_(keep, keep)], M[np.ix_(keep, keep)], nodes


def beam(n=11, length=2.0):
    """K, M of a beam along x with 6 dofs per node, node 1 clamped (its dofs removed)."""
    pts = [(x, 0.0, 0.0) for x in np.linspace(0, length, n)]
    K, M = np.zeros((6 * n, 6 * n)), np.zeros((6 * n, 6 * n))
    for e in range(n - 1):
        k, m = beam_element(pts[e], pts[e + 1], Iy=2e-7, Iz=3e-7)
        K[6 * e:6 * e + 12, 6 * e:6 * e + 12] += k
        M[6 * e:6 * e + 12, 6 * e:6 * e + 12] += m
    return K[6:, 6:], M[6:, 6:]


def free_beam(n=9, length=2.0):
    """K, M (6 dofs per node) and node rows of a free beam along x."""
    pts = [(x, 0.0, 0.0) for x in np.linspace(0, length, n)]
    K, M = np.zeros((6 * n, 6 * n)), np.zeros((6 * n, 6 * n))
    for e in range(n - 1):
        k, m = beam_element(pts[e], pts[e + 1], Iy=2e-7, Iz=3e-7)
        K[6 * e:6 * e + 12, 6 * e:6 * e + 12] += k
        M[6 * e:6 * e + 12, 6 * e:6 * e + 12] += m
    return K, M, [(i + 1, *p, "6") for i, p in enumerate(pts)]


def dmig_star(name, A, dofs):
    """Long-field DMIG* cards (upper triangle, IFO 6, 8 significant digits), as Nastran punches them."""
    lines = ["%-8s%-16s%16s%16s%16s" % ("DMIG*", name, "0", "6", "2"),
             "%-8s%16s%16s%16s%16s" % ("*", "0", "", "", len(dofs))]
    for j, (gj, cj) in enumerate(dofs):
        rows = [i for i in range(j + 1) if A[i, j] != 0]
        fields = [name, str(gj), str(cj), ""]
        for i in rows:
            fields += [str(dofs[i][0]), str(dofs[i][1]), "%.7E" % A[i, j], ""]
        for k in range(0, len(fields), 4):
            chunk = fields[k:k + 4]
            head = "DMIG*" if k == 0 else "*"
            lines.append("%-8s" % head + "".join(("%-16s" if f[:1].isalpha() else "%16s") % f for f in chunk))
    return lines


def main():
    K, M, nodes = plate()
    C = 1e-5 * K      # a stiffness-proportional damping matrix (leaves the rigid motions undamped)
    for name, A in (("K", K), ("M", M), ("C", C)):
        scipy.io.mmwrite(os.path.join(HERE, "plate_%s.mtx" % name), sp.coo_matrix(np.where(np.abs(A) > 0, A, 0.0)), symmetry="symmetric",
                         comment="single_structure plate, generated by examples/single_structure/generate.py",
                         precision=17)
    with open(os.path.join(HERE, "plate_nodes.txt"), "w") as f:
        f.write("# id x y z dofs: a 5 x 4 grillage in the xy plane, uz rx ry per node\n")
        for r in nodes:
            f.write("%d %r %r %r %s\n" % r)
    dofs = [(r[0], c) for r in nodes for c in (3, 4, 5)]
    with open(os.path.join(HERE, "plate.pch"), "w") as f:
        f.write("$ the single_structure plate as a DMIG punch (PARAM,EXTOUT,DMIGPCH style), generate.py\n")
        for r in nodes:
            f.write("%-8s%8d%8s%8s%8s%8s\n" % ("GRID", r[0], "", *("%.4f" % x for x in r[1:4])))
        f.write("\n".join(dmig_star("KAAX", K, dofs) + dmig_star("MAAX", M, dofs)) + "\n")
    # the same punch split as Nastran runs write it: GRID cards in the bulk data, DMIG matrices in the punch
    with open(os.path.join(HERE, "plate.pch")) as f:
        lines = f.read().splitlines()
    with open(os.path.join(HERE, "plate_grids.bdf"), "w") as f:
        f.write("SOL 103\nCEND\nBEGIN BULK\n" + "\n".join(x for x in lines if x.startswith("GRID")) + "\nENDDATA\n")
    with open(os.path.join(HERE, "plate_dmig.pch"), "w") as f:
        f.write("\n".join(x for x in lines if not x.startswith("GRID")) + "\n")
    # a run's .f06: its sorted bulk-data echo holds the GRID cards (a page break inside it, as Nastran prints it)
    grids = [x for x in lines if x.startswith("GRID")]
    page = "1    SINGLE STRUCTURE PLATE                                        NOVEMBER  29, 2026  MSC Nastran   PAGE %5d\n"
    head = ("0                                                 S O R T E D   B U L K   D A T A   E C H O\n"
            "                 ENTRY\n                 COUNT        .   1  ..   2  ..   3  ..   4  ..   5  ..   6  ..   "
            "7  ..   8  ..   9  ..  10  .\n")
    with open(os.path.join(HERE, "plate.f06"), "w") as f:
        f.write(page % 1 + "0        N A S T R A N    E X E C U T I V E    C O N T R O L    E C H O\n     SOL 103\n"
                "     CEND\n" + page % 2 + head)
        for k, card in enumerate(grids + ["ENDDATA"], start=1):
            if k == 11:
                f.write(page % 3 + head)
            f.write("%20d-        %s\n" % (k, card))
        f.write("                        TOTAL COUNT=       %d\n" % (len(grids) + 1))
        f.write(page % 4 + "0                                           R E A L   E I G E N V A L U E S\n")
    # a free beam with 6 dofs per node and a damping matrix: beam_free.yaml
    Kf, Mf, nf = free_beam()
    for key, A in (("K", Kf), ("M", Mf), ("C", 2e-5 * Kf)):
        scipy.io.mmwrite(os.path.join(HERE, "beam_free_%s.mtx" % key), sp.coo_matrix(np.where(np.abs(A) > 0, A, 0.0)),
                         symmetry="symmetric", precision=17,
                         comment="single_structure free beam, generated by examples/single_structure/generate.py")
    with open(os.path.join(HERE, "beam_free_nodes.txt"), "w") as f:
        f.write("# id x y z dofs: a free beam along x\n")
        for r in nf:
            f.write("%d %r %r %r %s\n" % r)
    # MORwiki-style second-order models: M q'' + D q' + K q = B u, y = C q (or Cp q + Cv q')
    Kb, Mb = beam()
    n = len(Kb)
    B = np.zeros((n, 1))
    B[n - 4, 0] = 1.0                     # a force along z at the tip (node 11: dofs n-6 .. n-1, uz is n-4)
    C = np.zeros((2, n))
    C[0, n - 4] = 1.0                     # tip uz
    C[1, n - 6 * 5 - 4] = 1.0             # uz at node 6
    scipy.io.savemat(os.path.join(HERE, "beam.mat"), dict(M=sp.csc_matrix(Mb), K=sp.csc_matrix(Kb),
                                                          D=sp.csc_matrix(2e-5 * Kb), B=B, C=C))
    scipy.io.savemat(os.path.join(HERE, "damped.mat"), dict(M=sp.csc_matrix(Mb), K=sp.csc_matrix(Kb),
                                                            E=sp.csc_matrix(1e-5 * Kb + 0.5 * Mb), B=B, Cp=C[:1],
                                                            Cv=C[1:]))


if __name__ == "__main__":
    main()
