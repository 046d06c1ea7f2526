"""The reduced model as an Exudyn multibody system: one ObjectFFRFreducedOrder per body, joined as the model's joints.

    from kryflex.export.exudyn import build_mbs, set_input, output_values, joint_angles
    SC, mbs, h = build_mbs("out/reduced.h5", [30.0])            # assembled, at 30 deg
    lam, _ = mbs.ComputeODE2Eigenvalues()                         # linearized: kryflex's frequencies at 30 deg
    set_input(mbs, h, "tip_force", 10.0)                          # input amplitude (scene units), any time
    y = output_values(mbs, h)                                     # outputs (dict name -> value) of the current state
    a = joint_angles(mbs, h)                                      # revolute joints' current angles (degrees)

Per body (bodies.py): a rigid-body node (the floating frame; Euler parameters by default: no singularity), a generic
node with the flexible coordinates q, and ObjectFFRFreducedOrder with the reduced flexible mass (identity) and
stiffness (diagonal), and the frame's exact mass, centre of mass and inertia. The flexible shapes are M-orthogonal to
the rigid motions, so the rigid-flexible mass couplings mPhitTPsi and mXRefTildePsi are zero; the second-order
inertia terms (mPsiTildePsi, mPsiTildePsiTilde, mPhitTPsiTilde, mXRefTildePsiTilde: how the inertia changes with the
elastic deformation) need the full-order mass matrix and mode shapes over every node, which a reduced model does not
hold: they are set to zero. They vanish in the linearization at rest (eigenvalues, frequency responses), and in a
time simulation they matter only where elastic deflections change the inertia noticeably (fast spin of very
flexible bodies).

Mesh nodes: an Exudyn body's markers need mesh nodes with 3 translations; a reduced body knows its interface nodes
(6 dofs: translations and rotations) only. Each interface node becomes 7 mesh nodes: the node itself, and 6 points at
+-d along the frame's axes that move rigidly with it, u = u_I + theta_I x d (d: 'arm', default 1/10 of the body's
radius of gyration). A MarkerSuperElementRigid over the 6 points (equal weights; Exudyn's default alternative
approach fits the rotation with the points' inertia-like matrix, exact for a rigid motion) gives the interface node's
position and rotation, so joints tie exactly what kryflex ties (eq. 20: translations, and the rotations across the
axis of a revolute joint). This works for bodies of any node type: solids (3-dof nodes with RBE2 interface nodes),
beams and shells alike; the reduced matrices carry the rotary inertia already.

Joints: GenericJoint between the interface markers, in a joint frame whose z is the joint axis; a revolute joint
leaves the rotation about it free (constrainedAxes [1,1,1,1,1,0]), a fixed joint ties all six. The angle is set by
the configuration: each child body's frame is the parent's turned by R(alpha) = Rot(axis, alpha) R0, placed so that
the interface nodes coincide. Bodies not reached from the first body through joints stay where the scene has them.

Ties (a model of shared directions, export/ties.py): linear constraints on the bodies' flexible coordinates,
ObjectConnectorCoordinateVector between the modal nodes (_add_ties).

Inputs: per body the generalized forces of a unit input, a body-fixed force and torque on the frame (about its origin)
and a load on each flexible coordinate; set_input scales them all. Outputs: the linear outputs of kryflex,
y = H R r + H F q, with r the frame's small motion relative to its reference (body frame) and q the flexible
coordinates (output_values).
"""
import numpy as np

from .bodies import ExportError


def _exudyn():
    try:
        import exudyn
        import exudyn.itemInterface  # noqa: F401
        import exudyn.rigidBodyUtilities  # noqa: F401
    except ImportError as e:
        raise ExportError("Exudyn is not installed in this Python (%s): run kryflex from the project's .venv, which "
                          "scripts/setup makes with Exudyn 1.13.6" % e) from None
    return exudyn


def _rotation(axis, R0, alpha):
    from exudyn.rigidBodyUtilities import RotationVector2RotationMatrix
    k = np.asarray(axis, dtype=float)
    k = k / np.linalg.norm(k)
    return np.asarray(RotationVector2RotationMatrix(list(alpha * k))) @ np.asarray(R0, dtype=float)


def _joint_frame(axis):
    """An orthonormal frame (columns) whose third axis is the joint axis."""
    k = np.asarray(axis, dtype=float)
    k = k / np.linalg.norm(k)
    c = np.zeros(3)
    c[np.argmin(np.abs(k))] = 1.0
    e1 = c - (c @ k) * k
    e1 /= np.linalg.norm(e1)
    return np.column_stack([e1, np.cross(k, e1), k])


def placements(data, angles_deg):
    """Frame position p and orientation A (global) of every body at the given angles (degrees, one per revolute
    joint, in joint order): the first body at the origin, each child placed by its joint from its parent."""
    angles = np.atleast_1d(np.asarray(angles_deg, dtype=float))
    nrev = len(data.revolute)
    if angles.ndim != 1 or angles.size != nrev or not np.all(np.isfinite(angles)):
        raise ExportError("the model has %d revolute joint(s) (%s): give %d finite angle(s) in degrees, got %s"
                          % (nrev, ", ".join(data.revolute), nrev, list(np.atleast_1d(angles_deg))))
    rot, irev = [], 0
    for j in data.joints:
        if j["type"] == "revolute":
            rot.append(_rotation(j["axis"], j["R0"], np.radians(angles[irev])))
            irev += 1
        else:
            rot.append(np.asarray(j["R0"], dtype=float))
    nb = len(data.bodies)
    place = [None] * nb
    for start in range(nb):                     # one tree per connected group, rooted at its first body
        if place[start] is not None:
            continue
        place[start] = (np.zeros(3), np.eye(3))
        grown = True
        while grown:
            grown = False
            for j, R in zip(data.joints, rot):
                p, c = j["parent"], j["child"]
                if place[p] is not None and place[c] is None:
                    pp, Ap = place[p]
                    Ac = Ap @ R
                    xp = data.bodies[p].interface_positions[j["parent_interface"]]
                    xc = data.bodies[c].interface_positions[j["child_interface"]]
                    place[c] = (pp + Ap @ xp - Ac @ xc, Ac)
                    grown = True
                elif place[c] is not None and place[p] is None:
                    pc, Ac = place[c]
                    Ap = Ac @ R.T
                    xp = data.bodies[p].interface_positions[j["parent_interface"]]
                    xc = data.bodies[c].interface_positions[j["child_interface"]]
                    place[p] = (pc + Ac @ xc - Ap @ xp, Ap)
                    grown = True
    return place, rot


def _mesh_nodes(body, arm):
    """Reference positions (nodes x 3) and mode basis (3 nodes x f) of the 7 mesh nodes per interface node."""
    f = body.nflex
    xs, rows = [], []
    offsets = [np.zeros(3)] + [s * arm * e for e in np.eye(3) for s in (1.0, -1.0)]
    from .bodies import skew
    for i in range(len(body.interfaces)):
        U = body.interface_modes[i]               # (6, f): translations, rotations
        for d in offsets:
            xs.append(body.interface_positions[i] + d)
            rows.append(U[:3] - skew(d) @ U[3:])  # u + theta x d = u - d x theta
    if not xs:
        return np.zeros((0, 3)), np.zeros((0, f))
    return np.array(xs), np.vstack(rows)


def _arm(body):
    """1/10 of the body's radius of gyration about its centre of mass (a length of the body's own scale)."""
    c = body.center_of_mass
    Jc = body.inertia - body.mass * (np.dot(c, c) * np.eye(3) - np.outer(c, c))
    r = np.sqrt(max(np.trace(Jc), 0.0) / (2 * body.mass))
    return 0.1 * r if r > 0 else 1.0


def build_mbs(source, angles_deg, SC=None, mbs=None, assemble=True, arm=None, modal_damping=0.0,
              rotation="RotationEulerParameters", show_nodes=False):
    """An Exudyn system of the reduced model at the given angles (degrees, one per revolute joint).

    source: a MultibodyExport, a ReducedModel, a reduced-model file (.h5) or a neutral export (.npz).
    SC, mbs: an existing SystemContainer / MainSystem to add to (default: new ones). arm: the mesh points' distance
    from their interface node (default per body: 1/10 of its radius of gyration). Returns (SC, mbs, handles), handles a
    dict: 'export' (the MultibodyExport), 'bodies' (per body name: object, rigid_node, modal_node, nodes, markers per
    interface name, reference position and rotation), 'joints' (name -> object), 'inputs' (name -> loads with their
    unit vectors), 'outputs' (name -> per body the coefficient rows)."""
    exu = _exudyn()
    from exudyn import itemInterface as eii
    from exudyn.rigidBodyUtilities import GetRigidBodyNode

    from . import load
    data = load(source)
    if not data.floating:
        body = next(b for b in data.bodies if not b.floating)
        raise ExportError("%s: Exudyn's floating-frame bodies need all 6 rigid motions; a structure without joints goes "
                          "to Exudyn as its reassembled system (kryflex.export.systems.system_mbs of the export's "
                          "systems[0], as 'kryflex export --format exudyn' does)" % body.why_not_floating())
    zeta = float(modal_damping)
    if not (np.isfinite(zeta) and zeta >= 0):
        raise ExportError("modal_damping %r: give a damping ratio >= 0" % (modal_damping,))
    if rotation not in ("RotationEulerParameters", "RotationRotationVector", "RotationRxyz"):
        raise ExportError("rotation %r: use RotationEulerParameters, RotationRotationVector or RotationRxyz" % (rotation,))
    place, rot = placements(data, angles_deg)
    if SC is None:
        SC = exu.SystemContainer()
    if mbs is None:
        mbs = SC.AddSystem()
    handles = dict(export=data, angles_deg=list(np.atleast_1d(np.asarray(angles_deg, dtype=float))), bodies={},
                   joints={}, inputs={n: [] for n in data.inputs}, outputs={n: [] for n in data.outputs})
    for b, (body, (p, A)) in enumerate(zip(data.bodies, place)):
        f = body.nflex
        xref, Psi = _mesh_nodes(body, arm if arm is not None else _arm(body))
        if not len(xref):
            # a body without interface nodes still needs one mesh node (Exudyn requires a mode basis): its frame origin
            xref, Psi = np.zeros((1, 3)), np.zeros((3, f))
        node = GetRigidBodyNode(getattr(exu.NodeType, rotation), position=list(p), rotationMatrix=A.tolist())
        node.name = "frame:" + body.name
        nRigid = mbs.AddNode(node)
        if f == 0:
            # reduced to its rigid motions: an Exudyn rigid body (inertia about the node, the frame's origin)
            nModal, J = None, body.inertia
            obj = mbs.AddObject(eii.ObjectRigidBody(name=body.name, nodeNumber=nRigid, mass=body.mass,
                                                    inertia=[J[0, 0], J[1, 1], J[2, 2], J[1, 2], J[0, 2], J[0, 1]],
                                                    centerOfMass=list(body.center_of_mass)))
        else:
            obj, nModal = _add_ffrf(exu, eii, mbs, body, nRigid, xref, Psi, zeta, show_nodes)
        markers = {}
        for i, name in enumerate(body.interfaces):
            markers[name] = dict(rigid=_interface_marker(exu, eii, mbs, body, obj, i, np.eye(3), "%s/%s" % (body.name, name)),
                                 mesh_node=7 * i if f else None)
            if f:
                markers[name]["position"] = mbs.AddMarker(eii.MarkerSuperElementPosition(
                    name="%s/%s:position" % (body.name, name), bodyNumber=obj, meshNodeNumbers=[7 * i],
                    weightingFactors=[1.0]))
            else:
                markers[name]["position"] = mbs.AddMarker(eii.MarkerBodyPosition(
                    name="%s/%s:position" % (body.name, name), bodyNumber=obj,
                    localPosition=list(body.interface_positions[i])))
        handles["bodies"][body.name] = dict(object=obj, rigid_node=nRigid, modal_node=nModal, markers=markers,
                                            position=p, rotation=A, mesh_positions=xref)
        _add_inputs(mbs, eii, handles, body, nRigid, nModal)
        for k, name in enumerate(data.outputs):
            if np.any(body.output_rigid[k]) or np.any(body.output_flex[k]):
                handles["outputs"][name].append(dict(body=body.name, rigid=body.output_rigid[k].copy(),
                                                     flex=body.output_flex[k].copy()))
    for j, R in zip(data.joints, rot):
        P, C = data.bodies[j["parent"]], data.bodies[j["child"]]
        Jp = _joint_frame(j["axis"])              # joint frame in the parent's body frame
        Jc = R.T @ Jp                             # the same frame in the child's body frame at this configuration
        ends = []
        for body, i, Jb in ((P, j["parent_interface"], Jp), (C, j["child_interface"], Jc)):
            # the joint's own marker on the interface, its frame turned to the joint frame
            ends.append(_interface_marker(exu, eii, mbs, body, handles["bodies"][body.name]["object"], i, Jb,
                                          "%s:%s/%s" % (j["name"], body.name, body.interfaces[i])))
        axes = [1, 1, 1, 1, 1, 0] if j["type"] == "revolute" else [1] * 6
        handles["joints"][j["name"]] = mbs.AddObject(eii.ObjectJointGeneric(
            name=j["name"], markerNumbers=ends, constrainedAxes=axes, visualization=eii.VObjectJointGeneric(show=False)))
    handles["ties"] = _add_ties(eii, mbs, data, handles)
    if assemble:
        mbs.Assemble()
    return SC, mbs, handles


def _add_ties(eii, mbs, data, handles):
    """A model of shared directions: its coordinate ties T q = 0 on the bodies' flexible coordinates (export/ties.py)
    as linear coordinate constraints, ObjectConnectorCoordinateVector (X_m1 q_m1 - X_m0 q_m0 = 0, Exudyn's sign):
    one connector per pair of bodies the rows couple, between the MarkerNodeCoordinates of their modal nodes; one per
    body for rows on its own coordinates (marker 0 there: the body's frame node, with no scaling). Rows that couple
    three or more bodies act on the coordinates of an ObjectGenericODE2 over those bodies' modal nodes, without mass
    or stiffness: it only gathers their coordinates for a MarkerObjectODE2Coordinates. Returns the connectors."""
    if data.ties is None:
        return []
    from .ties import split_ties
    sizes = data.coordinate_sizes
    off = np.concatenate([[0], np.cumsum(sizes)])
    names = [b.name for b in data.bodies]
    nodes = [handles["bodies"][b]["modal_node"] for b in names]
    groups, rest = split_ties(data.ties, sizes)
    if rest is not None:
        groups.append((tuple(b for b in range(len(sizes)) if sizes[b] and np.any(rest[:, off[b]:off[b + 1]])), rest))
    markers, out = {}, []

    def marker(key, item):
        if key not in markers:
            markers[key] = mbs.AddMarker(item)
        return markers[key]
    for bodies, rows in groups:
        label = "ties:" + "/".join(names[b] for b in bodies)
        cols = [rows[:, off[b]:off[b + 1]] for b in bodies]
        if len(bodies) == 2:
            m = [marker(b, eii.MarkerNodeCoordinates(name="ties:" + names[b], nodeNumber=nodes[b])) for b in bodies]
            X0, X1 = -cols[0], cols[1]
        else:
            m0 = marker(("frame", bodies[0]), eii.MarkerNodeCoordinates(
                name="ties:frame:" + names[bodies[0]], nodeNumber=handles["bodies"][names[bodies[0]]]["rigid_node"]))
            if len(bodies) == 1:
                b = bodies[0]
                m1 = marker(b, eii.MarkerNodeCoordinates(name="ties:" + names[b], nodeNumber=nodes[b]))
            else:
                n = sum(sizes[b] for b in bodies)
                gather = mbs.AddObject(eii.ObjectGenericODE2(
                    name=label, nodeNumbers=[nodes[b] for b in bodies], massMatrix=np.zeros((n, n)),
                    stiffnessMatrix=np.zeros((n, n)), visualization=eii.VObjectGenericODE2(show=False)))
                m1 = mbs.AddMarker(eii.MarkerObjectODE2Coordinates(name=label, objectNumber=gather))
            m, X0, X1 = [m0, m1], np.zeros((0, 0)), np.hstack(cols)
        out.append(mbs.AddObject(eii.ObjectConnectorCoordinateVector(
            name=label, markerNumbers=m, scalingMarker0=X0, scalingMarker1=X1, offset=np.zeros(rows.shape[0]))))
    return out


def _add_ffrf(exu, eii, mbs, body, nRigid, xref, Psi, zeta, show_nodes):
    """The body's ObjectFFRFreducedOrder and the node of its flexible coordinates."""
    f = body.nflex
    nModal = mbs.AddNode(eii.NodeGenericODE2(name="modes:" + body.name, numberOfODE2Coordinates=f,
                                             referenceCoordinates=[0.0] * f, initialCoordinates=[0.0] * f,
                                             initialCoordinates_t=[0.0] * f))
    Mmc, Kmc = exu.MatrixContainer(), exu.MatrixContainer()
    Mmc.SetWithDenseMatrix(body.mass_flex, useDenseMatrix=True)
    Kmc.SetWithDenseMatrix(body.stiffness_flex, useDenseMatrix=True)
    Dmc = []
    # modal damping on the body's flexible modes plus its own viscous damping matrix in flexible coordinates
    D = np.diag(2 * zeta * 2 * np.pi * body.frequencies_hz) + body.damping_flex
    if np.any(D):
        Dmc = exu.MatrixContainer()
        Dmc.SetWithDenseMatrix(D, useDenseMatrix=True)
    z3ff, R = np.zeros((3, 3 * f)), body.rigid_coords
    obj = mbs.AddObject(eii.ObjectFFRFreducedOrder(
        name=body.name, nodeNumbers=[nRigid, nModal], massMatrixReduced=Mmc, stiffnessMatrixReduced=Kmc,
        dampingMatrixReduced=Dmc, modeBasis=Psi, referencePositions=xref.ravel(), mass=body.mass,
        inertia=body.inertia, centerOfMass=body.center_of_mass, mPsiTildePsi=np.zeros((3 * f, f)),
        mPsiTildePsiTilde=np.zeros((3 * f, 3 * f)), mPhitTPsiTilde=z3ff, mXRefTildePsiTilde=z3ff,
        # Phit^T M Psi and xRefTilde^T M Psi: the rigid motions' couplings with the flexible shapes (~0 here)
        mPhitTPsi=R[:, :3].T @ body.M @ body.modes, mXRefTildePsi=-R[:, 3:].T @ body.M @ body.modes,
        computeFFRFterms=True, visualization=eii.VObjectFFRFreducedOrder(showNodes=show_nodes)))
    return obj, nModal


def _interface_marker(exu, eii, mbs, body, obj, i, frame, name):
    """A rigid marker at interface i whose frame is `frame` (columns, body frame): on the 6 points of a flexible body
    (MarkerSuperElementRigid), at the node of a rigid one (MarkerBodyRigid)."""
    if body.nflex:
        return mbs.AddMarker(eii.MarkerSuperElementRigid(
            name=name, bodyNumber=obj, meshNodeNumbers=[7 * i + k for k in range(1, 7)], weightingFactors=[1.0 / 6] * 6,
            useAlternativeApproach=True, localHT=exu.HT(rotation=frame.tolist(), translation=[0.0, 0.0, 0.0])))
    return mbs.AddMarker(eii.MarkerBodyRigid(name=name, bodyNumber=obj, localHT=exu.HT(
        rotation=frame.tolist(), translation=list(body.interface_positions[i]))))


def _add_inputs(mbs, eii, handles, body, nRigid, nModal):
    """Loads of every input acting on the body, at amplitude 0 (set_input sets them): a body-fixed force and torque on
    the frame, and one load per flexible coordinate."""
    frame = None
    coords = {}
    for k, name in enumerate(handles["export"].inputs):
        g_r, g_f = body.input_rigid[:, k], body.input_flex[:, k]
        if not (np.any(g_r) or np.any(g_f)):
            continue
        if frame is None:
            frame = mbs.AddMarker(eii.MarkerNodeRigid(nodeNumber=nRigid))
        entry = dict(body=body.name, force=mbs.AddLoad(eii.LoadForceVector(markerNumber=frame, bodyFixed=True,
                                                                          loadVector=[0.0] * 3)),
                     torque=mbs.AddLoad(eii.LoadTorqueVector(markerNumber=frame, bodyFixed=True, loadVector=[0.0] * 3)),
                     unit_force=g_r[:3].copy(), unit_torque=g_r[3:].copy(), modal=[])
        for i in np.nonzero(g_f)[0]:
            if i not in coords:
                coords[i] = mbs.AddMarker(eii.MarkerNodeCoordinate(nodeNumber=nModal, coordinate=int(i)))
            entry["modal"].append((mbs.AddLoad(eii.LoadCoordinate(markerNumber=coords[i], load=0.0)), float(g_f[i])))
        handles["inputs"][name].append(entry)


def set_input(mbs, handles, name, value):
    """Sets input `name` to `value` (the scene's input units): every load it makes, on every body."""
    if name not in handles["inputs"]:
        raise ExportError("no input '%s' (inputs: %s)" % (name, ", ".join(handles["inputs"])))
    for e in handles["inputs"][name]:
        mbs.SetLoadParameter(e["force"], "loadVector", list(value * e["unit_force"]))
        mbs.SetLoadParameter(e["torque"], "loadVector", list(value * e["unit_torque"]))
        for load, g in e["modal"]:
            mbs.SetLoadParameter(load, "load", value * g)


def frame_motion(mbs, handles, body):
    """The frame's small motion r (6: translation, rotation vector) relative to its reference, in the reference body
    frame; and the flexible coordinates q."""
    from exudyn.rigidBodyUtilities import RotationMatrix2RotationVector
    import exudyn as exu
    h = handles["bodies"][body]
    A0, p0 = h["rotation"], h["position"]
    p = np.asarray(mbs.GetNodeOutput(h["rigid_node"], exu.OutputVariableType.Position))
    A = np.asarray(mbs.GetNodeOutput(h["rigid_node"], exu.OutputVariableType.RotationMatrix)).reshape(3, 3)
    r = np.concatenate([A0.T @ (p - p0), np.asarray(RotationMatrix2RotationVector(A0.T @ A))])
    q = np.zeros(0) if h["modal_node"] is None else \
        np.asarray(mbs.GetNodeOutput(h["modal_node"], exu.OutputVariableType.Coordinates))
    return r, q


def output_values(mbs, handles):
    """kryflex's outputs y = H R r + H F q of the current state (dict name -> value): linear in the frames' motions
    relative to the reference configuration and in the flexible coordinates, as kryflex defines them."""
    y = {}
    for name, parts in handles["outputs"].items():
        total = 0.0
        for part in parts:
            r, q = frame_motion(mbs, handles, part["body"])
            total += float(part["rigid"] @ r + part["flex"] @ q)
        y[name] = total
    return y


# eigenvalues at or below this fraction of the largest are rigid-body or mechanism modes
ZERO_TOL = 1e-12
# or at or below this many times the energy K carries in kryflex's rigid modes (a stiffness rounded when exported
# leaves them a little, of either sign: kryflex check reports it; the same margin as its null-pivot count)
RIGID_MARGIN = 100.0


def rigid_level(M, K, Phir):
    """RIGID_MARGIN x the largest |Rayleigh quotient| of K on the rigid modes Phir (rad^2/s^2), 0 without them."""
    if Phir is None or not np.asarray(Phir).shape[1]:
        return 0.0
    Phir = np.asarray(Phir)
    import scipy.linalg as sl
    lam = sl.eigh(Phir.T @ K @ Phir, Phir.T @ M @ Phir, eigvals_only=True)
    return RIGID_MARGIN * float(np.abs(lam).max())


def linearized_frequencies(mbs, zero_tol=ZERO_TOL, rigid=0.0):
    """The assembled system's linearized undamped frequencies (Hz) at its initial state, through Exudyn's
    ComputeODE2Eigenvalues (constraints by the null space of their Jacobian): (flexible frequencies ascending, number
    of rigid-body and mechanism modes: |lambda| <= zero_tol * max |lambda| or <= rigid (rigid_level), and the lowest
    of those eigenvalues when below -zero_tol * max |lambda|, as a stiffness rounded when exported gives them,
    else 0)."""
    lam, _ = mbs.ComputeODE2Eigenvalues(useAbsoluteValues=False)
    lam = np.sort(np.real(np.asarray(lam)))
    top = np.abs(lam).max() if lam.size else 0.0
    zero = np.abs(lam) <= max(zero_tol * top, rigid)
    flex = lam[~zero]
    if np.any(flex < 0):
        raise ExportError("the Exudyn system has %d negative eigenvalue(s) (lowest %.3g): its linearization is unstable"
                          % (int(np.sum(flex < 0)), flex.min()))
    low = float(lam[zero].min()) if zero.any() else 0.0
    return np.sqrt(flex) / (2 * np.pi), int(zero.sum()), low if low < -zero_tol * top else 0.0


def joint_angles(mbs, handles):
    """The revolute joints' current angles (dict name -> degrees): the configured angle plus the joint's relative
    rotation about its axis since then (Exudyn's joint output; that change is wrapped to (-180, 180] deg)."""
    import exudyn as exu
    data, out, irev = handles["export"], {}, 0
    for j in data.joints:
        if j["type"] != "revolute":
            continue
        turn = mbs.GetObjectOutput(handles["joints"][j["name"]], exu.OutputVariableType.Rotation)[2]
        out[j["name"]] = handles["angles_deg"][irev] + float(np.degrees(turn))
        irev += 1
    return out
