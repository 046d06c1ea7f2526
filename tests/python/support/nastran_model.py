"""A small free-free Nastran model written card by card, and its reference built directly in basic coordinates.

The model: a 3-D frame of 8 grids and 13 Euler-Bernoulli beams, lumped masses, and one scalar point
(a Craig-Bampton-like modal coordinate: stiffness w^2 to nothing, mass coupled to a grid's translations). The
reference is the frame in basic coordinates in NumPy (beam stiffness rotated from the element frame, lumped
masses), with the components kryflex must leave out condensed statically:
  grid 107: only uz rx ry (its ux uy rz condensed)        -> nodes-file dofs c345, CD rotated about z only
  grid 108: translations only (its rotations condensed)    -> dofs 3, CD cylindrical, CP spherical
  grids 103, 105: no rotary inertia                        -> their rotations are absent from MAAX (in KAAX)
Coordinate systems: CORD2R 10, CORD2C 20 (defined in 10: RID=10), CORD2S 30, CORD2R 40 (z-rotation), CORD1R 60
(on three grids); the grids use them in CP and CD. The punch holds KAAX and MAAX as long-field DMIG* cards in each grid's CD system:
K_cd = T^T K_basic T with u_basic = T u_cd (T = blockdiag(R, R), R's columns the CD axes at the grid), computed
here from the coordinate-system definitions independently of the converter. The bulk data (GRID/GRID*, CORD2x,
SPOINT, PARAM,WTMASS) goes in a .bdf and, as Nastran echoes it, in a .f06.
"""
import numpy as np

WTMASS = 0.00259
SPOINT = 150
GRID_IDS = [101, 102, 103, 104, 105, 106, 107, 108]
NOMINAL = {101: (0.0, 0.0, 0.0), 102: (2.0, 0.0, 0.0), 103: (2.0, 1.5, 0.0), 104: (0.0, 1.5, 0.0),
           105: (0.0, 0.0, 1.2), 106: (2.0, 0.1, 1.2), 107: (2.1, 1.5, 1.25), 108: (1.0, 0.7, 2.0)}
BEAMS = [(101, 102), (102, 103), (103, 104), (104, 101), (101, 105), (102, 106), (103, 107), (105, 106),
         (106, 107), (105, 108), (106, 108), (101, 103), (104, 105)]
CP = {101: 0, 102: 10, 103: 20, 104: 10, 105: 20, 106: 0, 107: 0, 108: 30}
CD = {101: 0, 102: 10, 103: 20, 104: 20, 105: 30, 106: 60, 107: 40, 108: 20}
COMPONENTS = {g: [1, 2, 3, 4, 5, 6] for g in GRID_IDS}
COMPONENTS[107] = [3, 4, 5]
COMPONENTS[108] = [1, 2, 3]
NO_ROTARY_INERTIA = (103, 105)
MASS = {101: 3.0, 102: 2.5, 103: 2.0, 104: 2.0, 105: 1.5, 106: 2.2, 107: 1.8, 108: 1.2}
INERTIA = {101: 0.05, 102: 0.04, 104: 0.03, 106: 0.06, 107: 0.02}
SPOINT_K, SPOINT_M = 50.0, 1.0
SPOINT_COUPLING = (104, np.array([0.1, -0.05, 0.08]))   # mass coupling of the scalar point to 104's ux uy uz

# coordinate systems: (type, RID, A, B, C) as on the CORD2x cards (short decimals: written exactly)
SYSTEMS = {
    10: ("R", 0, (1.0, 2.0, 0.5), (1.5, 2.3, 1.4), (2.0, 1.0, 0.7)),
    20: ("C", 10, (0.3, -0.2, 0.1), (0.1, 0.4, 1.0), (1.2, 0.1, -0.3)),
    30: ("S", 0, (-0.5, 0.2, 0.3), (-0.4, 0.1, 1.3), (0.5, 0.6, 0.2)),
    40: ("R", 0, (0.25, 0.5, 0.0), (0.25, 0.5, 2.0), (1.116025, 1.0, 0.0)),   # z-rotation by 30 degrees
    60: ("1R", None, 104, 105, 102),      # CORD1R: origin at grid 104, z toward 105, xz-plane through 102
}


def frame_of(cid):
    """(origin, A) of system cid in basic: A's columns are the system's i, j, k (the CORD2x rule)."""
    if cid == 0:
        return np.zeros(3), np.eye(3)
    kind, rid, a, b, c = SYSTEMS[cid]
    if kind.startswith("1"):                                  # CORD1x: the three points are grids
        basic = grid_fields()[1]
        a, b, c = basic[a], basic[b], basic[c]
    else:
        o_r, A_r = frame_of(rid)
        a, b, c = (o_r + A_r @ np.array(p) for p in (a, b, c))   # the points are given in RID (rectangular here)
    k = (b - a) / np.linalg.norm(b - a)
    j = np.cross(k, c - a)
    j /= np.linalg.norm(j)
    i = np.cross(j, k)
    return a, np.column_stack([i, j, k])


def to_system(cid, p):
    """Basic point p in system cid's coordinates (r, theta deg, z) or (r, theta deg, phi deg)."""
    o, A = frame_of(cid)
    x = A.T @ (np.asarray(p) - o)
    kind = "R" if cid == 0 else SYSTEMS[cid][0][-1]
    if kind == "R":
        return x
    if kind == "C":
        return np.array([np.hypot(x[0], x[1]), np.degrees(np.arctan2(x[1], x[0])), x[2]])
    r = np.linalg.norm(x)
    return np.array([r, np.degrees(np.arccos(x[2] / r)), np.degrees(np.arctan2(x[1], x[0]))])


def from_system(cid, q):
    o, A = frame_of(cid)
    kind = "R" if cid == 0 else SYSTEMS[cid][0][-1]
    q = np.asarray(q, dtype=float)
    if kind == "R":
        x = q
    elif kind == "C":
        t = np.radians(q[1])
        x = np.array([q[0] * np.cos(t), q[0] * np.sin(t), q[2]])
    else:
        t, f = np.radians(q[1]), np.radians(q[2])
        x = q[0] * np.array([np.sin(t) * np.cos(f), np.sin(t) * np.sin(f), np.cos(t)])
    return o + A @ x


def cd_axes(cid, p):
    """R: columns = system cid's displacement directions at basic point p."""
    o, A = frame_of(cid)
    kind = "R" if cid == 0 else SYSTEMS[cid][0][-1]
    if kind == "R":
        return A
    x = A.T @ (np.asarray(p) - o)
    if kind == "C":
        t = np.arctan2(x[1], x[0])
        e_r, e_t, e_z = [np.cos(t), np.sin(t), 0], [-np.sin(t), np.cos(t), 0], [0, 0, 1]
        return A @ np.column_stack([e_r, e_t, e_z])
    r = np.linalg.norm(x)
    t, f = np.arccos(x[2] / r), np.arctan2(x[1], x[0])
    e_r = [np.sin(t) * np.cos(f), np.sin(t) * np.sin(f), np.cos(t)]
    e_t = [np.cos(t) * np.cos(f), np.cos(t) * np.sin(f), -np.sin(t)]
    e_f = [-np.sin(f), np.cos(f), 0]
    return A @ np.column_stack([e_r, e_t, e_f])


def large(value):
    """A real in a 16-character field with as many digits as fit: Nastran's exponent without E (1.23456789012+05)
    gives 11-12 significant digits."""
    for digits in range(11, 4, -1):
        text = f"{value:.{digits}E}".replace("E", "")
        if len(text) <= 16:
            return f"{text:>16}"
    raise ValueError(value)


def real(text):
    """The value of a Nastran real as written by large(): 1.25+03 is 1.25E+03."""
    import re
    return float(re.sub(r"(?<=[0-9.])([+-]\d+)$", r"E\1", text.strip()))


def grid_fields():
    """{grid: the three coordinate strings on its GRID card (in CP)} and the exact basic positions they give."""
    fields, basic = {}, {}
    for g in GRID_IDS:
        q = to_system(CP[g], NOMINAL[g])
        text = [large(v) for v in q]
        fields[g] = text
        basic[g] = from_system(CP[g], [real(t) for t in text])
    return fields, basic


# ---------------------------------------------------------------- the reference in basic coordinates

def beam_stiffness(p1, p2, E=7.0e10, G=2.7e10, A=1.0e-3, Iy=2.0e-5, Iz=3.0e-5, J=4.0e-5):
    """12 x 12 Euler-Bernoulli frame element in basic dofs (u1 r1 u2 r2)."""
    d = np.asarray(p2) - np.asarray(p1)
    L = np.linalg.norm(d)
    ex = d / L
    ref = np.array([0.0, 0.0, 1.0]) if abs(ex[2]) < 0.9 else np.array([1.0, 0.0, 0.0])
    ey = np.cross(ref, ex)
    ey /= np.linalg.norm(ey)
    ez = np.cross(ex, ey)
    k = np.zeros((12, 12))
    a, t = E * A / L, G * J / L
    k[np.ix_([0, 6], [0, 6])] = a * np.array([[1, -1], [-1, 1]])
    k[np.ix_([3, 9], [3, 9])] = t * np.array([[1, -1], [-1, 1]])
    for (u, r, I, s) in ((1, 5, Iz, 1.0), (2, 4, Iy, -1.0)):   # bending in xy (uy, rz) and xz (uz, ry)
        c = E * I / L ** 3
        idx = [u, r, u + 6, r + 6]
        kb = c * np.array([[12, 6 * L, -12, 6 * L], [6 * L, 4 * L * L, -6 * L, 2 * L * L],
                           [-12, -6 * L, 12, -6 * L], [6 * L, 2 * L * L, -6 * L, 4 * L * L]])
        S = np.diag([1.0, s, 1.0, s])
        k[np.ix_(idx, idx)] += S @ kb @ S
    Lam = np.vstack([ex, ey, ez])
    T = np.kron(np.eye(4), Lam)
    return T.T @ k @ T


def reference(basic):
    """(K, M, dofs) of the model in basic coordinates, dofs [(id, comp)] with the left-out components condensed."""
    full = [(g, c) for g in GRID_IDS for c in range(1, 7)] + [(SPOINT, 0)]
    index = {d: i for i, d in enumerate(full)}
    n = len(full)
    K, M = np.zeros((n, n)), np.zeros((n, n))
    for g1, g2 in BEAMS:
        idx = [index[g1, c] for c in range(1, 7)] + [index[g2, c] for c in range(1, 7)]
        K[np.ix_(idx, idx)] += beam_stiffness(basic[g1], basic[g2])
    for g in GRID_IDS:
        for c in (1, 2, 3):
            M[index[g, c], index[g, c]] = MASS[g]
        for c in (4, 5, 6):
            M[index[g, c], index[g, c]] = INERTIA.get(g, 0.0)
    M[index[107, 1], index[107, 1]] = M[index[107, 2], index[107, 2]] = M[index[107, 6], index[107, 6]] = 0.0
    s = index[SPOINT, 0]
    K[s, s], M[s, s] = SPOINT_K, SPOINT_M
    g, cvec = SPOINT_COUPLING
    for c in range(3):
        M[s, index[g, c + 1]] = M[index[g, c + 1], s] = cvec[c]
    kept = [d for d in full if d[1] == 0 or d[1] in COMPONENTS[d[0]]]
    K, M = condense(K, M, [index[d] for d in kept])
    return K, M, kept


def condense(K, M, keep):
    """Static (Guyan) condensation onto keep: exact for dofs without mass, which the dropped ones are here."""
    keep = np.asarray(keep)
    drop = np.setdiff1d(np.arange(K.shape[0]), keep)
    if drop.size == 0:
        return K, M
    assert np.all(M[np.ix_(drop, drop)] == 0) and np.all(M[np.ix_(drop, keep)] == 0)
    X = -np.linalg.solve(K[np.ix_(drop, drop)], K[np.ix_(drop, keep)])
    Kc = K[np.ix_(keep, keep)] + K[np.ix_(keep, drop)] @ X
    return 0.5 * (Kc + Kc.T), M[np.ix_(keep, keep)]


def eigenvalues(K, M):
    """The finite eigenvalues of K x = lambda M x: massless dofs (zero rows of M) condensed first."""
    massless = np.flatnonzero(np.abs(M).sum(axis=1) == 0)
    keep = np.setdiff1d(np.arange(K.shape[0]), massless)
    Kc, Mc = condense(K, M, keep)
    import scipy.linalg
    return scipy.linalg.eigh(Kc, Mc, eigvals_only=True)


def rigid_modes(dofs, xyz):
    """n x 6 rigid-body modes about the origin from node coordinates: u = t + theta x x, r = theta; 0 on scalar
    points."""
    Phi = np.zeros((len(dofs), 6))
    for row, (g, c) in enumerate(dofs):
        if c == 0:
            continue
        x = xyz[g]
        if c <= 3:
            Phi[row, c - 1] = 1.0
            e = np.eye(3)[c - 1]
            for r in range(3):   # (theta_r e_r) x x . e
                Phi[row, 3 + r] = np.dot(np.cross(np.eye(3)[r], x), e)
        else:
            Phi[row, c - 1] = 1.0
    return Phi


# ---------------------------------------------------------------- the files

def transform(basic, dofs):
    """T with u_basic = T u_cd over dofs (the CD axes at each grid)."""
    n = len(dofs)
    T = np.zeros((n, n))
    pos = {d: i for i, d in enumerate(dofs)}
    for g in GRID_IDS:
        R = cd_axes(CD[g], basic[g])
        for triple in (1, 4):
            comps = [c for c in COMPONENTS[g] if triple <= c < triple + 3]
            for a in comps:
                for b in comps:
                    T[pos[g, a], pos[g, b]] = R[a - triple, b - triple]
    T[pos[SPOINT, 0], pos[SPOINT, 0]] = 1.0
    return T


def dmig_star(name, A, dofs, skip_zero_columns=False):
    """Long-field DMIG* cards (upper triangle, IFO 6), as Nastran punches with PARAM,EXTOUT,DMIGPCH."""
    lines = [f"{'DMIG*':<8}{name:<16}{'0':>16}{'6':>16}{'2':>16}",
             f"{'*':<8}{'0':>16}{'':>16}{'':>16}{str(len(dofs)):>16}"]
    for j, (gj, cj) in enumerate(dofs):
        rows = [i for i in range(j + 1) if A[i, j] != 0]
        if not rows:
            continue
        fields = [name, str(gj), str(cj) if cj else "", ""]
        for i in rows:
            gi, ci = dofs[i]
            fields += [str(gi), str(ci) if ci else "", large(A[i, j]), ""]
        for k in range(0, len(fields), 4):
            chunk = fields[k:k + 4] + [""] * (4 - len(fields[k:k + 4]))
            head = f"{'DMIG*':<8}" if k == 0 else f"{'*':<8}"
            lines.append(head + "".join(f"{f:<16}" if f[:1].isalpha() else f"{f:>16}" for f in chunk))
    return lines


def bulk_cards(fields):
    """The bulk data: PARAM, CORD2x, GRID (small field for some, GRID* for others), SPOINT."""
    lines = ["PARAM   WTMASS  %-8s" % WTMASS]
    for cid, (kind, rid, a, b, c) in SYSTEMS.items():
        if kind.startswith("1"):
            lines.append(f"CORD{kind:<4}{cid:>8}{a:>8}{b:>8}{c:>8}")
            continue
        vals = [str(v) for v in (*a, *b, *c)]
        lines.append(f"CORD2{kind:<3}{cid:>8}{rid:>8}" + "".join(f"{v:>8}" for v in vals[:6]) + "+C" + str(cid))
        lines.append(f"{'+C' + str(cid):<8}" + "".join(f"{v:>8}" for v in vals[6:]))
    for k, g in enumerate(GRID_IDS):
        x = fields[g]
        lines.append(f"{'GRID*':<8}{g:>16}{CP[g]:>16}{x[0]:>16}{x[1]:>16}")
        lines.append(f"{'*':<8}{x[2]:>16}{CD[g]:>16}")
    lines.append(f"{'SPOINT':<8}{SPOINT:>8}")
    return lines


def write_model(folder):
    """Writes model.pch (DMIG* KAAX, MAAX), model.bdf (a whole deck) and model.f06 (its bulk echo); returns the
    reference {'K', 'M', 'dofs', 'basic'} (basic-coordinate matrices over dofs, grid positions)."""
    import os
    fields, basic = grid_fields()
    K, M, dofs = reference(basic)
    T = transform(basic, dofs)
    K_cd, M_cd = T.T @ K @ T, T.T @ M @ T
    # massless rotations: their rows and columns are zero in the mass, so MAAX leaves them out
    for g in NO_ROTARY_INERTIA:
        for c in (4, 5, 6):
            assert not M_cd[dofs.index((g, c))].any()
    with open(os.path.join(folder, "model.pch"), "w") as f:
        f.write("\n".join(dmig_star("KAAX", K_cd, dofs) + dmig_star("MAAX", M_cd, dofs)) + "\n")
    bulk = bulk_cards(fields)
    with open(os.path.join(folder, "model.bdf"), "w") as f:
        f.write("SOL 103\nCEND\nTITLE = kryflex test frame\nBEGIN BULK\n" + "\n".join(bulk) + "\nENDDATA\n")
    with open(os.path.join(folder, "model.f06"), "w") as f:
        f.write(f06_echo(bulk))
    return {"K": K, "M": M, "dofs": dofs, "basic": basic}


def f06_echo(bulk):
    """An .f06 as MSC Nastran prints it: headers, a page break inside the sorted bulk-data echo, then results."""
    page = ("1    KRYFLEX TEST FRAME                                                      NOVEMBER  24, 2026  "
            "MSC Nastran  2/ 1/22   PAGE     %d\n")
    head = ("0                                                 S O R T E D   B U L K   D A T A   E C H O\n"
            "                 ENTRY\n"
            "                 COUNT        .   1  ..   2  ..   3  ..   4  ..   5  ..   6  ..   7  ..   8  ..   9  "
            "..  10  .\n")
    out = [page % 1, "0        N A S T R A N    E X E C U T I V E    C O N T R O L    E C H O\n", "     SOL 103\n",
           "     CEND\n", page % 2, head]
    for k, card in enumerate(bulk + ["ENDDATA"], start=1):
        if k == 9:
            out += [page % 3, head]
        out.append(f"{k:>20d}-        {card}\n")
    out.append("                        TOTAL COUNT=       %d\n" % (len(bulk) + 1))
    out.append(page % 4 + "0                                           R E A L   E I G E N V A L U E S\n")
    return "".join(out)


def write_punch(folder, K, M, nodes, name="plate"):
    """A body exported as a commercial code writes it: KAAX and MAAX as long-field DMIG* cards (11-12 digits) over the
    nodes' components (nodes: rows id, x, y, z, 'c345' or 6) and the GRIDs in basic coordinates in a .bdf. Returns the
    two paths (punch, bulk)."""
    import os
    dofs = []
    for row in nodes:
        comps = [int(c) for c in row[4][1:]] if isinstance(row[4], str) else list(range(1, int(row[4]) + 1))
        dofs += [(int(row[0]), c) for c in comps]
    pch, bdf = os.path.join(folder, name + ".pch"), os.path.join(folder, name + ".bdf")
    with open(pch, "w") as f:
        f.write("\n".join(dmig_star("KAAX", np.asarray(K), dofs) + dmig_star("MAAX", np.asarray(M), dofs)) + "\n")
    with open(bdf, "w") as f:
        f.write("BEGIN BULK\n" + "\n".join(f"{'GRID*':<8}{int(r[0]):>16}{0:>16}{large(r[1])}{large(r[2])}\n"
                                            f"{'*':<8}{large(r[3])}" for r in nodes) + "\nENDDATA\n")
    return pch, bdf
