"""Small models with boundary conditions and their dense references (NumPy/SciPy only), shared by
test_boundary_conditions.py and its 2-rank probe. Nothing here calls kryflex's numerics."""
import numpy as np
import scipy.linalg as sl

ZETA = 0.01
BAND = [0.5, 200.0]


def beam_element(xa, xb, E=70e9, G=27e9, A=1e-3, Iy=2e-7, Iz=3e-7, rho=2700.0):
    """3-D Euler-Bernoulli beam element (12 x 12 stiffness and consistent mass, global axes)."""
    xa, xb = np.asarray(xa, float), np.asarray(xb, float)
    L = np.linalg.norm(xb - xa)
    ex = (xb - xa) / L
    up = np.array([0.0, 0.0, 1.0]) if abs(ex[2]) < 0.9 else np.array([1.0, 0.0, 0.0])
    ez = up - (up @ ex) * ex
    ez /= np.linalg.norm(ez)
    ey = np.cross(ez, ex)
    J = Iy + Iz
    k = np.zeros((12, 12))
    m = np.zeros((12, 12))
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


def beam(points, tip_mass=0.5):
    """K, M (6 dofs per node) and node rows (id, x, y, z, 6), ids 1.. along the points."""
    n = len(points)
    K = np.zeros((6 * n, 6 * n))
    M = np.zeros((6 * n, 6 * n))
    for e in range(n - 1):
        k, m = beam_element(points[e], points[e + 1])
        K[6 * e:6 * e + 12, 6 * e:6 * e + 12] += k
        M[6 * e:6 * e + 12, 6 * e:6 * e + 12] += m
    M[6 * (n - 1):6 * (n - 1) + 3, 6 * (n - 1):6 * (n - 1) + 3] += tip_mass * np.eye(3)
    nodes = [[i + 1, *p, 6] for i, p in enumerate(points)]
    return K, M, nodes


def modal_frf(Ms, Ks, Gs, Hs, f_hz, zeta=ZETA, rigid=None):
    """Modal FRF with uniform modal damping; rigid (columns spanning the null space of Ks) undamped. Dense."""
    w = 2 * np.pi * np.asarray(f_hz)
    lam, Phi = sl.eigh(Ks, Ms)
    if rigid is not None and rigid.shape[1]:
        R = rigid @ np.linalg.inv(np.linalg.cholesky(rigid.T @ Ms @ rigid)).T
        P = np.eye(len(Ms)) - R @ R.T @ Ms
        Q = sl.null_space((Ms @ R).T)
        lam, V = sl.eigh(Q.T @ Ks @ Q, Q.T @ Ms @ Q)
        Phi = Q @ V
    else:
        R = np.zeros((len(Ms), 0))
    T = np.zeros((len(w), Hs.shape[0], Gs.shape[1]), complex)
    HP, PG = Hs @ Phi, Phi.T @ Gs
    HR, RG = Hs @ R, R.T @ Gs
    for i, wi in enumerate(w):
        d = lam - wi**2 + 2j * zeta * np.sqrt(np.maximum(lam, 0)) * wi
        T[i] = (HP / d) @ PG - (HR @ RG) / wi**2
    return T


def hinf_error(Tf, Tr):
    """max over pairs of max_w |Tf - Tr| / max_w |Tf| (pairs below 1e-4 of the largest peak measured against it)."""
    peak = np.abs(Tf).max(axis=0)
    floor = 1e-4 * peak.max()
    return float((np.abs(Tf - Tr).max(axis=0) / np.maximum(peak, floor)).max())


def rot_z(deg):
    a = np.radians(deg)
    return np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1.0]])


def tie_rows(n, i_p, i_c, R, revolute_axis=None):
    """Rows of u_p - R u_c = 0 (translations) and of the rotations (all 3, or the 2 perpendicular to the axis)."""
    rows = []
    for comp0 in (0, 3):
        E = np.eye(3)
        if comp0 == 3 and revolute_axis is not None:
            E = sl.null_space(np.asarray(revolute_axis, float)[None, :]).T
        for e in E:
            r = np.zeros(n)
            r[i_p + comp0:i_p + comp0 + 3] += e
            r[i_c + comp0:i_c + comp0 + 3] -= e @ R
            rows.append(r)
    return rows


def grounded_arm():
    """Body 'post' (a beam along z, 1 m) on a revolute joint to ground at its base (axis z), body 'arm' (a beam
    along x, 1.5 m in its own frame) on a revolute joint (axis z) at the post's top."""
    Kp, Mp, np_ = beam([(0.0, 0.0, z) for z in np.linspace(0, 1.0, 6)], tip_mass=2.0)
    Ka, Ma, na = beam([(x, 0.0, 0.0) for x in np.linspace(0, 1.5, 7)], tip_mass=0.3)
    spec = {"name": "grounded_arm",
            "bodies": {"post": {"mass": Mp, "stiffness": Kp, "nodes": np_, "interfaces": {"base": 1, "top": 6}},
                       "arm": {"mass": Ma, "stiffness": Ka, "nodes": na, "interfaces": {"root": 1}}},
            "joints": {"pivot": {"type": "revolute", "parent": "ground", "child": "post", "child_interface": "base",
                                 "axis": [0, 0, 1]},
                       "elbow": {"type": "revolute", "parent": "post", "parent_interface": "top", "child": "arm",
                                 "child_interface": "root", "axis": [0, 0, 1]}},
            "inputs": {"torque": [{"body": "arm", "node": 1, "dof": "rz"}, {"body": "post", "node": 6, "dof": "rz",
                                                                             "weight": -1.0}],
                       "push": [{"body": "arm", "node": 7, "dof": "uz"}]},
            "outputs": {"tip_y": [{"body": "arm", "node": 7, "dof": "uy"}],
                        "tip_z": [{"body": "arm", "node": 7, "dof": "uz"}],
                        "post_x": [{"body": "post", "node": 6, "dof": "ux"}]},
            "angles": [0.0, 40.0, 90.0], "band": BAND, "damping": ZETA, "accuracy": 0.02}
    return spec


def grounded_arm_reference(spec, angle_deg):
    """Dense system of grounded_arm at the elbow angle: stacked dofs, constraint null space (SVD)."""
    Mp, Kp = spec["bodies"]["post"]["mass"], spec["bodies"]["post"]["stiffness"]
    Ma, Ka = spec["bodies"]["arm"]["mass"], spec["bodies"]["arm"]["stiffness"]
    npost = len(Kp)
    n = npost + len(Ka)
    M = sl.block_diag(Mp, Ma)
    K = sl.block_diag(Kp, Ka)
    rows = []
    for c in (0, 1, 2, 3, 4):         # ground: base translations and rx, ry
        r = np.zeros(n)
        r[c] = 1
        rows.append(r)
    rows += tie_rows(n, 6 * 5, npost, rot_z(angle_deg), revolute_axis=[0, 0, 1])
    P = sl.null_space(np.array(rows))
    G = np.zeros((n, 2))
    G[npost + 5, 0] = 1
    G[6 * 5 + 5, 0] = -1
    G[npost + 6 * 6 + 2, 1] = 1
    H = np.zeros((3, n))
    H[0, npost + 6 * 6 + 1] = 1
    H[1, npost + 6 * 6 + 2] = 1
    H[2, 6 * 5 + 0] = 1
    Ks = P.T @ K @ P
    return P.T @ M @ P, 0.5 * (Ks + Ks.T), P.T @ G, H @ P


def rigid_null(Ks, rtol=1e-9):
    """Null space of Ks by SVD (relative tolerance)."""
    U, s, Vt = np.linalg.svd(Ks)
    return Vt[s <= rtol * s[0]].T


def clamped_beam():
    """A 2 m cantilever along x, clamped at node 1."""
    K, M, nodes = beam([(x, 0.0, 0.0) for x in np.linspace(0, 2.0, 11)])
    return {"name": "clamped", "bodies": {"beam": {"mass": M, "stiffness": K, "nodes": nodes,
                                                   "constraints": [{"node": 1, "dofs": "123456"}]}},
            "inputs": {"fy": [{"body": "beam", "node": 11, "dof": "uy"}], "fz": [{"body": "beam", "node": 8, "dof": "uz"}]},
            "outputs": {"y": [{"body": "beam", "node": 11, "dof": "uy"}], "z": [{"body": "beam", "node": 6, "dof": "uz"}],
                        "t": [{"body": "beam", "node": 11, "dof": "rx"}]},
            "band": BAND, "damping": ZETA, "accuracy": 0.01}


def free_clustered_beam():
    """The cantilever's beam left free, with equal section inertias: 6 rigid modes, the bending frequencies in y and z
    in pairs (double eigenvalues)."""
    pts = [(x, 0.0, 0.0) for x in np.linspace(0, 2.0, 11)]
    n = len(pts)
    K, M = np.zeros((6 * n, 6 * n)), np.zeros((6 * n, 6 * n))
    for e in range(n - 1):
        k, m = beam_element(pts[e], pts[e + 1], Iy=3e-7, Iz=3e-7)
        K[6 * e:6 * e + 12, 6 * e:6 * e + 12] += k
        M[6 * e:6 * e + 12, 6 * e:6 * e + 12] += m
    M[6 * (n - 1):6 * (n - 1) + 3, 6 * (n - 1):6 * (n - 1) + 3] += 0.5 * np.eye(3)
    spec = clamped_beam()
    del spec["bodies"]["beam"]["constraints"]
    spec["bodies"]["beam"].update(mass=M, stiffness=K)
    spec["name"] = "free_clustered"
    return spec


def sprung_beam():
    """A free beam along x on vertical (uz) springs at both ends: 4 rigid modes (ux, uy, rx, rz) remain."""
    K, M, nodes = beam([(x, 0.0, 0.0) for x in np.linspace(0, 2.0, 11)])
    return {"name": "sprung", "bodies": {"beam": {"mass": M, "stiffness": K, "nodes": nodes,
                                                  "springs": [{"node": 1, "dof": "uz", "stiffness": 2e4},
                                                              {"node": 11, "dof": "uz", "stiffness": 5e3}]}},
            "inputs": {"fz": [{"body": "beam", "node": 11, "dof": "uz"}], "fy": [{"body": "beam", "node": 6, "dof": "uy"}]},
            "outputs": {"z": [{"body": "beam", "node": 9, "dof": "uz"}], "y": [{"body": "beam", "node": 11, "dof": "uy"}]},
            "band": BAND, "damping": ZETA, "accuracy": 0.01}


def single_body_reference(spec):
    """Dense system of a one-body spec: clamped dofs removed, springs added; G, H from the point terms."""
    b = spec["bodies"]["beam"]
    K, M = np.array(b["stiffness"], float), np.array(b["mass"], float)
    first = {int(r[0]): 6 * i for i, r in enumerate(b["nodes"])}
    names = {"ux": 0, "uy": 1, "uz": 2, "rx": 3, "ry": 4, "rz": 5}
    for s in b.get("springs", []):
        d = first[s["node"]] + names[s["dof"]]
        K[d, d] += s["stiffness"]
    clamped = [first[c["node"]] + int(ch) - 1 for c in b.get("constraints", []) for ch in c["dofs"]]
    keep = np.setdiff1d(np.arange(len(K)), clamped)

    def terms(section):
        A = np.zeros((len(K), len(spec[section])))
        for j, (_, ts) in enumerate(spec[section].items()):
            for t in ts:
                A[first[t["node"]] + names[t["dof"]], j] += t.get("weight", 1.0)
        return A[keep]
    return M[np.ix_(keep, keep)], K[np.ix_(keep, keep)], terms("inputs"), terms("outputs").T




def bad_case(name):
    """Specs with one bad boundary condition each (the message must name it)."""
    if name == "unknown_node":
        spec = clamped_beam()
        spec["bodies"]["beam"]["constraints"] = [{"node": 99, "dofs": "123"}]
    elif name == "missing_component":
        spec = clamped_beam()
        spec["bodies"]["beam"]["nodes"][0][4] = 3
        K = spec["bodies"]["beam"]["stiffness"]
        spec["bodies"]["beam"]["stiffness"] = K[3:, 3:]
        spec["bodies"]["beam"]["mass"] = spec["bodies"]["beam"]["mass"][3:, 3:]
        spec["bodies"]["beam"]["constraints"] = [{"node": 1, "dofs": "1234"}]
    elif name == "oblique_ground_axis":
        spec = grounded_arm()
        spec["joints"]["pivot"]["axis"] = [0, 1, 1]
    elif name == "tied_clamp":
        spec = grounded_arm()
        spec["bodies"]["arm"]["constraints"] = [{"node": 1, "dofs": "3"}]
    elif name == "undeclared_support":
        # K carries a support the scene does not declare: a stiff spring inside K on node 1's uz
        spec = clamped_beam()
        del spec["bodies"]["beam"]["constraints"]
        spec["bodies"]["beam"]["stiffness"] = spec["bodies"]["beam"]["stiffness"].copy()
        spec["bodies"]["beam"]["stiffness"][2, 2] += 1e6
    elif name == "clamped_output":
        spec = plate_supported()
        spec["outputs"]["z"] = [{"body": "beam", "node": 1, "dof": "uz"}]
    elif name == "plate_ux_output":
        spec = plate_c345()
        spec["outputs"]["z"] = [{"body": "beam", "node": 1, "dof": "ux"}]
    elif name == "plate_interface":
        spec = plate_c345()
        spec["bodies"]["beam"]["interfaces"] = {"hinge": 2}
    elif name == "scalar_as_ux":
        spec = scalar_points()
        spec["inputs"]["fs"] = [{"body": "beam", "node": 101, "dof": "uz"}]
    else:
        raise KeyError(name)
    return spec


def lumped_frame():
    """A free-free L-shaped frame (x leg 2 m, y leg 1.5 m) with lumped translational masses only: every rotation is
    massless (M has zero rows), as in many exported models."""
    pts = [(x, 0.0, 0.0) for x in np.linspace(0, 2.0, 9)] + [(2.0, y, 0.0) for y in np.linspace(0.25, 1.5, 6)]
    n = len(pts)
    K = np.zeros((6 * n, 6 * n))
    M = np.zeros((6 * n, 6 * n))
    for e in range(n - 1):
        k, m = beam_element(pts[e], pts[e + 1])
        K[6 * e:6 * e + 12, 6 * e:6 * e + 12] += k
        lm = np.trace(m[:3, :3]) / 3 + np.trace(m[6:9, 6:9]) / 3       # the element's mass, half to each end
        for node in (e, e + 1):
            M[6 * node:6 * node + 3, 6 * node:6 * node + 3] += 0.5 * lm * np.eye(3) * 1.0
    M[6 * (n - 1):6 * (n - 1) + 3, 6 * (n - 1):6 * (n - 1) + 3] += 0.4 * np.eye(3)
    nodes = [[i + 1, *p, 6] for i, p in enumerate(pts)]
    return {"name": "lumped", "bodies": {"beam": {"mass": M, "stiffness": K, "nodes": nodes}},
            "inputs": {"fz": [{"body": "beam", "node": n, "dof": "uz"}], "mx": [{"body": "beam", "node": 5, "dof": "rx"}]},
            "outputs": {"z": [{"body": "beam", "node": 3, "dof": "uz"}], "ry": [{"body": "beam", "node": n, "dof": "ry"}],
                        "y": [{"body": "beam", "node": 9, "dof": "uy"}]},
            "band": BAND, "damping": ZETA, "accuracy": 0.01}


def rigid_offset_frame():
    """The lumped frame as a code writes it after eliminating rigid elements: each node of lumped_frame (its mass at
    the node p, rotations massless) becomes the dependent end of an RBE2 from an independent node at p - r (r random,
    a few centimetres to 0.2 m per component), and the dependent dofs are condensed into the independent node's: u_dep = T u_ind,
    T = [[I, -[r]x], [0, I]] per node, K and M replaced by T^T K T and T^T M T, the nodes at the independent points.
    The mass block m T^T T couples the independent rotations to the translations: no zero diagonal is left, yet M is
    as singular as before (rank 3 per node: half the 90 dofs are M's null space). Rigid modes are the geometric ones
    of the independent nodes (T maps them onto the frame's)."""
    spec = lumped_frame()
    body = spec["bodies"]["beam"]
    K, M = np.asarray(body["stiffness"]), np.asarray(body["mass"])
    n = len(body["nodes"])
    rng = np.random.default_rng(5)
    T = np.eye(6 * n)
    nodes = []
    for i, (nid, x, y, z, dofs) in enumerate(body["nodes"]):
        r = rng.uniform(0.03, 0.2, 3) * rng.choice([-1.0, 1.0], 3)
        T[6 * i:6 * i + 3, 6 * i + 3:6 * i + 6] = -np.array([[0, -r[2], r[1]], [r[2], 0, -r[0]], [-r[1], r[0], 0]])
        nodes.append([nid, x - r[0], y - r[1], z - r[2], dofs])
    Kc, Mc = T.T @ K @ T, T.T @ M @ T
    body.update(stiffness=0.5 * (Kc + Kc.T), mass=0.5 * (Mc + Mc.T), nodes=nodes)
    spec["name"] = "rigid_offset_frame"
    return spec


def condensed_frf(Ms, Ks, Gs, Hs, f_hz, zeta=ZETA):
    """FRF of a pencil with massless dofs (zero rows of Ms): static condensation onto the dofs with mass, the
    condensed loads and readings, the rigid modes from the condensed K's null space."""
    z = np.flatnonzero(~np.abs(Ms).any(axis=1))
    m = np.setdiff1d(np.arange(len(Ms)), z)
    X = np.linalg.solve(Ks[np.ix_(z, z)], Ks[np.ix_(z, m)])
    T = np.vstack([np.eye(len(m)), -X])              # full = T x_m, rows ordered (m, z)
    order = np.concatenate([m, z])
    Kf, Mf, Gf, Hf = Ks[np.ix_(order, order)], Ms[np.ix_(order, order)], Gs[order], Hs[:, order]
    Kc = T.T @ Kf @ T
    Kc = 0.5 * (Kc + Kc.T)
    return modal_frf(T.T @ Mf @ T, Kc, T.T @ Gf, Hf @ T, f_hz, zeta, rigid=rigid_null(Kc))


def grillage(nx=4, ny=3, hx=0.5, hy=0.5):
    """A free-free grillage of beams in the xy plane: nodes (i, j), beams along x and y."""
    pts = [(i * hx, j * hy, 0.0) for j in range(ny) for i in range(nx)]
    n = len(pts)
    K = np.zeros((6 * n, 6 * n))
    M = np.zeros((6 * n, 6 * n))
    for j in range(ny):
        for i in range(nx):
            a = j * nx + i
            for b in ([a + 1] if i + 1 < nx else []) + ([a + nx] if j + 1 < ny else []):
                k, m = beam_element(pts[a], pts[b], Iy=4e-7, Iz=4e-7)
                idx = np.r_[6 * a:6 * a + 6, 6 * b:6 * b + 6]
                K[np.ix_(idx, idx)] += k
                M[np.ix_(idx, idx)] += m
    return K, M, pts


def plate_c345():
    """The grillage's out-of-plane part only (uz rx ry per node, nodes 'c345'): exactly decoupled from the in-plane
    part for beams in the xy plane. 3 rigid modes remain (uz, rx, ry)."""
    K, M, pts = grillage()
    keep = np.array([6 * i + c for i in range(len(pts)) for c in (2, 3, 4)])
    nodes = [[i + 1, *p, "c345"] for i, p in enumerate(pts)]
    n = len(pts)
    return {"name": "plate", "bodies": {"beam": {"mass": M[np.ix_(keep, keep)], "stiffness": K[np.ix_(keep, keep)],
                                                 "nodes": nodes}},
            "inputs": {"fz": [{"body": "beam", "node": n, "dof": "uz"}], "mx": [{"body": "beam", "node": 6, "dof": "rx"}]},
            "outputs": {"z": [{"body": "beam", "node": 1, "dof": "uz"}], "ry": [{"body": "beam", "node": n - 1, "dof": "ry"}]},
            "band": BAND, "damping": ZETA, "accuracy": 0.01}


def scalar_points():
    """A free beam with two scalar points: each a mass on a spring to a node's uz (a CELAS/CMASS pair on SPOINTs);
    the scalar points follow the rigid motions by static condensation, so 6 rigid modes remain."""
    K0, M0, nodes = beam([(x, 0.0, 0.0) for x in np.linspace(0, 2.0, 9)])
    n0 = len(K0)
    K = np.zeros((n0 + 2, n0 + 2))
    M = np.zeros((n0 + 2, n0 + 2))
    K[:n0, :n0], M[:n0, :n0] = K0, M0
    for s, (node, k, m) in enumerate(((9, 3e4, 0.3), (5, 8e3, 0.2))):
        d, q = 6 * (node - 1) + 2, n0 + s
        K[np.ix_([d, q], [d, q])] += k * np.array([[1, -1], [-1, 1]])
        M[q, q] += m
    nodes = nodes + [[101, 0.0, 0.0, 0.0, "s"], [102, 0.0, 0.0, 0.0, "s"]]
    return {"name": "spoints", "bodies": {"beam": {"mass": M, "stiffness": K, "nodes": nodes}},
            "inputs": {"fs": [{"body": "beam", "node": 101, "dof": "s"}], "fz": [{"body": "beam", "node": 3, "dof": "uz"}]},
            "outputs": {"s2": [{"body": "beam", "node": 102, "dof": "s"}], "z": [{"body": "beam", "node": 9, "dof": "uz"}]},
            "band": BAND, "damping": ZETA, "accuracy": 0.01}


def layout_reference(spec):
    """Dense (M, K, G, H) of a one-body spec with any layout: dofs node by node, components ascending."""
    b = next(iter(spec["bodies"].values()))   # the one body
    first, comps, d = {}, {}, 0
    for r in b["nodes"]:
        c = r[4]
        comps[int(r[0])] = [6] if c == "s" else ([int(ch) - 1 for ch in c[1:]] if isinstance(c, str) else list(range(int(c))))
        first[int(r[0])] = d
        d += len(comps[int(r[0])])
    names = {"ux": 0, "uy": 1, "uz": 2, "rx": 3, "ry": 4, "rz": 5, "s": 6}

    def terms(section):
        A = np.zeros((d, len(spec[section])))
        for j, (_, ts) in enumerate(spec[section].items()):
            for t in ts:
                A[first[t["node"]] + comps[t["node"]].index(names[t["dof"]]), j] += t.get("weight", 1.0)
        return A[keep]
    K = np.array(b["stiffness"], float)
    for s in b.get("springs", []):
        i = first[s["node"]] + comps[s["node"]].index(names[s["dof"]])
        K[i, i] += s["stiffness"]
    clamped = [first[c["node"]] + comps[c["node"]].index(int(ch) - 1) for c in b.get("constraints", [])
               for ch in (c.get("dofs") or "".join(str(x + 1) for x in comps[c["node"]]))]
    keep = np.setdiff1d(np.arange(d), clamped)
    return (np.array(b["mass"])[np.ix_(keep, keep)], K[np.ix_(keep, keep)], terms("inputs"), terms("outputs").T)


def plate_supported():
    """The c345 plate clamped at node 1 (uz rx ry) and node 4 (all it has), on a spring at node 12: no rigid mode."""
    spec = plate_c345()
    spec["name"] = "plate_supported"
    spec["bodies"]["beam"]["constraints"] = [{"node": 1, "dofs": "345"}, {"node": 4}]
    spec["bodies"]["beam"]["springs"] = [{"node": 12, "dof": "uz", "stiffness": 500.0}]
    spec["outputs"]["z"] = [{"body": "beam", "node": 2, "dof": "uz"}]     # node 1 is clamped
    return spec


CASES = {"clamped": clamped_beam, "sprung": sprung_beam, "grounded": grounded_arm, "lumped": lumped_frame}
CASES.update(plate=plate_c345, spoints=scalar_points, plate_supported=plate_supported)


def lumped_plate(nx=5, ny=3, hx=0.5, hy=0.5, band=BAND):
    """A free-free plate as a commercial code exports it: the grillage's out-of-plane part (uz rx ry per node, nodes
    'c345') and lumped translational masses only, some at the node (every 7th node) and two or three
    offset from it at the others (a CONM2 with an offset
    puts m v v^T on the node, v = (1, dy, -dx): out-of-plane motion of the mass point is uz + rx dy - ry dx). One mass
    at the node leaves rx, ry with a zero diagonal; one offset mass gives a rank-1 block with a full diagonal; two
    offset masses a rank-2 block, three a rank-3 one. M is then singular far beyond its zero diagonal: rank = masses placed."""
    K6, _, pts = grillage(nx, ny, hx, hy)
    n = len(pts)
    keep = np.array([6 * i + c for i in range(n) for c in (2, 3, 4)])
    K = K6[np.ix_(keep, keep)]
    M = np.zeros_like(K)
    rng = np.random.default_rng(7)
    for i in range(n):
        offsets = [(0.0, 0.0)] if i % 7 == 0 else [tuple(rng.uniform(-0.2, 0.2, 2)) for _ in range(2 + i % 2)]
        for dx, dy in offsets:
            v = np.array([1.0, dy, -dx])
            M[3 * i:3 * i + 3, 3 * i:3 * i + 3] += rng.uniform(1.0, 3.0) * np.outer(v, v)
    nodes = [[i + 1, *p, "c345"] for i, p in enumerate(pts)]
    return {"name": "lumped_plate", "bodies": {"plate": {"mass": M, "stiffness": K, "nodes": nodes}},
            "inputs": {"fz": [{"body": "plate", "node": n, "dof": "uz"}],
                       "mx": [{"body": "plate", "node": nx + 2, "dof": "rx"}]},
            "outputs": {"z": [{"body": "plate", "node": 1, "dof": "uz"}],
                        "ry": [{"body": "plate", "node": n - 1, "dof": "ry"}]},
            "band": list(band), "damping": ZETA, "accuracy": 0.01}


def lumped_aircraft(band=(0.5, 60.0)):
    """A free-free aircraft-like stick model as exported from a commercial code: a fuselage along x, two wings along
    y and a fin along z (6-dof beam nodes, stiffness only), with lumped masses only. Most masses sit off their node
    (a CONM2 offset r: m T^T T on the node with T = [I, -[r]x], rank 3 with a full diagonal); the fin's nodes and the
    wing tips carry none (zero-mass dofs). M is then singular far beyond its zero diagonal."""
    fus = [(x, 0.0, 0.0) for x in np.linspace(0.0, 12.0, 13)]
    wing_r = [(5.0, y, 0.0) for y in np.linspace(1.0, 8.0, 8)]
    wing_l = [(5.0, -y, 0.0) for y in np.linspace(1.0, 8.0, 8)]
    fin = [(12.0, 0.0, z) for z in np.linspace(0.8, 2.4, 3)]
    pts = fus + wing_r + wing_l + fin
    n = len(pts)
    links = [(i, i + 1) for i in range(12)]
    for chain, root in ((range(13, 21), 5), (range(21, 29), 5), (range(29, 32), 12)):
        prev = root
        for k in chain:
            links.append((prev, k))
            prev = k
    K = np.zeros((6 * n, 6 * n))
    for a, b in links:
        k, _ = beam_element(pts[a], pts[b], A=4e-3, Iy=4e-6, Iz=6e-6)
        idx = np.r_[6 * a:6 * a + 6, 6 * b:6 * b + 6]
        K[np.ix_(idx, idx)] += k
    M = np.zeros_like(K)
    rng = np.random.default_rng(11)
    massless = {20, 28, 29, 30, 31}                     # wing tips and the fin: no mass at all
    for i in range(n):
        if i in massless:
            continue
        r = rng.uniform(-0.3, 0.3, 3) if i % 4 else np.zeros(3)
        T = np.hstack([np.eye(3), -np.array([[0, -r[2], r[1]], [r[2], 0, -r[0]], [-r[1], r[0], 0]])])
        M[6 * i:6 * i + 6, 6 * i:6 * i + 6] += rng.uniform(20.0, 60.0) * T.T @ T
    nodes = [[i + 1, *p, 6] for i, p in enumerate(pts)]
    return {"name": "lumped_aircraft", "bodies": {"aircraft": {"mass": M, "stiffness": K, "nodes": nodes}},
            "inputs": {"fz_tip": [{"body": "aircraft", "node": 20, "dof": "uz"}],
                       "my_fus": [{"body": "aircraft", "node": 9, "dof": "ry"}]},
            "outputs": {"z_nose": [{"body": "aircraft", "node": 1, "dof": "uz"}],
                        "rx_wing": [{"body": "aircraft", "node": 17, "dof": "rx"}],
                        "y_fin": [{"body": "aircraft", "node": 32, "dof": "uy"}]},
            "band": list(band), "damping": ZETA, "accuracy": 0.01}
