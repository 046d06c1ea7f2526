"""Trilinear 8-node hexahedron (hex8) for 3-D linear elasticity, 2x2x2 Gauss.

Local node l sits at the corner (a, b, c) of the reference cube with
l = a + 2 b + 4 c (a along x, b along y, c along z). This lexicographic order,
not the usual counter-clockwise one, lets the grid assembly find a node's
local number from its grid offset inside the element by arithmetic alone.
Element dofs are node by node: ux uy uz of node 0, then node 1, ...
"""
import numpy as np

# Reference-cube corners in local node order, as 0/1 and as -1/+1.
CORNERS = np.array([(a, b, c) for c in (0, 1) for b in (0, 1) for a in (0, 1)], dtype=np.int64)
_SIGNS = 2.0 * CORNERS - 1.0
# 2x2x2 Gauss points (weights 1): exact for the consistent mass (N_i N_j is
# quadratic per direction) and for a box element's stiffness.
_G = 1.0 / np.sqrt(3.0)
GAUSS_POINTS = np.array([(x, y, z) for z in (-_G, _G) for y in (-_G, _G) for x in (-_G, _G)])


def elasticity_matrix(E, nu):
    """Isotropic 6x6 D in Voigt order xx yy zz yz xz xy (engineering shears)."""
    if not (E > 0 and -1.0 < nu < 0.5):
        raise ValueError(f"material E={E}, nu={nu} is not positive definite: need E > 0 and -1 < nu < 0.5")
    lam = E * nu / ((1 + nu) * (1 - 2 * nu))
    mu = E / (2 * (1 + nu))
    D = np.zeros((6, 6))
    D[:3, :3] = lam
    D[np.arange(3), np.arange(3)] += 2 * mu
    D[np.arange(3, 6), np.arange(3, 6)] = mu
    return D


def shape_functions(xi):
    """N (8,) at reference point xi = (xi, eta, zeta)."""
    return np.prod(1.0 + _SIGNS * np.asarray(xi), axis=1) / 8.0


def shape_gradients(xi):
    """dN/dxi (8, 3) at reference point xi."""
    f = 1.0 + _SIGNS * np.asarray(xi)          # (8, 3) one-dimensional factors
    g = np.empty((8, 3))
    g[:, 0] = _SIGNS[:, 0] * f[:, 1] * f[:, 2]
    g[:, 1] = _SIGNS[:, 1] * f[:, 0] * f[:, 2]
    g[:, 2] = _SIGNS[:, 2] * f[:, 0] * f[:, 1]
    return g / 8.0


def strain_displacement(grad):
    """B (6, 24) from physical shape-function gradients grad (8, 3)."""
    B = np.zeros((6, 24))
    gx, gy, gz = grad[:, 0], grad[:, 1], grad[:, 2]
    B[0, 0::3] = gx
    B[1, 1::3] = gy
    B[2, 2::3] = gz
    B[3, 1::3], B[3, 2::3] = gz, gy
    B[4, 0::3], B[4, 2::3] = gz, gx
    B[5, 0::3], B[5, 1::3] = gy, gx
    return B


def element_matrices(coords, E, nu, rho):
    """Stiffness and consistent mass (24x24 each) of one hex8 with node coordinates coords (8, 3).

    Both are symmetrized exactly so that the assembled matrices are bitwise
    symmetric (the grid assembly relies on K_e[l, m] == K_e[m, l].T)."""
    coords = np.asarray(coords, dtype=float)
    D = elasticity_matrix(E, nu)
    K = np.zeros((24, 24))
    M = np.zeros((24, 24))
    for xi in GAUSS_POINTS:
        J = shape_gradients(xi).T @ coords        # J[i, j] = dx_j / dxi_i
        detJ = np.linalg.det(J)
        if detJ <= 0:
            raise ValueError(f"hex8 element with node coordinates {coords.tolist()} is inverted or degenerate "
                             f"(det J = {detJ:g} at Gauss point {xi}); check the node order (l = a + 2b + 4c)")
        grad = np.linalg.solve(J, shape_gradients(xi).T).T   # dN/dx (8, 3)
        B = strain_displacement(grad)
        K += B.T @ D @ B * detJ
        N = shape_functions(xi)
        M += rho * detJ * np.kron(np.outer(N, N), np.eye(3))
    return 0.5 * (K + K.T), 0.5 * (M + M.T)


def box_coords(size):
    """Node coordinates (8, 3) of an axis-aligned box element of edge lengths size (hx, hy, hz)."""
    return CORNERS * np.asarray(size, dtype=float)


def lump(M):
    """Row-sum lumped mass (diagonal 24x24); for a box hex8 every node gets rho V / 8."""
    return np.diag(M.sum(axis=1))
