"""The reduced bodies of a model as floating-frame bodies, from the reduced model alone.

A reduced body's coordinates phi (v of them) span its 6 rigid-body motions (the model's `rigid` rows: Psi^T M Phi_rig,
so the motions' own coordinates are R = M^-1 rigid) and its flexible shapes. A multibody code (Exudyn's
ObjectFFRFreducedOrder, or any floating-frame-of-reference body) wants them split:

    phi = R r + F q      r: 6 small frame motions (translation, rotation about the body frame's origin)
                         q: flexible coordinates, F M-orthonormal, M-orthogonal to R, K-diagonal

With F M-orthogonal to the rigid motions, the frame's mass terms decouple from the flexible ones (mean-axis frame):
mass m, centre of mass c and inertia J about the origin follow from R^T M R exactly, whatever dofs the body's nodes
have (translations only, or rotations too: the reduced M already holds the rotary inertia of beams, shells and RBE2
nodes). The change of coordinates [R F] is square and invertible, so at rest the floating-frame body has exactly the
kryflex reduced body's linear dynamics.

Interface nodes: their 6 rows (iface) give their translation and rotation for any phi; their positions follow from the
rows of the rigid rotations (w x x at the node), so the reduced model needs no node coordinates. Inputs and outputs:
per body the generalized forces R^T G (force, moment about the origin, body frame) and F^T G, and the output rows
H R and H F.
"""
import dataclasses

import numpy as np


class ExportError(ValueError):
    """A model that cannot be exported: the message names the body, the fault and the fix."""


# how far the reduced rigid motions may be from exact ones before the export refuses the body (relative)
RIGID_TOL = 1e-6


def _axial(A):
    """x from A = -skew(x) (least squares over both off-diagonal triangles)."""
    return 0.5 * np.array([A[1, 2] - A[2, 1], A[2, 0] - A[0, 2], A[0, 1] - A[1, 0]])


def skew(x):
    """skew(x) y = x cross y."""
    return np.array([[0.0, -x[2], x[1]], [x[2], 0.0, -x[0]], [-x[1], x[0], 0.0]])


@dataclasses.dataclass(eq=False)
class FloatingBody:
    """One reduced body as a floating-frame body. Arrays (SI units if the scene's are; v reduced, f = v - 6 flexible
    coordinates, a inputs, t outputs, n interfaces):

    M, K, G, H, iface: the kryflex reduced body as stored (v x v, v x v, v x a, t x v, 6n x v)
    rigid_coords R (v x 6): the reduced coordinates of the rigid motions (ux, uy, uz, rx, ry, rz about the origin)
    modes F (v x f): flexible modes, F^T M F = I, R^T M F = 0, F^T K F diagonal (ascending)
    mass_flex (f x f) = F^T M F, stiffness_flex (f x f) = F^T K F
    mass, center_of_mass (3), inertia (3 x 3 about the body frame's origin)
    interface_positions (n x 3); interface_modes (n, 6, f): interface translations and rotations per flexible mode
    input_rigid (6 x a) = R^T G: force and moment about the origin per unit input; input_flex (f x a) = F^T G
    output_rigid (t x 6) = H R, output_flex (t x f) = H F

    A body that lacks some of its 6 rigid motions (clamped, on springs, a plate's uz rx ry nodes, scalar points) has
    no floating frame: floating is False, missing_rigid names the absent motions, and only the reduced M, K, G, H,
    iface and damping_matrix are set (the floating-frame fields are None).
    """
    name: str
    interfaces: list
    M: np.ndarray
    K: np.ndarray
    G: np.ndarray
    H: np.ndarray
    iface: np.ndarray
    rigid_coords: np.ndarray = None
    modes: np.ndarray = None
    mass_flex: np.ndarray = None
    stiffness_flex: np.ndarray = None
    mass: float = None
    center_of_mass: np.ndarray = None
    inertia: np.ndarray = None
    interface_positions: np.ndarray = None
    interface_modes: np.ndarray = None
    input_rigid: np.ndarray = None
    input_flex: np.ndarray = None
    output_rigid: np.ndarray = None
    output_flex: np.ndarray = None
    # the viscous damping matrix of the reduced body (v x v; zeros when the body has none) and F^T C F (f x f); the
    # neutral file names it body<i>/C
    damping_matrix: np.ndarray = None
    damping_flex: np.ndarray = None
    floating: bool = True
    missing_rigid: tuple = ()

    def __post_init__(self):
        v = self.M.shape[0]
        if self.damping_matrix is None:
            self.damping_matrix = np.zeros((v, v))
        if not self.floating:
            return
        f = self.modes.shape[1]
        if self.damping_flex is None:
            self.damping_flex = self.modes.T @ self.damping_matrix @ self.modes if f else np.zeros((0, 0))

    @property
    def C(self):
        """Deprecated name of damping_matrix (C is a ReducedSystem's output matrix)."""
        import warnings
        warnings.warn("FloatingBody.C is deprecated: use FloatingBody.damping_matrix (C is a ReducedSystem's output "
                      "matrix)", DeprecationWarning, stacklevel=2)
        return self.damping_matrix

    @property
    def nflex(self):
        """Flexible coordinates of a floating body (0 for a body without a floating frame)."""
        return self.modes.shape[1] if self.floating else 0

    @property
    def frequencies_hz(self):
        """The body's free-free flexible frequencies (Hz); without a floating frame, those of its reduced (K, M)."""
        if not self.floating:
            lam = np.linalg.eigvals(np.linalg.solve(self.M, self.K)).real
            return np.sqrt(np.maximum(np.sort(lam), 0)) / (2 * np.pi)
        return np.sqrt(np.maximum(np.diag(self.stiffness_flex), 0)) / (2 * np.pi)

    def why_not_floating(self):
        """Why the body has no floating frame, with the fix (empty for a floating body)."""
        if self.floating:
            return ""
        return ("body '%s' cannot move rigidly along %s (its supports or its dof layout remove them)"
                % (self.name, " ".join(self.missing_rigid)))


RIGID_NAMES = ("ux", "uy", "uz", "rx", "ry", "rz")


def missing_rigid_motions(v, rigid):
    """The rigid motions (names) a reduced body of v coordinates lacks: all 6 without rigid-body rows (a clamped body,
    or a model of an older kryflex), else those whose rows are zero (supports, or a dof layout such as uz rx ry)."""
    if rigid is None or rigid.shape != (v, 6):
        return RIGID_NAMES
    scale = max(np.abs(rigid).max(), 1e-300)
    return tuple(RIGID_NAMES[k] for k in range(6) if np.abs(rigid[:, k]).max() <= 1e-12 * scale)


def reduced_body(name, interfaces, M, K, G, H, iface=None, rigid=None, damping_matrix=None):
    """The export's body: a floating-frame body (floating_body) when the body has its 6 rigid motions, else the reduced
    body as it is (M, K, G, H, iface, damping_matrix; floating False, the missing motions named)."""
    C = damping_matrix
    v = M.shape[0]
    missing = missing_rigid_motions(v, rigid)
    if not missing:
        return floating_body(name, interfaces, M, K, G, H, iface=iface, rigid=rigid, damping_matrix=C)
    return FloatingBody(name=name, interfaces=list(interfaces), M=0.5 * (M + M.T), K=0.5 * (K + K.T), G=G, H=H,
                        iface=np.zeros((0, v)) if iface is None else iface,
                        damping_matrix=None if C is None else 0.5 * (C + C.T), floating=False,
                        missing_rigid=tuple(missing))


def floating_body(name, interfaces, M, K, G, H, iface=None, rigid=None, damping_matrix=None):
    """The FloatingBody of one reduced body (the arrays of ReducedModel.bodies: iface absent for a body without
    interfaces, damping_matrix for a body with a viscous damping matrix); ExportError when the body lacks any of its 6 rigid
    motions (clamped, on springs, or a dof layout such as a plate's uz rx ry) or its basis does not reproduce them."""
    v = M.shape[0]
    if iface is None:
        iface = np.zeros((0, v))
    if rigid is None or rigid.shape != (v, 6):
        raise ExportError("body '%s': the reduced model holds no rigid-body rows for it (a clamped body, or a model of an "
                          "older kryflex): a floating-frame body needs its 6 rigid motions; take its matrices with "
                          "'kryflex reassemble -o' instead" % name)
    absent = missing_rigid_motions(v, rigid)
    if absent:
        raise ExportError("body '%s' cannot move rigidly along %s (its supports or its dof layout remove them): a "
                          "floating-frame body needs all 6 rigid motions; give its nodes all six components, or take "
                          "its matrices with 'kryflex reassemble -o' instead" % (name, " ".join(absent)))
    if v < 6:
        raise ExportError("body '%s' has %d reduced dofs, fewer than its 6 rigid motions: it cannot float" % (name, v))
    M = 0.5 * (M + M.T)
    K = 0.5 * (K + K.T)
    try:
        L = np.linalg.cholesky(M)
    except np.linalg.LinAlgError:
        raise ExportError("body '%s': its reduced mass matrix is not positive definite (massless reduced coordinates): "
                          "a multibody body needs mass in every coordinate" % name) from None
    R = np.linalg.solve(M, rigid)
    # R^T M R is the rigid body's 6 x 6 mass matrix: m I, -m skew(c); m skew(c), J
    Mr = R.T @ M @ R
    mass = float(np.trace(Mr[:3, :3]) / 3)
    if not mass > 0:
        raise ExportError("body '%s' has no mass in its rigid translations (m = %g): check its mass matrix" % (name, mass))
    dev = np.abs(Mr[:3, :3] - mass * np.eye(3)).max() / mass
    if dev > RIGID_TOL:
        raise ExportError("body '%s': its reduced rigid translations do not carry one mass (|R^T M R - m I| / m = %.2g): "
                          "its reduced basis does not contain its rigid motions exactly" % (name, dev))
    com = _axial(Mr[:3, 3:]) / mass
    inertia = 0.5 * (Mr[3:, 3:] + Mr[3:, 3:].T)
    # interface positions from the rotations' translation rows, checked against the exact rigid pattern
    nif = iface.shape[0] // 6
    positions = np.zeros((nif, 3))
    for i in range(nif):
        A = iface[6 * i:6 * i + 6] @ R
        x = _axial(A[:3, 3:])
        positions[i] = x
        exact = np.block([[np.eye(3), -skew(x)], [np.zeros((3, 3)), np.eye(3)]])
        err = np.abs(A - exact).max() / max(1.0, np.abs(exact).max())
        if err > RIGID_TOL:
            raise ExportError("body '%s', interface '%s': the reduced rigid motions do not move the interface node rigidly "
                              "(error %.2g): its reduced basis does not contain the body's rigid motions" % (name, interfaces[i], err))
    # flexible modes: the M-orthogonal complement of the rigid motions, diagonalized on K
    Y = L.T @ R
    Q, _ = np.linalg.qr(Y, mode="complete")
    F0 = np.linalg.solve(L.T, Q[:, 6:])
    lam, V = np.linalg.eigh(0.5 * ((F0.T @ K @ F0) + (F0.T @ K @ F0).T))
    F = F0 @ V
    Mf = F.T @ M @ F
    Kf = F.T @ K @ F
    imodes = np.stack([iface[6 * i:6 * i + 6] @ F for i in range(nif)]) if nif else np.zeros((0, 6, F.shape[1]))
    return FloatingBody(name=name, interfaces=list(interfaces), M=M, K=K, G=G, H=H, iface=iface, rigid_coords=R,
                        modes=F, mass_flex=0.5 * (Mf + Mf.T), stiffness_flex=0.5 * (Kf + Kf.T), mass=mass,
                        center_of_mass=com, inertia=inertia, interface_positions=positions, interface_modes=imodes,
                        input_rigid=R.T @ G, input_flex=F.T @ G, output_rigid=H @ R, output_flex=H @ F,
                        damping_matrix=None if damping_matrix is None
                        else 0.5 * (damping_matrix + damping_matrix.T))
