"""Structured block grids: a body is a union of axis-aligned boxes meshed on one tensor grid.

Each axis is cut at every block face (and every RBE2 patch edge) into
segments; a segment is divided uniformly into ceil(length / h) cells, h being
the smallest target size among the blocks that span it, divided by the
refinement factor. A cell is active when its centre lies inside a block.
Because the lines are shared, blocks that touch are conforming by
construction (no node merging), and a body is described by a few small
integer grids: cell type (-1 = empty) and node number (-1 = unused).
Empty cells cost one byte each; all work is on active nodes only.
"""
from dataclasses import dataclass, field

import numpy as np


@dataclass
class Block:
    """Box [lo, hi] meshed with target element size h (per axis) at refinement 1."""
    name: str
    lo: tuple
    hi: tuple
    h: tuple


@dataclass
class Rbe2Patch:
    """Surface nodes on the plane x[axis] == plane inside [lo, hi] (other axes), tied rigidly (RBE2) to
    one 6-dof node at their centroid. point_mass (kg) is lumped on that node's translations."""
    name: str
    axis: int
    plane: float
    lo: tuple
    hi: tuple
    point_mass: float = 0.0


@dataclass
class BodySpec:
    name: str
    blocks: list
    patches: list
    E: float
    nu: float
    rho: float
    points: dict = field(default_factory=dict)   # name -> (x, y, z): nearest solid node, for loads/readings


@dataclass
class Rbe2Node:
    name: str
    surface: np.ndarray      # active-node numbers of the tied surface nodes
    centroid: np.ndarray     # (3,) location of the 6-dof node
    point_mass: float


@dataclass
class GridBody:
    """Mesh of one body. Active nodes are numbered 0..n-1 in C order of the node grid (k fastest)."""
    spec: BodySpec
    refine: float
    lines: list              # 3 arrays of grid-line coordinates
    cell_type: np.ndarray    # (ncx, ncy, ncz) int32, -1 = empty, else index into type_sizes
    type_sizes: np.ndarray   # (ntypes, 3) element edge lengths
    node_number: np.ndarray  # (nnx, nny, nnz) int32, -1 = unused
    node_ijk: np.ndarray     # (n, 3) grid indices of the active nodes
    rbe2: list               # Rbe2Node per patch, in spec order
    # Reduced numbering (what the files hold): solid nodes first in active order, then the RBE2 nodes.
    reduced_node: np.ndarray # (n,) reduced node index of every active node (surface nodes -> n_solid + q)
    solid_active: np.ndarray # (n_solid,) active-node number of each solid node, in file order

    @property
    def n_solid(self):
        return len(self.solid_active)

    @property
    def n_rbe2(self):
        return len(self.rbe2)

    @property
    def n_dofs(self):
        return 3 * self.n_solid + 6 * self.n_rbe2

    @property
    def n_elements(self):
        return int(np.count_nonzero(self.cell_type >= 0))

    def coords(self, active=None):
        """Coordinates (m, 3) of active nodes (all when active is None)."""
        ijk = self.node_ijk if active is None else self.node_ijk[active]
        return np.column_stack([self.lines[a][ijk[:, a]] for a in range(3)])

    def solid_coords(self):
        return self.coords(self.solid_active)

    def rbe2_coords(self):
        return np.array([r.centroid for r in self.rbe2]).reshape(-1, 3)

    def nearest_solid_node(self, point):
        """Reduced (0-based) index of the solid node nearest to point."""
        d = np.linalg.norm(self.solid_coords() - np.asarray(point, dtype=float), axis=1)
        return int(np.argmin(d))


def _axis_lines(spec, axis, refine):
    cuts = set()
    for b in spec.blocks:
        cuts.update((float(b.lo[axis]), float(b.hi[axis])))
    for p in spec.patches:
        if p.axis == axis:
            cuts.add(float(p.plane))
        else:
            cuts.update((float(p.lo[axis]), float(p.hi[axis])))
    cuts = np.array(sorted(cuts))
    span = cuts[-1] - cuts[0]
    # merge cuts closer than a round-off tolerance so that no sliver cells appear
    cuts = cuts[np.concatenate([[True], np.diff(cuts) > 1e-9 * span])]
    lines = [cuts[:1]]
    for lo, hi in zip(cuts[:-1], cuts[1:]):
        sizes = [b.h[axis] for b in spec.blocks
                 if b.lo[axis] <= lo + 1e-9 * span and hi <= b.hi[axis] + 1e-9 * span]
        h = (min(sizes) if sizes else hi - lo) / refine
        n = max(1, int(np.ceil((hi - lo) / h - 1e-6)))
        lines.append(np.linspace(lo, hi, n + 1)[1:])
    return np.concatenate(lines)


def _cell_types(lines, spec):
    centres = [0.5 * (l[:-1] + l[1:]) for l in lines]
    active = np.zeros(tuple(len(c) for c in centres), dtype=bool)
    for b in spec.blocks:
        sel = [np.nonzero((c > b.lo[a]) & (c < b.hi[a]))[0] for a, c in enumerate(centres)]
        if any(len(s) == 0 for s in sel):
            raise ValueError(f"block '{b.name}' of body '{spec.name}' has no cells: give it hi > lo on every axis")
        active[np.ix_(*sel)] = True
    # one element matrix per distinct (hx, hy, hz): few, because spacing is uniform per segment
    uniq, inv = zip(*(np.unique(np.round(np.diff(l), 12), return_inverse=True) for l in lines))
    counts = [len(u) for u in uniq]
    type_index = (inv[0][:, None, None] * counts[1] + inv[1][None, :, None]) * counts[2] + inv[2][None, None, :]
    cell_type = np.where(active, type_index, -1).astype(np.int32)
    sizes = np.array([(x, y, z) for x in uniq[0] for y in uniq[1] for z in uniq[2]])
    return cell_type, sizes


def _active_nodes(cell_type):
    ncx, ncy, ncz = cell_type.shape
    used = np.zeros((ncx + 1, ncy + 1, ncz + 1), dtype=bool)
    act = cell_type >= 0
    for a in (0, 1):
        for b in (0, 1):
            for c in (0, 1):
                used[a:a + ncx, b:b + ncy, c:c + ncz] |= act
    node_number = np.full(used.shape, -1, dtype=np.int32)
    node_ijk = np.argwhere(used).astype(np.int32)   # C order
    node_number[tuple(node_ijk.T)] = np.arange(len(node_ijk), dtype=np.int32)
    return node_number, node_ijk


def _patch_nodes(grid_lines, cell_type, node_number, node_ijk, spec, patch):
    a = patch.axis
    others = [o for o in range(3) if o != a]
    la = grid_lines[a]
    span = max(l[-1] - l[0] for l in grid_lines)
    k = int(np.argmin(np.abs(la - patch.plane)))
    if abs(la[k] - patch.plane) > 1e-9 * span:
        raise ValueError(f"RBE2 patch '{patch.name}' of body '{spec.name}': plane x[{a}] = {patch.plane} is not a grid plane")
    on_plane = node_ijk[:, a] == k
    inside = on_plane.copy()
    for o in others:
        x = grid_lines[o][node_ijk[:, o]]
        inside &= (x >= patch.lo[o] - 1e-9 * span) & (x <= patch.hi[o] + 1e-9 * span)
    nodes = np.nonzero(inside)[0]
    if len(nodes) < 3:
        raise ValueError(f"RBE2 patch '{patch.name}' of body '{spec.name}' holds {len(nodes)} nodes; "
                         "a rigid tie needs at least 3 non-collinear surface nodes: enlarge lo/hi")
    # A tie to interior nodes would silently stiffen the body: require every patch node to have
    # no active cell on one side of the plane (an outer face).
    ct = np.pad(cell_type, 1, constant_values=-1)
    ijk = node_ijk[nodes] + 1
    below = np.zeros(len(nodes), dtype=bool)
    above = np.zeros(len(nodes), dtype=bool)
    for d0 in (-1, 0):
        for d1 in (-1, 0):
            idx = [None, None, None]
            idx[others[0]] = ijk[:, others[0]] + d0
            idx[others[1]] = ijk[:, others[1]] + d1
            idx[a] = ijk[:, a] - 1
            below |= ct[tuple(idx)] >= 0
            idx[a] = ijk[:, a]
            above |= ct[tuple(idx)] >= 0
    if np.any(below & above):
        raise ValueError(f"RBE2 patch '{patch.name}' of body '{spec.name}' reaches inside the body "
                         f"({int(np.sum(below & above))} nodes have material on both sides of x[{a}] = {patch.plane}); "
                         "put the patch on an outer face")
    return nodes


def build_grid(spec, refine=1.0):
    """Mesh spec at refinement refine (> 0; element sizes are the blocks' h / refine)."""
    if not refine > 0:
        raise ValueError(f"refine must be > 0 (got {refine})")
    lines = [_axis_lines(spec, a, refine) for a in range(3)]
    cell_type, sizes = _cell_types(lines, spec)
    node_number, node_ijk = _active_nodes(cell_type)
    n = len(node_ijk)
    xyz = np.column_stack([lines[a][node_ijk[:, a]] for a in range(3)])
    span = max(l[-1] - l[0] for l in lines)

    surface_of = np.full(n, -1, dtype=np.int64)
    rbe2 = []
    for q, patch in enumerate(spec.patches):
        nodes = _patch_nodes(lines, cell_type, node_number, node_ijk, spec, patch)
        if np.any(surface_of[nodes] >= 0):
            raise ValueError(f"RBE2 patches '{spec.patches[surface_of[nodes].max()].name}' and '{patch.name}' "
                             f"of body '{spec.name}' share nodes; make them disjoint")
        surface_of[nodes] = q
        centroid = xyz[nodes].mean(axis=0)
        centroid[np.abs(centroid) < 1e-12 * span] = 0.0   # symmetric patches: exact zeros, not round-off
        rbe2.append(Rbe2Node(patch.name, nodes, centroid, patch.point_mass))
    _check_patches_apart(spec, node_number, node_ijk, surface_of)

    solid_active = np.nonzero(surface_of < 0)[0]
    reduced = np.empty(n, dtype=np.int64)
    reduced[solid_active] = np.arange(len(solid_active))
    reduced[surface_of >= 0] = len(solid_active) + surface_of[surface_of >= 0]
    return GridBody(spec, refine, lines, cell_type, sizes, node_number, node_ijk, rbe2, reduced, solid_active)


def _check_patches_apart(spec, node_number, node_ijk, surface_of):
    """The assembly assumes no element touches two different RBE2 surfaces."""
    if len(spec.patches) < 2:
        return
    nn = np.pad(node_number, 1, constant_values=-1)
    sof = np.append(surface_of, -1)
    for q in range(len(spec.patches)):
        ijk = node_ijk[surface_of == q] + 1
        for d in np.ndindex(3, 3, 3):
            nb = nn[tuple((ijk + np.array(d) - 1).T)]
            other = sof[nb]
            if np.any((other >= 0) & (other != q)):
                q2 = int(other[(other >= 0) & (other != q)][0])
                raise ValueError(f"RBE2 patches '{spec.patches[q].name}' and '{spec.patches[q2].name}' "
                                 f"of body '{spec.name}' are adjacent; leave at least one element between them")
