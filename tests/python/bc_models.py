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
