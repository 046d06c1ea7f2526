"""Parallel assembly of a grid body's K or M, with the RBE2 surfaces eliminated, into a PETSc AIJ matrix.

Why row-wise and not element-wise: each rank owns a contiguous range of solid
nodes and computes exactly its own rows, gathering for every (row node,
neighbour) pair the 3x3 blocks of the (at most 4) elements that contain both.
Nothing is sent between ranks, no entry is computed twice, memory is the
matrix plus one chunk of rows, and the result is bitwise the same on any
number of ranks (each entry is summed in the same order: ascending element
number). petsc4py 3.18 (Debian) has no setPreallocationCOO, so the rows go
into an exactly preallocated MPIAIJ with setValuesIJV, one chunk at a time.

RBE2 by elimination: a surface node s of patch q moves with the patch's
6-dof node I as u_s = u_I + theta_I x r_s (r_s = x_s - x_I), i.e. u_s = T_s x_I
with T_s = [1 | S_s], S_s theta = theta x r_s. With T the sparse map from the
reduced dofs to all dofs, K' = T^T K T:
  solid row n, solid column m : K_nm                                  (unchanged)
  solid row n, column I       : sum over surface neighbours s of K_ns T_s   (A_nI, 3x6)
  row I, solid column n       : A_nI^T                                (transposed, so exactly symmetric)
  row I, column I             : sum over s, s' of T_s^T K_ss' T_s'    (symmetrized)
Only the rank owning the RBE2 nodes (the last) computes the last two, from
the ring of solid nodes next to the surface and the surface nodes themselves.
"""
import itertools

import numpy as np
from petsc4py import PETSc

import solid_hex8

# Grid offsets of a neighbour node, in C order, so neighbours come in ascending node number.
ALL_OFFSETS = list(itertools.product((-1, 0, 1), repeat=3))
# Per axis, for a neighbour offset d: the elements containing both nodes, as
# (element index - node index, corner of the row node, corner of the neighbour), ascending.
_CANDIDATES = {-1: [(-1, 1, 0)], 0: [(-1, 1, 1), (0, 0, 0)], 1: [(0, 0, 1)]}


def element_blocks(body, kind, lumped=False):
    """Per element type, the 8x8 grid of 3x3 node blocks (ntypes, 8, 8, 3, 3) of K or M."""
    spec = body.spec
    out = np.empty((len(body.type_sizes), 8, 8, 3, 3))
    for t, size in enumerate(body.type_sizes):
        K, M = solid_hex8.element_matrices(solid_hex8.box_coords(size), spec.E, spec.nu, spec.rho)
        E = K if kind == "stiffness" else (solid_hex8.lump(M) if lumped else M)
        out[t] = E.reshape(8, 3, 8, 3).transpose(0, 2, 1, 3)
    return out


def _lever_matrix(r):
    """S (m, 3, 3) with S theta = theta x r, i.e. S = -skew(r)."""
    S = np.zeros((len(r), 3, 3))
    S[:, 0, 1], S[:, 0, 2] = r[:, 2], -r[:, 1]
    S[:, 1, 0], S[:, 1, 2] = -r[:, 2], r[:, 0]
    S[:, 2, 0], S[:, 2, 1] = r[:, 1], -r[:, 0]
    return S


def _matmul3(B, S):
    """B @ S for stacks of 3x3, summed in a fixed order (k = 0, 1, 2) so results are reproducible."""
    return (B[:, :, 0, None] * S[:, None, 0, :] + B[:, :, 1, None] * S[:, None, 1, :]) + B[:, :, 2, None] * S[:, None, 2, :]


class RowAssembler:
    """Computes rows of the reduced K' (or M') of one grid body; see the module docstring."""

    def __init__(self, body, kind, lumped=False):
        if kind not in ("stiffness", "mass"):
            raise ValueError(f"kind must be 'stiffness' or 'mass' (got {kind!r})")
        self.body, self.kind = body, kind
        blocks = element_blocks(body, kind, lumped)
        self.zero_type = len(blocks)
        self.blocks = np.concatenate([blocks, np.zeros((1, 8, 8, 3, 3))])
        ct = np.where(body.cell_type >= 0, body.cell_type, self.zero_type)
        self.cells = np.pad(ct, 1, constant_values=self.zero_type).astype(np.int32)
        self.nodes = np.pad(body.node_number, 1, constant_values=-1)
        self.offsets = [(0, 0, 0)] if (kind == "mass" and lumped) else ALL_OFFSETS
        self.n_solid, self.n_rbe2 = body.n_solid, body.n_rbe2
        # per active node (plus a sentinel at index -1): reduced index, RBE2 patch, lever arm
        n = len(body.node_ijk)
        self.reduced = np.append(body.reduced_node, -1)
        self.patch_of = np.append(np.where(body.reduced_node >= self.n_solid, body.reduced_node - self.n_solid, -1), -1)
        lever = np.zeros((n + 1, 3))
        xyz = body.coords()
        for q, r in enumerate(body.rbe2):
            lever[r.surface] = xyz[r.surface] - r.centroid
        self.lever = lever

    def rows(self, active, values=True):
        """Rows of the active nodes `active` (before any left-multiplication by T^T).

        Returns solid_cols (c, noff) reduced index of each coupled solid neighbour (-1: none),
        rbe2_mask (c, nq) whether the row couples to RBE2 node q, and when values is set
        B (c, noff, 3, 3) solid-neighbour blocks and A (c, nq, 3, 6) = sum_s K_ns T_s."""
        ijk = self.body.node_ijk[active] + 1
        c, nq, noff = len(active), self.n_rbe2, len(self.offsets)
        solid_cols = np.full((c, noff), -1, dtype=np.int64)
        rbe2_mask = np.zeros((c, nq), dtype=bool)
        Bs = np.zeros((c, noff, 3, 3)) if values else None
        A = np.zeros((c, nq, 3, 6)) if values else None
        for o, d in enumerate(self.offsets):
            coupled = np.zeros(c, dtype=bool)
            B = np.zeros((c, 3, 3)) if values else None
            for ex, ap, aq in _CANDIDATES[d[0]]:
                for ey, bp, bq in _CANDIDATES[d[1]]:
                    for ez, cp, cq in _CANDIDATES[d[2]]:
                        t = self.cells[ijk[:, 0] + ex, ijk[:, 1] + ey, ijk[:, 2] + ez]
                        coupled |= t != self.zero_type
                        if values:
                            B += self.blocks[t, ap + 2 * bp + 4 * cp, aq + 2 * bq + 4 * cq]
            nb = self.nodes[ijk[:, 0] + d[0], ijk[:, 1] + d[1], ijk[:, 2] + d[2]]
            red = self.reduced[nb]
            solid = coupled & (red >= 0) & (red < self.n_solid)
            solid_cols[solid, o] = red[solid]
            if values:
                Bs[:, o] = np.where(solid[:, None, None], B, 0.0)
            patch = np.where(coupled, self.patch_of[nb], -1)
            for q in range(nq):
                m = np.nonzero(patch == q)[0]
                if len(m) == 0:
                    continue
                rbe2_mask[m, q] = True
                if values:
                    Bm = B[m]
                    A[m, q, :, :3] += Bm
                    A[m, q, :, 3:] += _matmul3(Bm, _lever_matrix(self.lever[nb[m]]))
        return solid_cols, rbe2_mask, Bs, A

    def solid_rows_csr(self, active, values=True):
        """CSR of the reduced rows of solid nodes `active` (3 dof rows each): indptr, cols, vals."""
        solid_cols, rbe2_mask, Bs, A = self.rows(active, values)
        c, noff, nq = len(active), len(self.offsets), self.n_rbe2
        cols = np.concatenate([
            (3 * solid_cols[:, :, None] + np.arange(3)).reshape(c, 3 * noff),
            np.broadcast_to(3 * self.n_solid + 6 * np.arange(nq)[:, None] + np.arange(6), (c, nq, 6)).reshape(c, 6 * nq),
        ], axis=1)
        mask = np.concatenate([np.repeat(solid_cols >= 0, 3, axis=1), np.repeat(rbe2_mask, 6, axis=1)], axis=1)
        counts = np.repeat(mask.sum(axis=1), 3)
        indptr = np.concatenate([[0], np.cumsum(counts)])
        mask3 = np.broadcast_to(mask[:, None, :], (c, 3, mask.shape[1]))
        J = np.broadcast_to(cols[:, None, :], mask3.shape)[mask3]
        V = None
        if values:
            vals = np.concatenate([Bs.transpose(0, 2, 1, 3).reshape(c, 3, 3 * noff),
                                   A.transpose(0, 2, 1, 3).reshape(c, 3, 6 * nq)], axis=2)
            V = vals[mask3]
        return indptr, J, V

    def rbe2_rows_csr(self, point_masses=True):
        """CSR of the 6 rows of every RBE2 node (all of them, in order)."""
        body, ns, nq = self.body, self.n_solid, self.n_rbe2
        nodes = np.pad(body.node_number, 1, constant_values=-1)
        indptr, J, V = [0], [], []
        for q, r in enumerate(body.rbe2):
            ring = self._ring(nodes, r.surface)
            _, mask, _, A = self.rows(ring)
            ring, A = ring[mask[:, q]], A[mask[:, q], q]            # (m, 3, 6)
            _, _, _, As = self.rows(r.surface)
            S = _lever_matrix(self.lever[r.surface])
            Aq = As[:, q]                                             # (s, 3, 6)
            top = Aq.sum(axis=0)
            bottom = np.einsum("skm,skn->mn", S, Aq)                  # sum_s S_s^T A_s
            Z = np.vstack([top, bottom])
            Z = 0.5 * (Z + Z.T)
            if self.kind == "mass" and point_masses and r.point_mass:
                Z[:3, :3] += r.point_mass * np.eye(3)
            cols = np.concatenate([(3 * body.reduced_node[ring][:, None] + np.arange(3)).ravel(),
                                   3 * ns + 6 * q + np.arange(6)])
            for m in range(6):
                J.append(cols)
                V.append(np.concatenate([A[:, :, m].ravel(), Z[m]]))
                indptr.append(indptr[-1] + len(cols))
        return np.array(indptr), np.concatenate(J), np.concatenate(V)

    def _ring(self, nodes, surface):
        """Active numbers of solid nodes in the 27-neighbourhood of the surface nodes, ascending."""
        ijk = self.body.node_ijk[surface] + 1
        cand = [nodes[tuple((ijk + np.array(d)).T)] for d in ALL_OFFSETS]
        cand = np.unique(np.concatenate(cand))
        cand = cand[cand >= 0]
        return cand[self.reduced[cand] < self.n_solid]


def ownership(body, comm_size):
    """Solid-node range per rank (contiguous, balanced); the last rank also owns the RBE2 nodes."""
    ns = body.n_solid
    return [(ns * r // comm_size, ns * (r + 1) // comm_size) for r in range(comm_size)]


def assemble(body, kind, comm=None, lumped=False, chunk=16384):
    """K' (kind='stiffness') or M' (kind='mass') of body as a distributed PETSc AIJ matrix."""
    comm = comm or PETSc.COMM_WORLD
    size, rank = comm.getSize(), comm.getRank()
    ra = RowAssembler(body, kind, lumped)
    lo, hi = ownership(body, size)[rank]
    last = rank == size - 1
    n_local = 3 * (hi - lo) + (6 * body.n_rbe2 if last else 0)
    N = body.n_dofs
    rstart = 3 * lo                  # solid rows of lower ranks come first; the RBE2 rows are last
    rend = rstart + n_local
    chunks = [body.solid_active[a:min(a + chunk, hi)] for a in range(lo, hi, chunk)]

    def split(indptr, J):
        inside = (J >= rstart) & (J < rend)
        d = np.add.reduceat(inside, indptr[:-1]) if len(J) else np.zeros(len(indptr) - 1, int)
        d = np.where(np.diff(indptr) > 0, d, 0)
        return d, np.diff(indptr) - d

    d_nnz, o_nnz = [], []
    for act in chunks:
        indptr, J, _ = ra.solid_rows_csr(act, values=False)
        d, o = split(indptr, J)
        d_nnz.append(d), o_nnz.append(o)
    rbe2 = ra.rbe2_rows_csr() if last and body.n_rbe2 else None
    if rbe2 is not None:
        d, o = split(rbe2[0], rbe2[1])
        d_nnz.append(d), o_nnz.append(o)
    d_nnz = np.concatenate(d_nnz).astype(PETSc.IntType) if d_nnz else np.zeros(0, PETSc.IntType)
    o_nnz = np.concatenate(o_nnz).astype(PETSc.IntType) if o_nnz else np.zeros(0, PETSc.IntType)

    mat = PETSc.Mat().createAIJ(size=((n_local, N), (n_local, N)), nnz=(d_nnz, o_nnz), comm=comm)
    mat.setOption(PETSc.Mat.Option.NEW_NONZERO_ALLOCATION_ERR, True)
    row = rstart
    for act in chunks:
        indptr, J, V = ra.solid_rows_csr(act)
        nrows = len(indptr) - 1
        mat.setValuesIJV(indptr.astype(PETSc.IntType), J.astype(PETSc.IntType), V,
                         addv=PETSc.InsertMode.INSERT_VALUES,
                         rowmap=np.arange(row, row + nrows, dtype=PETSc.IntType))
        row += nrows
    if rbe2 is not None:
        indptr, J, V = rbe2
        mat.setValuesIJV(indptr.astype(PETSc.IntType), J.astype(PETSc.IntType), V,
                         addv=PETSc.InsertMode.INSERT_VALUES,
                         rowmap=np.arange(row, row + len(indptr) - 1, dtype=PETSc.IntType))
    mat.assemblyBegin()
    mat.assemblyEnd()
    return mat
