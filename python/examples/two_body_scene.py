#!/usr/bin/env python3
"""A two-body scene built from scratch in Python and reduced with kryflex.

A spacecraft "bus" (a stubby free-free 3-D beam with the equipment mass at its bottom) carries a long
magnetometer "boom" on a revolute hinge at its top. Both bodies are meshed here with 3-D Euler-Bernoulli
beam elements, the way any finite-element code produces its matrices:

  * the bus is assembled element by element straight into a distributed petsc4py Mat, each rank adding the
    elements it owns (what DOLFINx's assemble_matrix hands you);
  * the boom is assembled into a SciPy sparse matrix (what a NumPy/SciPy code or an exported model gives you).

kryflex then reduces the articulated model (the hinge motor's torque in; the hinge encoder and the boom tip's
sideways displacement out), and everything after that is small dense NumPy: the reduced bodies, the reduced
system at any hinge angle, its moments and its frequency response.

Run (the output folder is created; default ./two_body_out):

    PYTHONPATH=python /usr/bin/python3 python/examples/two_body_scene.py [OUTDIR] [-quiet] [PETSc options]
    mpiexec -n 2 /usr/bin/python3 python/examples/two_body_scene.py OUTDIR

It writes OUTDIR/two_body.h5 (the reduced model; reload with kryflex.ReducedModel.load), OUTDIR/two_body.npz
(its arrays exported for NumPy) and OUTDIR/bode.png, and prints a summary.
"""
import os
import sys

import numpy as np
import scipy.sparse as sp

import kryflex

kryflex.init(sys.argv)               # first: hand the command line to PETSc/SLEPc (e.g. -log_view)
from petsc4py import PETSc  # noqa: E402

COMM = PETSc.COMM_WORLD

# The angles we want the model for (degrees of the hinge); 45 and 75 are NOT given to the reduction:
# the reduced model is reassembled there from the reduced bodies alone.
ANGLES_OF_INTEREST = [0.0, 30.0, 60.0, 90.0]
OTHER_ANGLES = [45.0, 75.0]
BAND_HZ = [0.01, 20.0]
DAMPING = 0.005


# ----------------------------------------------------------------------------------------------------------
# A 3-D Euler-Bernoulli beam element (12 dofs: ux uy uz rx ry rz at each end), consistent mass.

def beam_element(xa, xb, E, G, A, Iy, Iz, rho, up=(0.0, 0.0, 1.0)):
    """Stiffness and mass (12 x 12, global axes) of a straight beam from xa to xb.

    Iy, Iz: second moments about the section's local y and z axes; local x runs along the beam and local z is
    the part of `up` perpendicular to it (any vector not parallel to the beam).
    """
    xa, xb = np.asarray(xa, float), np.asarray(xb, float)
    L = np.linalg.norm(xb - xa)
    ex = (xb - xa) / L
    up = np.asarray(up, float)
    if abs(ex @ up) > 0.99 * np.linalg.norm(up):      # beam along `up`: take another reference direction
        up = np.array([1.0, 0.0, 0.0])
    ez = up - (up @ ex) * ex
    ez /= np.linalg.norm(ez)
    ey = np.cross(ez, ex)
    J = Iy + Iz                                        # torsion constant of a thin closed section ~ polar moment

    k = np.zeros((12, 12))
    m = np.zeros((12, 12))
    # axial (ux) and torsion (rx): two-node bars
    for (i, j), stiff, inertia in (((0, 6), E * A / L, rho * A * L), ((3, 9), G * J / L, rho * J * L)):
        k[np.ix_([i, j], [i, j])] += stiff * np.array([[1, -1], [-1, 1]])
        m[np.ix_([i, j], [i, j])] += inertia / 6 * np.array([[2, 1], [1, 2]])
    # bending in the local x-y plane (uy, rz) with Iz, and in the x-z plane (uz, ry) with Iy (opposite sign
    # convention: a positive ry turns +x towards -z)
    for dofs, I, s in (((1, 5, 7, 11), Iz, 1.0), ((2, 4, 8, 10), Iy, -1.0)):
        kb = E * I / L**3 * np.array([[12, 6 * L * s, -12, 6 * L * s],
                                       [6 * L * s, 4 * L**2, -6 * L * s, 2 * L**2],
                                       [-12, -6 * L * s, 12, -6 * L * s],
                                       [6 * L * s, 2 * L**2, -6 * L * s, 4 * L**2]])
        mb = rho * A * L / 420 * np.array([[156, 22 * L * s, 54, -13 * L * s],
                                            [22 * L * s, 4 * L**2, 13 * L * s, -3 * L**2],
                                            [54, 13 * L * s, 156, -22 * L * s],
                                            [-13 * L * s, -3 * L**2, -22 * L * s, 4 * L**2]])
        k[np.ix_(dofs, dofs)] += kb
        m[np.ix_(dofs, dofs)] += mb
    T = np.kron(np.eye(4), np.vstack([ex, ey, ez]))   # global -> local, per 3-vector
    return T.T @ k @ T, T.T @ m @ T


def lumped_mass(mass, inertia):
    """A point mass with rotary inertias (Ixx, Iyy, Izz) on one 6-dof node."""
    return np.diag([mass, mass, mass, *inertia])


def beam_mesh(points, section):
    """Node table (id x y z ndof) and element list of a beam through `points`; node ids 1, 2, ..."""
    nodes = np.array([[i + 1, *p, 6] for i, p in enumerate(points)], dtype=float)
    elements = [((i, i + 1), beam_element(points[i], points[i + 1], **section)) for i in range(len(points) - 1)]
    return nodes, elements


# ----------------------------------------------------------------------------------------------------------
# The bodies

def bus_mesh():
    """A 2 m stubby aluminium box beam along z: hinge node at the top (z = +1), 300 kg of equipment at the
    bottom. Its section and its inertia differ about x and y, so the system changes with the hinge angle."""
    points = [(0.0, 0.0, z) for z in np.linspace(1.0, -1.0, 5)]
    section = dict(E=70e9, G=27e9, A=0.02, Iy=2e-4, Iz=6e-4, rho=2700.0, up=(1.0, 0.0, 0.0))
    nodes, elements = beam_mesh(points, section)
    bottom = len(points) - 1
    elements.append(((bottom,), (np.zeros((6, 6)), lumped_mass(300.0, (80.0, 40.0, 60.0)))))
    return nodes, elements, {"hinge": 1}


def boom_mesh():
    """A 10 m carbon-fibre tube (radius 3 cm, wall 1.5 mm) along x in its own frame, its root at the hinge and
    a 5 kg magnetometer at the tip: the slender appendage whose low modes the controller must know."""
    r, t = 0.03, 1.5e-3
    I = np.pi * r**3 * t
    points = [(x, 0.0, 0.0) for x in np.linspace(0.0, 10.0, 11)]
    section = dict(E=100e9, G=38e9, A=2 * np.pi * r * t, Iy=I, Iz=I, rho=1600.0)
    nodes, elements = beam_mesh(points, section)
    elements.append(((len(points) - 1,), (np.zeros((6, 6)), lumped_mass(5.0, (0.01, 0.01, 0.01)))))
    return nodes, elements, {"root": 1}


def element_dofs(element_nodes):
    return np.concatenate([np.arange(6 * n, 6 * n + 6) for n in element_nodes]).astype(PETSc.IntType)


def assemble_petsc(n, elements, which):
    """A distributed AIJ Mat assembled like a parallel FE code: each rank adds its share of the elements
    (ADD_VALUES); PETSc sends the entries of rows owned by another rank there at assembly."""
    A = PETSc.Mat().createAIJ((n, n), comm=COMM)
    A.setPreallocationNNZ((18, 18))                    # a beam node couples with itself and two neighbours
    A.setOption(PETSc.Mat.Option.NEW_NONZERO_ALLOCATION_ERR, True)
    rank, size = COMM.getRank(), COMM.getSize()
    for e, (element_nodes, mats) in enumerate(elements):
        if e % size == rank:
            idx = element_dofs(element_nodes)
            A.setValues(idx, idx, mats[which], addv=PETSc.InsertMode.ADD_VALUES)
    A.assemble()
    return A


def assemble_scipy(n, elements, which):
    """The same assembly into a SciPy sparse matrix (COO triplets summed into CSR)."""
    rows, cols, vals = [], [], []
    for element_nodes, mats in elements:
        idx = element_dofs(element_nodes)
        rows.append(np.repeat(idx, idx.size))
        cols.append(np.tile(idx, idx.size))
        vals.append(mats[which].ravel())
    return sp.coo_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(n, n)).tocsr()


def build_scene_spec():
    """The scene as a dict with the keys of a scene file, matrices and nodes in memory."""
    bus_nodes, bus_elements, bus_interfaces = bus_mesh()
    boom_nodes, boom_elements, boom_interfaces = boom_mesh()
    n_bus, n_boom = 6 * len(bus_nodes), 6 * len(boom_nodes)
    hinge, root, tip = 1, 1, int(boom_nodes[-1, 0])
    return {
        "name": "bus_and_boom",
        "bodies": {
            "bus": {"mass": assemble_petsc(n_bus, bus_elements, 1), "stiffness": assemble_petsc(n_bus, bus_elements, 0),
                    "nodes": bus_nodes, "interfaces": bus_interfaces},
            "boom": {"mass": assemble_scipy(n_boom, boom_elements, 1),
                     "stiffness": assemble_scipy(n_boom, boom_elements, 0),
                     "nodes": boom_nodes, "interfaces": boom_interfaces},
        },
        # the hinge turns the boom about the bus's z axis (axis in the parent's frame)
        "joints": {"hinge": {"type": "revolute", "parent": "bus", "parent_interface": "hinge",
                             "child": "boom", "child_interface": "root", "axis": [0, 0, 1]}},
        # the hinge motor: equal and opposite torques about z on the two sides of the hinge
        "inputs": {"hinge_torque": [{"body": "bus", "node": hinge, "dof": "rz", "weight": 1.0},
                                    {"body": "boom", "node": root, "dof": "rz", "weight": -1.0}]},
        # the hinge encoder (the boom's rotation relative to the bus: a reading on each side) and the boom tip's
        # sideways motion (readings are in the frame of the body they are on)
        "outputs": {"hinge_encoder": [{"body": "boom", "node": root, "dof": "rz", "weight": 1.0},
                                      {"body": "bus", "node": hinge, "dof": "rz", "weight": -1.0}],
                    "boom_tip_uy": [{"body": "boom", "node": tip, "dof": "uy"}]},
        "angles": ANGLES_OF_INTEREST,
        "band": BAND_HZ,
        "damping": DAMPING,
        "accuracy": 0.05,
        # multi-angle: Krylov vectors of every angle of interest projected together, so that the reduced model
        # matches all 8 moments exactly at each of them (the paper's single-angle method matches them at one
        # angle; here the coupling of the boom with the bus's unequal inertias changes with the angle). search false:
        # the whole 8-moment basis is kept (the accuracy search would keep only what the 5 % target needs)
        "reduction": {"moments": 8, "output_blocks": 1, "method": "multi-angle", "search": False},
    }


# ----------------------------------------------------------------------------------------------------------

def say(*args):
    """Print once (on rank 0) under MPI."""
    if COMM.getRank() == 0:
        print(*args, flush=True)


def fmt(values):
    return " ".join("%.12g" % v for v in values)


def bode_plot(model, angles, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    freqs = np.geomspace(BAND_HZ[0], BAND_HZ[1], 600)
    nout = len(model.output_names)
    fig, axes = plt.subplots(2, nout, figsize=(6 * nout, 7), sharex=True, squeeze=False)
    for a in angles:
        T = model.at([a]).frf(freqs, DAMPING)[:, :, 0]          # (frequencies, outputs) for the one input
        for o in range(nout):
            axes[0, o].loglog(freqs, np.abs(T[:, o]), label="%g deg" % a)
            axes[1, o].semilogx(freqs, np.degrees(np.unwrap(np.angle(T[:, o]))))
    for o, name in enumerate(model.output_names):
        axes[0, o].set_title("%s / %s" % (name, model.input_names[0]))
        axes[0, o].set_ylabel("magnitude")
        axes[1, o].set_ylabel("phase (deg)")
        axes[1, o].set_xlabel("frequency (Hz)")
        axes[0, o].grid(True, which="both", alpha=0.3)
        axes[1, o].grid(True, which="both", alpha=0.3)
    axes[0, 0].legend(title="hinge angle")
    fig.suptitle("reduced bus + boom model, %g %% modal damping" % (100 * DAMPING))
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)


def main(argv):
    # our own arguments: the output folder (first, optional) and -quiet; PETSc reads every option itself
    outdir = os.path.abspath(argv[0] if argv and not argv[0].startswith("-") else "two_body_out")
    quiet = "-quiet" in argv or "--quiet" in argv

    # 1. the scene, from matrices in memory
    scene = kryflex.scene_from_dict(build_scene_spec())
    say("scene '%s': bodies %s with %s dofs, %d system dofs, hinge angles of interest %s deg"
        % (scene.name, ", ".join(scene.body_names), " + ".join(map(str, scene.body_dofs)),
           scene.info["system_dofs"], ", ".join("%g" % a for a in ANGLES_OF_INTEREST)))

    # 2. the reduction by the C reducer (collective: every rank calls it and gets the same small dense model back)
    result = kryflex.Reducer(scene, quiet=quiet).reduce()
    model, summary = result.model, result.summary   # summary: a kryflex.results.Summary (typed; summary.json)
    say("reduced bodies: %s dofs (%s model, Krylov vectors of %s deg)"
        % (" + ".join(map(str, model.sizes)), model.settings["method"],
           ", ".join(kryflex.Scene.label(c) for c in model.settings["reduction_angles_deg"])))
    other = result.single_angle_model         # the model of the other method: the paper's single-angle one
    say("  (the paper's single-angle model, at alpha_G = %s deg with Krylov modes %s kept: %s dofs)"
        % (summary.reduction_label, summary.kept_modes, " + ".join(map(str, other.sizes))))

    # 3. the reduced bodies are plain NumPy arrays: M (identity), K, G, H, interface rows, rigid motions
    for name, body in zip(model.body_names, model.bodies):
        M, K, G, H = body["M"], body["K"], body["G"], body["H"]
        say("  %-5s M %s  K %s  G %s  H %s  |M - I| = %.1e"
            % (name, M.shape, K.shape, G.shape, H.shape, np.abs(M - np.eye(len(M))).max()))

    # 4. reassembly at any angle needs only the reduced bodies
    for a in ANGLES_OF_INTEREST + OTHER_ANGLES:
        system = model.at([a])
        say("reduced frequencies at %g deg (Hz): %s" % (a, fmt(system.frequencies_hz[:6])))
    say("  (reassembled system: %d dofs, %d rigid-body + mechanism modes)" % (system.dofs, system.rigid_modes.shape[1]))

    # 5. how close the reduced model is to the full order at the angles of interest: the reduction's
    #    verification (summary) holds the full-order frequencies, dominant modes and moments at each of them
    for config in summary.configurations:
        label, dominant = config.label, summary.dominant_modes[config.label]
        full = np.array(config.full_frequencies_hz)
        reduced = model.at(config.angles_deg).frequencies_hz
        freq_errors = [np.min(np.abs(reduced - full[i])) / full[i] for i in dominant]
        L_full = np.array(summary.full.moments[label])          # (moments, outputs, inputs)
        L_red = model.at(config.angles_deg).moments(L_full.shape[0])
        moment_error = max(np.linalg.norm(L_full[k] - L_red[k]) / np.linalg.norm(L_full[k]) for k in range(len(L_full)))
        say("at %s deg: dominant modes %s Hz reproduced to %s; %d moments to %.1e"
            % (label, fmt(full[dominant]), " ".join("%.1e" % e for e in freq_errors),
               len(L_full), moment_error))

    # 6. low-frequency moments L^k = H (K+ M)^k K+ G of the reduced model, e.g. at an angle it was not built at
    L = model.at([45.0]).moments(4)
    pairs = ", ".join("%s/%s" % (o, model.input_names[0]) for o in model.output_names)
    say("moments at 45 deg (k = 0..3, %s):" % pairs)
    for k in range(L.shape[0]):
        say("  L^%d = %s" % (k, fmt(L[k, :, 0])))

    # 7. files: the reduced model (HDF5, written by every rank together; a NumPy export) and a Bode plot
    if COMM.getRank() == 0:
        os.makedirs(outdir, exist_ok=True)
    COMM.barrier()
    model.save(os.path.join(outdir, "two_body.h5"))
    if COMM.getRank() == 0:
        model.export_npz(os.path.join(outdir, "two_body.npz"))
        bode_plot(model, sorted(ANGLES_OF_INTEREST + OTHER_ANGLES), os.path.join(outdir, "bode.png"))
    COMM.barrier()
    say("wrote %s (two_body.h5, two_body.npz, bode.png)" % outdir)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
