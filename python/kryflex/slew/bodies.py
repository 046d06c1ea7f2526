"""The articulated structure in its bodies' own coordinates, for time integration under slewing.

A SlewBodies holds, for the full-order model (from_scene: each body's dofs, the scene's matrices as the C scene
loaded them) or for a reduced model (from_model: each reduced body's coordinates, the C reduced bodies), the same
things: block-diagonal M, K (sparse), the stacked inputs G (N x a) and outputs H (t x N), the bodies' interface rows
I (6 per interface, stacked: the rows the reassembly ties, eq. 20) and the bodies' rigid motions (N x 6 per body).
The joint ties at angles alpha are D(alpha) = T(alpha) I, with T(alpha) the small matrix of the ties on the interface
rows: translations u_p - R u_c, rotations across the axis (revolute) or fully (fixed), R = R(alpha) from the C
library's KFJointRotation; the same rows C's KFReassemble builds (tests/python/slew/test_slew.py checks that the null
space of D(alpha) gives C's reassembled frequencies). Full and reduced models go through the same code.
A reduced model of shared directions also binds its bodies' coordinates by fixed rows D_s (ReducedModel.ties, appended
to the joints' ties at every angle, as the reassembly appends them): they are kept as extra rows of I with an identity
block in T, so that every user of T and I (the integrators, the trimmed mass, the Exudyn check) ties them too.
"""
import numpy as np
import scipy.sparse as sp

from .. import _core

DOF_ROWS = 6   # interface rows per interface node: ux, uy, uz, rx, ry, rz


def _perpendicular_pair(k):
    """Two unit vectors spanning the plane perpendicular to the unit axis k (any pair gives the same ties)."""
    c = np.zeros(3)
    c[int(np.argmin(np.abs(k)))] = 1.0
    e1 = c - k * (k @ c)
    e1 /= np.linalg.norm(e1)
    return np.vstack([e1, np.cross(k, e1)])


def _rigid_motions(ids, xyz, ndof):
    """A body's six rigid motions (translations, rotations about the origin) from its node coordinates:
    u = t + theta x x at every node, theta on the rotation dofs of 6-dof nodes."""
    n = int(np.sum(ndof))
    R = np.zeros((n, 6))
    first = np.concatenate([[0], np.cumsum(ndof)[:-1]]).astype(int)
    for f, x, d in zip(first, np.asarray(xyz, float).reshape(-1, 3), ndof):
        for k in range(3):
            e = np.zeros(3)
            e[k] = 1.0
            R[f + k, k] = 1.0
            R[f:f + 3, 3 + k] = np.cross(e, x)
            if d == 6:
                R[f + 3 + k, 3 + k] = 1.0
    return R


def _csr(mat):
    """A sequential petsc4py Mat (AIJ or dense) as a SciPy CSR matrix."""
    if mat.getType() in ("seqdense", "mpidense"):
        return sp.csr_matrix(mat.getDenseArray().copy())
    indptr, indices, data = mat.getValuesCSR()
    return sp.csr_matrix((data.copy(), indices.copy(), indptr.copy()), shape=mat.getSize())


class SlewBodies:
    """Bodies + joints in body coordinates (see the module doc). joints: dicts with parent, child (body indices),
    parent_interface, child_interface (interface indices), type, axis, R0 (3x3 or None), angle (index into the
    angle vector, or None for a fixed joint)."""

    def __init__(self, label, M, K, G, H, iface, rigid, joints, sizes, quantities=None, model_ties=None):
        self.label = label
        # what each output reads: displacement (H z), velocity (H z') or acceleration (H z'')
        self.quantities = list(quantities) if quantities is not None else ["displacement"] * np.shape(H)[0]
        self.M, self.K = sp.csr_matrix(M), sp.csr_matrix(K)
        self.G, self.H = np.asarray(G, float), np.asarray(H, float)
        self.sizes = list(sizes)
        self.offsets = np.concatenate([[0], np.cumsum(sizes)]).astype(int)
        # interface rows: per body a (6 n_if x v) block; stacked block-diagonally, with each block's first row
        self.iface_blocks = [np.asarray(x, float) if not sp.issparse(x) else x for x in iface]
        self.I = sp.block_diag([sp.csr_matrix(x) if x.shape[0] else sp.csr_matrix((0, v))
                                for x, v in zip(iface, sizes)], format="csr")
        self.iface_first = np.concatenate([[0], np.cumsum([x.shape[0] for x in iface])]).astype(int)
        self.rigid = sp.block_diag([sp.csr_matrix(r) for r in rigid], format="csr")   # N x 6 nbodies
        self.joints = joints
        self.nties = sum(5 if j["type"] == "revolute" else 6 for j in joints)
        # the model's coordinate ties D_s: rows of I past the interfaces', tied by an identity block of T
        Ds = np.zeros((0, self.M.shape[0])) if model_ties is None else np.asarray(model_ties, float)
        self.nmodel_ties = Ds.shape[0]
        if self.nmodel_ties:
            self.I = sp.vstack([self.I, sp.csr_matrix(Ds)], format="csr")
            self.nties += self.nmodel_ties
        self.nangles = sum(1 for j in joints if j["type"] == "revolute")

    @property
    def dofs(self):
        return self.M.shape[0]

    # ------------------------------------------------------------------ the two models

    @classmethod
    def from_scene(cls, scene):
        """The full-order model: every body's dofs, M, K, G, H as the C scene holds them (serial: the study runs
        on one rank)."""
        Ms, Ks, Gs, Hs, iface, rigid = [], [], [], [], [], []
        for b, name in enumerate(scene.body_names):
            M, K, G, Ht = scene.cscene.body_matrices(b)
            Ms.append(_csr(M))
            Ks.append(_csr(K))
            Gs.append(_csr(G).toarray())
            Hs.append(_csr(Ht).toarray().T)
            ids, xyz, ndof = scene.body_nodes[b]
            ids, ndof = np.asarray(ids), np.asarray(ndof)
            first = np.concatenate([[0], np.cumsum(ndof)[:-1]]).astype(int)
            spec = scene.spec["bodies"][name].get("interfaces", {})
            spec = dict(spec) if not isinstance(spec, dict) else spec
            rows = np.zeros((DOF_ROWS * len(scene.interfaces[b]), scene.body_dofs[b]))
            for i, iname in enumerate(scene.interfaces[b]):
                node = int(np.flatnonzero(ids == int(spec[iname]))[0])
                rows[DOF_ROWS * i + np.arange(DOF_ROWS), first[node] + np.arange(DOF_ROWS)] = 1.0
            iface.append(sp.csr_matrix(rows))
            rigid.append(_rigid_motions(ids, xyz, ndof))
        joints = []
        for j in scene.joints:
            joints.append(dict(j, angle=scene.revolute.index(j["name"]) if j["type"] == "revolute" else None))
        return cls("full", sp.block_diag(Ms), sp.block_diag(Ks), np.vstack(Gs), np.hstack(Hs), iface, rigid, joints,
                   scene.body_dofs, scene.output_quantities)

    @classmethod
    def from_system(cls, scene, angles_rad=()):
        """The full-order model of a scene without joints: the assembled system as the reduction's verification
        builds it (constraints, springs and the dof layouts applied; its rigid-body modes from the C library), one
        block, no ties."""
        system = _core.CSystem(scene.cscene)
        system.set_angles(np.asarray(angles_rad, float))
        M, K, G, Ht = system.matrices()
        Phi, _ = system.rigid_modes()
        n = M.getSize()[0]
        rigid = _csr(Phi).toarray() if Phi is not None and Phi.getSize()[1] else np.zeros((n, 0))
        return cls("full", _csr(M), _csr(K), _csr(G).toarray(), _csr(Ht).toarray().T, [np.zeros((0, n))], [rigid],
                   [], [n], scene.output_quantities)

    @classmethod
    def from_model(cls, model):
        """A reduced model: each reduced body's coordinates (the C reduced bodies, eq. 18-19)."""
        bodies = model.bodies
        if any(b.get("rigid") is None for b in bodies):
            raise ValueError("the reduced model lacks its bodies' rigid motions (a model from an older kryflex): "
                             "reduce the scene again")
        revolute = model.revolute
        joints = [dict(j, angle=revolute.index(j["name"]) if j["type"] == "revolute" else None)
                  for j in model.joints]
        return cls("reduced", sp.block_diag([b["M"] for b in bodies]), sp.block_diag([b["K"] for b in bodies]),
                   np.vstack([b["G"] for b in bodies]), np.hstack([b["H"] for b in bodies]),
                   [b["iface"] if b.get("iface") is not None else np.zeros((0, v))
                    for b, v in zip(bodies, model.sizes)],
                   [b["rigid"] for b in bodies], joints, model.sizes, model.output_quantities(),
                   getattr(model, "ties", None))

    # ------------------------------------------------------------------ the joint ties

    def _tie_template(self):
        """The angle-free part of T and, per revolute joint, where its child's -E R block goes (computed once)."""
        T0 = np.zeros((self.nties, self.I.shape[0]))
        turning, row = [], 0
        for j in self.joints:
            axis = np.asarray(j["axis"], float)
            axis = axis / np.linalg.norm(axis)
            R0 = None if j.get("R0") is None else np.asarray(j["R0"], float)
            across = _perpendicular_pair(axis) if j["type"] == "revolute" else np.eye(3)
            p = self.iface_first[j["parent"]] + DOF_ROWS * j["parent_interface"]
            c = self.iface_first[j["child"]] + DOF_ROWS * j["child_interface"]
            for E, k in ((np.eye(3), 0), (across, 3)):       # translations, then rotations
                n = E.shape[0]
                T0[row:row + n, p + k:p + k + 3] += E
                if j["type"] == "revolute":
                    turning.append((j["angle"], axis, R0, E, slice(row, row + n), slice(c + k, c + k + 3)))
                else:
                    T0[row:row + n, c + k:c + k + 3] -= E @ (np.eye(3) if R0 is None else R0)
                row += n
        T0[row:, self.iface_first[-1]:] = np.eye(self.nmodel_ties)
        return T0, turning

    def tie_matrix(self, angles_rad):
        """T(alpha) (ties x stacked interface rows): D(alpha) = T(alpha) I. The rows are those of C's KFReassemble:
        E (x_p - R x_c) on the translations (E = I) and rotations (E: the two directions across the axis of a
        revolute joint, I for a fixed one), R = R(alpha) from C's KFJointRotation."""
        if not hasattr(self, "_template"):
            self._template = self._tie_template()
        T0, turning = self._template
        angles = np.atleast_1d(np.asarray(angles_rad, float))
        T = T0.copy()
        rotations = {}
        for angle, axis, R0, E, rows, cols in turning:
            if angle not in rotations:
                rotations[angle] = _core.joint_rotation(axis, float(angles[angle]), R0)
            T[rows, cols] -= E @ rotations[angle]
        return T

    def ties(self, angles_rad):
        """D(alpha) (ties x N), dense."""
        return np.asarray((self.I.T @ self.tie_matrix(angles_rad).T).T)

    def rigid_modes(self, angles_rad):
        """The structure's rigid-body and mechanism modes at alpha (N x r): the combinations of the bodies' rigid
        motions that satisfy the ties, null(D R) by the C library's SVD null space (as KFReassemble forms them)."""
        DR = self.tie_matrix(angles_rad) @ (self.I @ self.rigid).toarray()
        Z, _, _ = _core.null_space(DR)
        return self.rigid @ Z
