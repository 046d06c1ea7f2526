# CScene: bodies, joints, inputs and outputs (the C KFScene, a reference-counted PETSc object).

cdef KFJointType joint_type(kind, name) except *:
    if kind == "revolute":
        return KF_JOINT_REVOLUTE
    if kind == "fixed":
        return KF_JOINT_FIXED
    raise ValueError("joint %r: type %r is not 'revolute' or 'fixed'" % (name, kind))


cdef cnp.ndarray column_major_3x3(R0, what):
    R = np.asarray(R0, dtype=np.float64)
    if R.shape != (3, 3) or not np.all(np.isfinite(R)):
        raise ValueError("%s must be a finite 3x3 matrix" % what)
    return np.ascontiguousarray(R.T.ravel())


cdef cnp.ndarray axis_vector(axis, what):
    ax = np.ascontiguousarray(axis, dtype=np.float64).ravel()
    if ax.shape[0] != 3 or not np.all(np.isfinite(ax)):
        raise ValueError("%s: axis needs 3 finite components, got %r" % (what, axis))
    return ax


cdef class CScene:
    """Bodies, joints, inputs and outputs (the C KFScene)."""
    cdef KFScene s

    def __cinit__(self, comm=None):
        cdef Comm c = as_comm(comm)
        check(KFSceneCreate(c.comm, &self.s))

    def __dealloc__(self):
        release(<PetscObject*>&self.s)

    def add_body(self, name, Mat M not None, Mat K not None, ids, xyz, ndof):
        cdef cnp.ndarray cids = index_array(ids, "body %r node ids" % name)
        cdef cnp.ndarray cndof = index_array(ndof, "body %r dofs per node" % name)
        cdef cnp.ndarray cxyz = np.ascontiguousarray(xyz, dtype=np.float64).reshape(-1, 3)
        cdef PetscInt b = -1
        if not (cids.shape[0] == cndof.shape[0] == cxyz.shape[0]):
            raise ValueError("body %r: ids, coordinates and dof counts must have one entry per node (%d, %d, %d)"
                             % (name, cids.shape[0], cxyz.shape[0], cndof.shape[0]))
        if cids.shape[0] == 0:
            raise ValueError("body %r has no nodes" % name)
        check(KFSceneAddBody(self.s, cstr(name, "body name"), M.mat, K.mat, <PetscInt>cids.shape[0],
                             int_ptr(cids), real_ptr(cxyz), int_ptr(cndof), &b))
        return b

    def add_body_components(self, name, Mat M not None, Mat K not None, ids, xyz, comps):
        """A body with any dof layout: comps[i] is node i's component set, bit c for component c (ux uy uz rx ry
        rz), 0 for a scalar point."""
        cdef cnp.ndarray cids = index_array(ids, "body %r node ids" % name)
        cdef cnp.ndarray ccomps = index_array(comps, "body %r node components" % name)
        cdef cnp.ndarray cxyz = np.ascontiguousarray(xyz, dtype=np.float64).reshape(-1, 3)
        cdef PetscInt b = -1
        if not (cids.shape[0] == ccomps.shape[0] == cxyz.shape[0]):
            raise ValueError("body %r: ids, coordinates and component sets must have one entry per node (%d, %d, %d)"
                             % (name, cids.shape[0], cxyz.shape[0], ccomps.shape[0]))
        if cids.shape[0] == 0:
            raise ValueError("body %r has no nodes" % name)
        check(KFSceneAddBodyComponents(self.s, cstr(name, "body name"), M.mat, K.mat, <PetscInt>cids.shape[0],
                                       int_ptr(cids), real_ptr(cxyz), int_ptr(ccomps), &b))
        return b

    def add_interface(self, PetscInt body, name, PetscInt node_id):
        check(KFSceneAddInterface(self.s, body, cstr(name, "interface name"), node_id))

    def add_joint(self, name, kind, PetscInt parent, parent_interface, PetscInt child, child_interface,
                  axis=(0, 0, 1), R0=None):
        cdef KFJointType t = joint_type(kind, name)
        cdef cnp.ndarray cax = axis_vector(axis, "joint %r" % name)
        cdef cnp.ndarray cR0 = None if R0 is None else column_major_3x3(R0, "joint %r: orientation" % name)
        cdef bytes pif = b"" if parent_interface is None else cstr(parent_interface, "interface name")
        check(KFSceneAddJoint(self.s, cstr(name, "joint name"), t, parent, NULL if parent_interface is None else <const char*>pif,
                              child, cstr(child_interface, "interface name"), real_ptr(cax),
                              NULL if cR0 is None else real_ptr(cR0)))

    def add_ground_joint(self, name, kind, PetscInt child, child_interface, axis=(0, 0, 1), R0=None):
        """A joint to ground (KF_GROUND): clamps the child's interface node (a revolute joint leaves the rotation
        about its axis free)."""
        self.add_joint(name, kind, -1, None, child, child_interface, axis, R0)

    def add_constraint(self, PetscInt body, PetscInt node_id, dofs=None):
        """Clamps components of a node: dofs a Nastran component string ("123456"), None for all it has."""
        cdef bytes d = b"" if dofs is None else cstr(dofs, "constraint dofs")
        check(KFSceneAddConstraint(self.s, body, node_id, d))

    def add_spring(self, PetscInt body, PetscInt node_id, PetscInt comp, PetscReal stiffness):
        check(KFSceneAddSpring(self.s, body, node_id, comp, stiffness))

    def rigid_count(self):
        """Rigid-body and mechanism modes derived from geometry, joints and boundary conditions (-1 before a
        system derived them)."""
        cdef PetscInt r
        check(KFSceneGetRigidCount(self.s, &r))
        return r

    def set_num_io(self, PetscInt ninputs, PetscInt noutputs):
        check(KFSceneSetNumIO(self.s, ninputs, noutputs))

    def add_input_load(self, PetscInt io, PetscInt body, PetscInt node_id, PetscInt comp, PetscReal w=1.0):
        check(KFSceneAddInputLoad(self.s, io, body, node_id, comp, w))

    def add_output_reading(self, PetscInt io, PetscInt body, PetscInt node_id, PetscInt comp, PetscReal w=1.0):
        check(KFSceneAddOutputReading(self.s, io, body, node_id, comp, w))

    def add_input_vector(self, PetscInt io, PetscInt body, Vec g not None):
        check(KFSceneAddInputVector(self.s, io, body, g.vec))

    def add_output_vector(self, PetscInt io, PetscInt body, Vec h not None):
        check(KFSceneAddOutputVector(self.s, io, body, h.vec))

    def set_body_damping(self, PetscInt body, Mat C not None):
        """body's viscous damping matrix C_b (n_b x n_b, symmetric, M's layout); checked at once"""
        check(KFSceneSetBodyDamping(self.s, body, C.mat))

    def set_output_quantity(self, PetscInt output, quantity):
        """displacement, velocity or acceleration"""
        check(KFSceneSetOutputQuantity(self.s, output, quantity_code(quantity, output)))

    def output_quantity(self, PetscInt output):
        cdef KFQuantity q
        check(KFSceneGetOutputQuantity(self.s, output, &q))
        return ["displacement", "velocity", "acceleration"][<int>q]

    def setup(self):
        check(KFSceneSetUp(self.s))

    def info(self):
        cdef PetscInt nb, nj, nr, ns, ni, no
        check(KFSceneGetInfo(self.s, &nb, &nj, &nr, &ns, &ni, &no))
        return dict(bodies=nb, joints=nj, revolute=nr, system_dofs=ns, inputs=ni, outputs=no)

    def body_info(self, PetscInt b):
        cdef const char *name
        cdef PetscInt n, nn
        check(KFSceneGetBodyInfo(self.s, b, &name, &n, &nn))
        return dict(name=name.decode(), dofs=n, nodes=nn)

    def body_matrices(self, PetscInt b):
        cdef PetscMat M, K, G, Ht
        check(KFSceneGetBodyMatrices(self.s, b, &M, &K, &G, &Ht))
        return wrap_mat(M, True), wrap_mat(K, True), wrap_mat(G, True), wrap_mat(Ht, True)

    def body_symmetric(self, PetscInt b):
        """(M, K) of body b found exactly symmetric (A = A^T entry for entry) when the scene was set up."""
        cdef PetscBool m, k
        check(KFSceneGetBodySymmetric(self.s, b, &m, &k))
        return bool(m), bool(k)

    def set_name(self, name):
        check(KFSceneSetName(self.s, cstr(name, "scene name")))

    def set_io_name(self, bint is_input, PetscInt i, name):
        check(KFSceneSetIOName(self.s, PETSC_TRUE if is_input else PETSC_FALSE, i, cstr(name, "input/output name")))

    def fingerprint(self):
        """16 hex digits over bodies, dofs, interfaces, joints, inputs, outputs: what a reduced model must match."""
        cdef char fp[17]
        check(KFSceneGetFingerprint(self.s, fp))
        return fp.decode()
