# cython: language_level=3, boundscheck=False, wraparound=False
"""Bindings of the kryflex C library on petsc4py objects and NumPy arrays.

Every call checks its arguments before it reaches C, and a PETSc error becomes a
kryflex Error carrying the message of the call that failed, never a crash."""

cimport cython
import numpy as np
cimport numpy as cnp
from cpython.mem cimport PyMem_Malloc, PyMem_Free
from petsc4py.PETSc cimport Mat, Vec, Comm
from petsc4py import PETSc

cnp.import_array()

ctypedef int PetscInt
ctypedef double PetscReal
ctypedef int PetscErrorCode

cdef extern from "petsc.h":
    ctypedef struct _p_Mat
    ctypedef _p_Mat* PetscMat "Mat"
    ctypedef struct _p_Vec
    ctypedef _p_Vec* PetscVec "Vec"
    ctypedef struct _p_MPI_Comm
    ctypedef _p_MPI_Comm* MPI_Comm
    PetscErrorCode PetscObjectReference(void*)

cdef extern from "slepcbv.h":
    ctypedef struct _p_BV
    ctypedef _p_BV* BV
    PetscErrorCode BVDestroy(BV*)
    PetscErrorCode BVGetActiveColumns(BV, PetscInt*, PetscInt*)

cdef extern from "kryflex.h":
    ctypedef struct _n_KFScene
    ctypedef _n_KFScene* KFScene
    ctypedef struct _n_KFSystem
    ctypedef _n_KFSystem* KFSystem
    ctypedef struct _n_KFFlexSolver
    ctypedef _n_KFFlexSolver* KFFlexSolver
    ctypedef struct _n_KFBodyBasis
    ctypedef _n_KFBodyBasis* KFBodyBasis
    ctypedef enum KFJointType:
        KF_JOINT_REVOLUTE
        KF_JOINT_FIXED
    ctypedef enum KFImportance:
        KF_IMPORTANCE_H2
        KF_IMPORTANCE_HINF
        KF_IMPORTANCE_STATIC
    ctypedef struct KFReducedBody:
        PetscInt v
        const PetscReal *M
        const PetscReal *K
        const PetscReal *G
        const PetscReal *H
        PetscInt ninterfaces
        const PetscReal *iface
        const PetscReal *rigid
    ctypedef struct KFJointDef:
        KFJointType type
        PetscInt parent, parent_interface, child, child_interface
        PetscReal axis[3]
        PetscReal R0[9]

    PetscErrorCode KFProgress(MPI_Comm, const char*, ...)
    PetscErrorCode KFPushErrorRecorder()
    const char *KFLastError()
    void KFClearError()
    PetscErrorCode KFInitialize()
    PetscErrorCode KFMatLoadFile(MPI_Comm, const char*, PetscMat*)
    PetscErrorCode KFSceneCreate(MPI_Comm, KFScene*)
    PetscErrorCode KFSceneDestroy(KFScene*)
    PetscErrorCode KFSceneAddBody(KFScene, const char*, PetscMat, PetscMat, PetscInt, const PetscInt*, const PetscReal*, const PetscInt*, PetscInt*)
    PetscErrorCode KFSceneAddInterface(KFScene, PetscInt, const char*, PetscInt)
    PetscErrorCode KFSceneAddJoint(KFScene, const char*, KFJointType, PetscInt, const char*, PetscInt, const char*, const PetscReal*, const PetscReal*)
    PetscErrorCode KFSceneSetNumIO(KFScene, PetscInt, PetscInt)
    PetscErrorCode KFSceneAddInputLoad(KFScene, PetscInt, PetscInt, PetscInt, PetscInt, PetscReal)
    PetscErrorCode KFSceneAddInputVector(KFScene, PetscInt, PetscInt, PetscVec)
    PetscErrorCode KFSceneAddOutputReading(KFScene, PetscInt, PetscInt, PetscInt, PetscInt, PetscReal)
    PetscErrorCode KFSceneAddOutputVector(KFScene, PetscInt, PetscInt, PetscVec)
    PetscErrorCode KFSceneSetUp(KFScene)
    PetscErrorCode KFSceneGetInfo(KFScene, PetscInt*, PetscInt*, PetscInt*, PetscInt*, PetscInt*, PetscInt*)
    PetscErrorCode KFSceneGetBodyInfo(KFScene, PetscInt, const char**, PetscInt*, PetscInt*)
    PetscErrorCode KFSceneGetBodyMatrices(KFScene, PetscInt, PetscMat*, PetscMat*, PetscMat*, PetscMat*)
    PetscErrorCode KFSystemCreate(KFScene, KFSystem*)
    PetscErrorCode KFSystemDestroy(KFSystem*)
    PetscErrorCode KFSystemSetAngles(KFSystem, const PetscReal*)
    PetscErrorCode KFSystemGetMatrices(KFSystem, PetscMat*, PetscMat*, PetscMat*, PetscMat*)
    PetscErrorCode KFSystemGetBodyMap(KFSystem, PetscInt, PetscMat*)
    PetscErrorCode KFSystemComputeRigidModes(KFSystem)
    PetscErrorCode KFSystemSetRigidModes(KFSystem, PetscMat)
    PetscErrorCode KFSystemGetRigidModes(KFSystem, PetscMat*, PetscReal*)
    PetscErrorCode KFSystemRigidIO(KFSystem, PetscInt*, PetscReal*, PetscReal*)
    PetscErrorCode KFSystemEigen(KFSystem, PetscInt, PetscInt*, PetscReal*, PetscReal*, PetscReal*)
    PetscErrorCode KFSystemEigenModes(KFSystem, PetscInt, PetscInt*, PetscReal*, PetscMat*)
    PetscErrorCode KFSystemProject(KFSystem, BV, PetscReal*, PetscReal*, PetscReal*, PetscReal*)
    PetscErrorCode KFBVCombine(BV, PetscInt, const PetscReal*, PetscMat*)
    PetscErrorCode KFMatCombine(PetscMat, PetscInt, const PetscReal*, PetscMat*)
    PetscErrorCode KFMatInner(PetscMat, PetscMat, PetscReal*)
    PetscErrorCode KFFlexSolverCreate(KFSystem, KFFlexSolver*)
    PetscErrorCode KFFlexSolverSetShift(KFFlexSolver, PetscReal)
    PetscErrorCode KFFlexSolverSetUp(KFFlexSolver)
    PetscErrorCode KFFlexSolverApply(KFFlexSolver, PetscMat, PetscMat)
    PetscErrorCode KFFlexSolverDestroy(KFFlexSolver*)
    PetscErrorCode KFFlexSolverGetStats(KFFlexSolver, PetscInt*, PetscInt*, PetscInt*)
    PetscErrorCode KFFlexSolverMoments(KFFlexSolver, PetscInt, PetscReal*)
    PetscErrorCode KFKrylovBasis(KFFlexSolver, PetscInt, PetscInt, PetscReal, BV*, PetscInt*)
    PetscErrorCode KFKrylovRawBasis(KFFlexSolver, PetscInt, PetscInt, PetscMat*, PetscReal*)
    PetscErrorCode KFBodyBasisCreate(KFScene, KFBodyBasis*)
    PetscErrorCode KFBodyBasisAdd(KFBodyBasis, KFSystem, PetscMat)
    PetscErrorCode KFBodyBasisFinish(KFBodyBasis, PetscReal)
    PetscErrorCode KFBodyBasisDestroy(KFBodyBasis*)
    PetscErrorCode KFBodyBasisGetReduced(KFBodyBasis, PetscInt, PetscInt*, const PetscReal**, const PetscReal**, const PetscReal**, const PetscReal**, PetscInt*, const PetscReal**, const PetscReal**, PetscInt*)
    PetscErrorCode KFBodyBasisGetMap(KFBodyBasis, PetscInt, PetscMat*)
    PetscErrorCode KFDenseEig(PetscInt, const PetscReal*, const PetscReal*, PetscReal*, PetscReal*)
    PetscErrorCode KFDenseModeImportance(PetscInt, const PetscReal*, const PetscReal*, PetscInt, const PetscReal*, PetscInt, const PetscReal*, PetscReal, KFImportance, PetscReal, PetscReal*)
    PetscErrorCode KFDenseStaticCorrection(PetscInt, PetscInt, const PetscReal*, const PetscReal*, PetscInt, const PetscReal*, PetscReal*)
    PetscErrorCode KFDenseNullSpace(PetscInt, PetscInt, const PetscReal*, PetscReal, PetscInt*, PetscReal*, PetscInt*, PetscReal*)
    PetscErrorCode KFDenseMoments(PetscInt, const PetscReal*, const PetscReal*, PetscInt, const PetscReal*, PetscInt, const PetscReal*, PetscReal, PetscInt, PetscReal*)
    PetscErrorCode KFDenseMomentsRigid(PetscInt, const PetscReal*, const PetscReal*, PetscInt, const PetscReal*, PetscInt, const PetscReal*, PetscInt, const PetscReal*, PetscInt, PetscReal*)
    PetscErrorCode KFModalFRF(PetscInt, const PetscReal*, PetscInt, const PetscReal*, PetscInt, const PetscReal*, PetscReal, PetscReal, PetscInt, const PetscReal*, PetscReal*, PetscReal*)
    PetscErrorCode KFReassemble(PetscInt, const KFReducedBody*, PetscInt, const KFJointDef*, const PetscReal*, PetscInt, PetscInt, PetscReal, PetscInt*, PetscReal*, PetscReal*, PetscReal*, PetscReal*, PetscInt*, PetscReal*, PetscInt*, PetscReal*)
    PetscErrorCode KFJointRotation(const PetscReal*, const PetscReal*, PetscReal, PetscReal*)


class Error(RuntimeError):
    """A kryflex or PETSc error, with the message of the call that failed."""


cdef int check(PetscErrorCode ierr) except -1:
    if ierr != 0:
        msg = KFLastError().decode(errors="replace") or "PETSc error %d" % ierr
        KFClearError()
        raise Error(msg)
    return 0


check(KFPushErrorRecorder())
check(KFInitialize())


cdef Mat wrap_mat(PetscMat m, bint borrowed):
    """A petsc4py Mat around a C Mat; a borrowed one gets its own reference."""
    cdef Mat out = Mat()
    if borrowed:
        check(PetscObjectReference(<void*>m))
    out.mat = m
    return out


cdef cnp.ndarray fortran(a, int ndim, name):
    """A column-major float64 copy with the expected number of dimensions."""
    arr = np.asarray(a, dtype=np.float64)
    if arr.ndim != ndim:
        raise ValueError("%s must have %d dimension(s), got shape %s" % (name, ndim, arr.shape))
    if not np.all(np.isfinite(arr)):
        raise ValueError("%s holds non-finite values" % name)
    return np.asfortranarray(arr)


cdef Comm as_comm(comm):
    if comm is None:
        return PETSc.COMM_WORLD
    if isinstance(comm, Comm):
        return comm
    return PETSc.Comm(comm)


def progress(msg, comm=None):
    """A progress line on rank 0 with the elapsed time, on the C library's clock (-kryflex_quiet silences it)."""
    cdef Comm c = as_comm(comm)
    cdef bytes text = str(msg).encode()
    cdef const char *ctext = text
    check(KFProgress(c.comm, "%s", ctext))


def load_matrix(path, comm=None):
    """Loads a body matrix (PETSc binary or Matrix Market) in parallel."""
    cdef PetscMat m = NULL
    cdef Comm c = as_comm(comm)
    check(KFMatLoadFile(c.comm, str(path).encode(), &m))
    return wrap_mat(m, False)


cdef class CScene:
    """Bodies, joints, inputs and outputs (the C KFScene)."""
    cdef KFScene s
    cdef object _refs

    def __cinit__(self, comm=None):
        cdef Comm c = as_comm(comm)
        self._refs = []
        check(KFSceneCreate(c.comm, &self.s))

    def __dealloc__(self):
        if self.s != NULL:
            KFSceneDestroy(&self.s)

    def add_body(self, name, Mat M not None, Mat K not None, ids, xyz, ndof):
        cdef cnp.ndarray[int, ndim=1] cids = np.ascontiguousarray(ids, dtype=np.intc)
        cdef cnp.ndarray[int, ndim=1] cndof = np.ascontiguousarray(ndof, dtype=np.intc)
        cdef cnp.ndarray[double, ndim=2] cxyz = np.ascontiguousarray(xyz, dtype=np.float64).reshape(-1, 3)
        cdef PetscInt b = -1
        if not (cids.shape[0] == cndof.shape[0] == cxyz.shape[0]):
            raise ValueError("body %r: ids, coordinates and dof counts must have one entry per node (%d, %d, %d)"
                             % (name, cids.shape[0], cxyz.shape[0], cndof.shape[0]))
        if cids.shape[0] == 0:
            raise ValueError("body %r has no nodes" % name)
        check(KFSceneAddBody(self.s, str(name).encode(), M.mat, K.mat, <PetscInt>cids.shape[0],
                             <PetscInt*>cids.data, <PetscReal*>cxyz.data, <PetscInt*>cndof.data, &b))
        return b

    def add_interface(self, int body, name, int node_id):
        check(KFSceneAddInterface(self.s, body, str(name).encode(), node_id))

    def add_joint(self, name, kind, int parent, parent_interface, int child, child_interface, axis=(0, 0, 1), R0=None):
        cdef cnp.ndarray[double, ndim=1] cax = np.ascontiguousarray(axis, dtype=np.float64).ravel()
        cdef cnp.ndarray[double, ndim=1] cR0
        cdef KFJointType t
        if kind == "revolute":
            t = KF_JOINT_REVOLUTE
        elif kind == "fixed":
            t = KF_JOINT_FIXED
        else:
            raise ValueError("joint %r: type %r is not 'revolute' or 'fixed'" % (name, kind))
        if cax.shape[0] != 3:
            raise ValueError("joint %r: axis needs 3 components, got %d" % (name, cax.shape[0]))
        if R0 is None:
            check(KFSceneAddJoint(self.s, str(name).encode(), t, parent, str(parent_interface).encode(), child,
                                  str(child_interface).encode(), <PetscReal*>cax.data, NULL))
        else:
            R = np.asarray(R0, dtype=np.float64)
            if R.shape != (3, 3):
                raise ValueError("joint %r: orientation must be a 3x3 matrix" % name)
            cR0 = np.ascontiguousarray(R.T.ravel())  # column-major
            check(KFSceneAddJoint(self.s, str(name).encode(), t, parent, str(parent_interface).encode(), child,
                                  str(child_interface).encode(), <PetscReal*>cax.data, <PetscReal*>cR0.data))

    def set_num_io(self, int ninputs, int noutputs):
        check(KFSceneSetNumIO(self.s, ninputs, noutputs))

    def add_input_load(self, int io, int body, int node_id, int comp, double w=1.0):
        check(KFSceneAddInputLoad(self.s, io, body, node_id, comp, w))

    def add_output_reading(self, int io, int body, int node_id, int comp, double w=1.0):
        check(KFSceneAddOutputReading(self.s, io, body, node_id, comp, w))

    def add_input_vector(self, int io, int body, Vec g not None):
        check(KFSceneAddInputVector(self.s, io, body, g.vec))

    def add_output_vector(self, int io, int body, Vec h not None):
        check(KFSceneAddOutputVector(self.s, io, body, h.vec))

    def setup(self):
        check(KFSceneSetUp(self.s))

    def info(self):
        cdef PetscInt nb, nj, nr, ns, ni, no
        check(KFSceneGetInfo(self.s, &nb, &nj, &nr, &ns, &ni, &no))
        return dict(bodies=nb, joints=nj, revolute=nr, system_dofs=ns, inputs=ni, outputs=no)

    def body_info(self, int b):
        cdef const char *name
        cdef PetscInt n, nn
        check(KFSceneGetBodyInfo(self.s, b, &name, &n, &nn))
        return dict(name=name.decode(), dofs=n, nodes=nn)

    def body_matrices(self, int b):
        cdef PetscMat M, K, G, Ht
        check(KFSceneGetBodyMatrices(self.s, b, &M, &K, &G, &Ht))
        return wrap_mat(M, True), wrap_mat(K, True), wrap_mat(G, True), wrap_mat(Ht, True)


# the owner (scene or system) must outlive this object's C data: never let the cyclic GC clear it first
@cython.no_gc_clear
cdef class CSystem:
    """The full-order system at one configuration (the C KFSystem)."""
    cdef KFSystem y
    cdef CScene scene

    def __cinit__(self, CScene scene not None):
        self.scene = scene
        check(KFSystemCreate(scene.s, &self.y))

    def __dealloc__(self):
        if self.y != NULL:
            KFSystemDestroy(&self.y)

    def set_angles(self, angles_rad):
        cdef cnp.ndarray[double, ndim=1] a = np.ascontiguousarray(np.atleast_1d(angles_rad), dtype=np.float64)
        nr = self.scene.info()["revolute"]
        if a.shape[0] != nr:
            raise ValueError("the scene has %d revolute joint(s): give %d angle(s), got %d" % (nr, nr, a.shape[0]))
        if nr == 0:
            a = np.zeros(1)
        check(KFSystemSetAngles(self.y, <PetscReal*>a.data))

    def matrices(self):
        cdef PetscMat Ms, Ks, G, Ht
        check(KFSystemGetMatrices(self.y, &Ms, &Ks, &G, &Ht))
        return wrap_mat(Ms, True), wrap_mat(Ks, True), wrap_mat(G, True), wrap_mat(Ht, True)

    def body_map(self, int b):
        cdef PetscMat P
        check(KFSystemGetBodyMap(self.y, b, &P))
        return wrap_mat(P, True)

    def rigid_modes(self):
        cdef PetscMat Phi
        cdef PetscReal res
        check(KFSystemGetRigidModes(self.y, &Phi, &res))
        return wrap_mat(Phi, True), res

    def set_rigid_modes(self, Mat Phi not None):
        check(KFSystemSetRigidModes(self.y, Phi.mat))

    def rigid_io(self):
        cdef PetscInt r
        info = self.scene.info()
        t, a = info["outputs"], info["inputs"]
        check(KFSystemRigidIO(self.y, &r, NULL, NULL))
        cdef cnp.ndarray[double, ndim=2] HPhi = np.zeros((t, r), order="F")
        cdef cnp.ndarray[double, ndim=2] PhiG = np.zeros((r, a), order="F")
        check(KFSystemRigidIO(self.y, &r, <PetscReal*>HPhi.data, <PetscReal*>PhiG.data))
        return HPhi, PhiG

    def eigen(self, int nev):
        """Lowest nev flexible modes: (omega^2, H Phi, Phi^T G)."""
        cdef PetscInt nconv = 0
        info = self.scene.info()
        t, a = info["outputs"], info["inputs"]
        if nev < 1:
            raise ValueError("nev must be >= 1")
        cdef cnp.ndarray[double, ndim=1] w2 = np.zeros(nev)
        cdef cnp.ndarray[double, ndim=2] HPhi = np.zeros((t, nev), order="F")
        cdef cnp.ndarray[double, ndim=2] PhiG = np.zeros((nev, a), order="F")
        check(KFSystemEigen(self.y, nev, &nconv, <PetscReal*>w2.data, <PetscReal*>HPhi.data, <PetscReal*>PhiG.data))
        return w2[:nconv].copy(), HPhi[:, :nconv].copy(), PhiG[:nconv, :].copy()


    def eigen_modes(self, int nev):
        """Lowest nev flexible modes: (omega^2, modes as a dense e x nconv petsc4py Mat)."""
        cdef PetscInt nconv = 0
        cdef PetscMat P
        if nev < 1:
            raise ValueError("nev must be >= 1")
        cdef cnp.ndarray[double, ndim=1] w2 = np.zeros(nev)
        check(KFSystemEigenModes(self.y, nev, &nconv, <PetscReal*>w2.data, &P))
        modes = wrap_mat(P, False)
        if nconv < nev:
            modes = combine(modes, np.eye(nev)[:, :nconv])
        return w2[:nconv].copy(), modes


# the owner (scene or system) must outlive this object's C data: never let the cyclic GC clear it first
@cython.no_gc_clear
cdef class KrylovBasis:
    """An M-orthonormal Krylov basis (a SLEPc BV) of one system."""
    cdef BV V
    cdef CSystem system

    def __dealloc__(self):
        if self.V != NULL:
            BVDestroy(&self.V)

    @property
    def size(self):
        cdef PetscInt l, k
        check(BVGetActiveColumns(self.V, &l, &k))
        return k - l

    def project(self):
        """The reduced system of eq. (10-11): Mr, Kr, Gr, Hr as NumPy arrays."""
        c = self.size
        info = self.system.scene.info()
        t, a = info["outputs"], info["inputs"]
        cdef cnp.ndarray[double, ndim=2] Mr = np.zeros((c, c), order="F")
        cdef cnp.ndarray[double, ndim=2] Kr = np.zeros((c, c), order="F")
        cdef cnp.ndarray[double, ndim=2] Gr = np.zeros((c, a), order="F")
        cdef cnp.ndarray[double, ndim=2] Hr = np.zeros((t, c), order="F")
        check(KFSystemProject(self.system.y, self.V, <PetscReal*>Mr.data, <PetscReal*>Kr.data, <PetscReal*>Gr.data, <PetscReal*>Hr.data))
        return Mr, Kr, Gr, Hr

    def combine(self, C):
        """V C as a petsc4py dense Mat (system vectors)."""
        cdef cnp.ndarray[double, ndim=2] cC = fortran(C, 2, "C")
        cdef PetscMat X
        if cC.shape[0] != self.size:
            raise ValueError("C must have %d rows (the basis size), got %d" % (self.size, cC.shape[0]))
        check(KFBVCombine(self.V, <PetscInt>cC.shape[1], <PetscReal*>cC.data, &X))
        return wrap_mat(X, False)


# the owner (scene or system) must outlive this object's C data: never let the cyclic GC clear it first
@cython.no_gc_clear
cdef class FlexSolver:
    """The flexible solve operator K+ of one system: one MUMPS factorization."""
    cdef KFFlexSolver f
    cdef CSystem system

    def __cinit__(self, CSystem system not None, shift=None):
        self.system = system
        check(KFFlexSolverCreate(system.y, &self.f))
        if shift is not None:
            check(KFFlexSolverSetShift(self.f, float(shift)))

    def __dealloc__(self):
        if self.f != NULL:
            KFFlexSolverDestroy(&self.f)

    def setup(self):
        check(KFFlexSolverSetUp(self.f))

    def stats(self):
        cdef PetscInt nh, nn, nneg
        check(KFFlexSolverGetStats(self.f, &nh, &nn, &nneg))
        return dict(held=nh, null_pivots=nn, negative_pivots=nneg)

    def apply(self, Mat B not None):
        """K+ B for a dense block B (system rows)."""
        X = B.duplicate()
        check(KFFlexSolverApply(self.f, B.mat, (<Mat>X).mat))
        return X

    def moments(self, int nmom):
        """L^k, k < nmom, as an array (nmom, t, a)."""
        info = self.system.scene.info()
        t, a = info["outputs"], info["inputs"]
        if nmom < 1:
            raise ValueError("nmom must be >= 1")
        cdef cnp.ndarray[double, ndim=1] L = np.zeros(nmom * t * a)
        check(KFFlexSolverMoments(self.f, nmom, <PetscReal*>L.data))
        return L.reshape(nmom, a, t).transpose(0, 2, 1).copy()

    def krylov_basis(self, int nin, int nout=1, double tol=1e-10):
        """Deflated block Krylov basis: (KrylovBasis, number of deflated columns)."""
        cdef KrylovBasis kb = KrylovBasis()
        cdef PetscInt ndefl = 0
        kb.system = self.system
        check(KFKrylovBasis(self.f, nin, nout, tol, &kb.V, &ndefl))
        return kb, ndefl

    def raw_basis(self, int nin, int nout=1):
        """The unorthogonalized recurrence of eq. (9): (Mat, condition number of its M-Gram matrix)."""
        cdef PetscMat P
        cdef PetscReal cond
        check(KFKrylovRawBasis(self.f, nin, nout, &P, &cond))
        return wrap_mat(P, False), cond


cdef object carray(const PetscReal *p, Py_ssize_t m, Py_ssize_t n):
    """A NumPy copy of a column-major C array."""
    out = np.empty((m, n), order="F")
    cdef double[::1, :] view = out
    cdef Py_ssize_t i, j
    for j in range(n):
        for i in range(m):
            view[i, j] = p[i + j * m]
    return out


# the owner (scene or system) must outlive this object's C data: never let the cyclic GC clear it first
@cython.no_gc_clear
cdef class BodyBasis:
    """Reduced bodies from system vectors of one or more configurations (eq. 18-19)."""
    cdef KFBodyBasis bb
    cdef CScene scene

    def __cinit__(self, CScene scene not None):
        self.scene = scene
        check(KFBodyBasisCreate(scene.s, &self.bb))

    def __dealloc__(self):
        if self.bb != NULL:
            KFBodyBasisDestroy(&self.bb)

    def add(self, CSystem system not None, Mat X not None):
        check(KFBodyBasisAdd(self.bb, system.y, X.mat))

    def finish(self, double tol=1e-10):
        check(KFBodyBasisFinish(self.bb, tol))

    def reduced(self, int b):
        """Reduced body b: dict with M, K (v x v), G (v x a), H (t x v), iface (6 n_if x v), deflated."""
        cdef PetscInt v, nif, ndefl
        cdef const PetscReal *M
        cdef const PetscReal *K
        cdef const PetscReal *G
        cdef const PetscReal *H
        cdef const PetscReal *I
        cdef const PetscReal *R
        info = self.scene.info()
        t, a = info["outputs"], info["inputs"]
        check(KFBodyBasisGetReduced(self.bb, b, &v, &M, &K, &G, &H, &nif, &I, &R, &ndefl))
        return dict(M=carray(M, v, v), K=carray(K, v, v), G=carray(G, v, a), H=carray(H, t, v),
                    iface=carray(I, 6 * nif, v), rigid=carray(R, v, 6), deflated=ndefl)

    def map(self, int b):
        cdef PetscMat Psi
        check(KFBodyBasisGetMap(self.bb, b, &Psi))
        return wrap_mat(Psi, True)


def combine(Mat X not None, C):
    """X C for a tall dense Mat X (N x p) and a small replicated C (p x m): a new tall dense Mat."""
    cdef cnp.ndarray[double, ndim=2] cC = fortran(C, 2, "C")
    cdef PetscMat Y
    if cC.shape[0] != X.getSize()[1]:
        raise ValueError("C must have %d rows (the columns of X), got %d" % (X.getSize()[1], cC.shape[0]))
    check(KFMatCombine(X.mat, <PetscInt>cC.shape[1], <PetscReal*>cC.data, &Y))
    return wrap_mat(Y, False)


def inner(Mat A not None, Mat B not None):
    """A^T B for tall dense Mats with the same rows, replicated on every rank as a NumPy array."""
    if A.getSize()[0] != B.getSize()[0] or A.getLocalSize()[0] != B.getLocalSize()[0]:
        raise ValueError("A and B must have the same rows and row layout")
    p, q = A.getSize()[1], B.getSize()[1]
    cdef cnp.ndarray[double, ndim=2] out = np.zeros((p, q), order="F")
    check(KFMatInner(A.mat, B.mat, <PetscReal*>out.data))
    return out


# ------------------------------------------------------------------ small dense algebra

def dense_eig(K, M):
    """K phi = lambda M phi: (lambda ascending, Phi M-orthonormal)."""
    cdef cnp.ndarray[double, ndim=2] cK = fortran(K, 2, "K")
    cdef cnp.ndarray[double, ndim=2] cM = fortran(M, 2, "M")
    n = cK.shape[0]
    if cK.shape[1] != n or cM.shape[0] != n or cM.shape[1] != n:
        raise ValueError("K and M must be square and of the same size")
    cdef cnp.ndarray[double, ndim=1] lam = np.zeros(n)
    cdef cnp.ndarray[double, ndim=2] Phi = np.zeros((n, n), order="F")
    check(KFDenseEig(n, <PetscReal*>cK.data, <PetscReal*>cM.data, <PetscReal*>lam.data, <PetscReal*>Phi.data))
    return lam, Phi


IMPORTANCE = {"h2": KF_IMPORTANCE_H2, "hinf": KF_IMPORTANCE_HINF, "static": KF_IMPORTANCE_STATIC}


def mode_importance(lam, Phi, G, H, double zeta, measure="h2", double rigid_tol=1e-8):
    cdef cnp.ndarray[double, ndim=1] cl = fortran(lam, 1, "lambda")
    cdef cnp.ndarray[double, ndim=2] cP = fortran(Phi, 2, "Phi")
    cdef cnp.ndarray[double, ndim=2] cG = fortran(G, 2, "G")
    cdef cnp.ndarray[double, ndim=2] cH = fortran(H, 2, "H")
    n = cl.shape[0]
    if measure not in IMPORTANCE:
        raise ValueError("importance measure %r is not one of %s" % (measure, ", ".join(IMPORTANCE)))
    if cP.shape[0] != n or cP.shape[1] != n or cG.shape[0] != n or cH.shape[1] != n:
        raise ValueError("inconsistent sizes: lambda %d, Phi %s, G %s, H %s" % (n, (cP.shape[0], cP.shape[1]), (cG.shape[0], cG.shape[1]), (cH.shape[0], cH.shape[1])))
    if zeta <= 0:
        raise ValueError("damping ratio must be > 0, got %g" % zeta)
    cdef cnp.ndarray[double, ndim=1] out = np.zeros(n)
    check(KFDenseModeImportance(n, <PetscReal*>cl.data, <PetscReal*>cP.data, <PetscInt>cG.shape[1], <PetscReal*>cG.data,
                                <PetscInt>cH.shape[0], <PetscReal*>cH.data, zeta, IMPORTANCE[measure], rigid_tol,
                                <PetscReal*>out.data))
    return out


def static_correction(Phid, lamd, G):
    cdef cnp.ndarray[double, ndim=2] cP = fortran(Phid, 2, "Phid")
    cdef cnp.ndarray[double, ndim=1] cl = fortran(lamd, 1, "lambdad")
    cdef cnp.ndarray[double, ndim=2] cG = fortran(G, 2, "G")
    n, d = cP.shape[0], cP.shape[1]
    if cl.shape[0] != d or cG.shape[0] != n:
        raise ValueError("inconsistent sizes for the static correction")
    cdef cnp.ndarray[double, ndim=2] S = np.zeros((n, cG.shape[1]), order="F")
    check(KFDenseStaticCorrection(n, d, <PetscReal*>cP.data, <PetscReal*>cl.data, <PetscInt>cG.shape[1], <PetscReal*>cG.data, <PetscReal*>S.data))
    return S


def null_space(D, double rtol=1e-10):
    """(N, rank, smallest kept / largest singular value)."""
    cdef cnp.ndarray[double, ndim=2] cD = fortran(D, 2, "D")
    m, n = cD.shape[0], cD.shape[1]
    cdef cnp.ndarray[double, ndim=2] N = np.zeros((n, n), order="F")
    cdef PetscInt h, rank
    cdef PetscReal ratio
    check(KFDenseNullSpace(m, n, <PetscReal*>cD.data, rtol, &h, <PetscReal*>N.data, &rank, &ratio))
    return N[:, :h].copy(), rank, ratio


def dense_moments(K, M, G, H, int nmom, double rigid_tol=1e-8):
    """Moments on the flexible subspace: array (nmom, t, a)."""
    cdef cnp.ndarray[double, ndim=2] cK = fortran(K, 2, "K")
    cdef cnp.ndarray[double, ndim=2] cM = fortran(M, 2, "M")
    cdef cnp.ndarray[double, ndim=2] cG = fortran(G, 2, "G")
    cdef cnp.ndarray[double, ndim=2] cH = fortran(H, 2, "H")
    n = cK.shape[0]
    if cM.shape[0] != n or cG.shape[0] != n or cH.shape[1] != n:
        raise ValueError("inconsistent sizes for the moments")
    t, a = cH.shape[0], cG.shape[1]
    cdef cnp.ndarray[double, ndim=1] L = np.zeros(nmom * t * a)
    check(KFDenseMoments(n, <PetscReal*>cK.data, <PetscReal*>cM.data, a, <PetscReal*>cG.data, t, <PetscReal*>cH.data,
                         rigid_tol, nmom, <PetscReal*>L.data))
    return L.reshape(nmom, a, t).transpose(0, 2, 1).copy()


def dense_moments_rigid(K, M, G, H, Phir, int nmom):
    """Moments with known rigid modes (n x r), by solves: array (nmom, t, a)."""
    cdef cnp.ndarray[double, ndim=2] cK = fortran(K, 2, "K")
    cdef cnp.ndarray[double, ndim=2] cM = fortran(M, 2, "M")
    cdef cnp.ndarray[double, ndim=2] cG = fortran(G, 2, "G")
    cdef cnp.ndarray[double, ndim=2] cH = fortran(H, 2, "H")
    cdef cnp.ndarray[double, ndim=2] cP = fortran(Phir, 2, "Phir")
    n = cK.shape[0]
    if cM.shape[0] != n or cG.shape[0] != n or cH.shape[1] != n or cP.shape[0] != n:
        raise ValueError("inconsistent sizes for the moments")
    t, a = cH.shape[0], cG.shape[1]
    cdef cnp.ndarray[double, ndim=1] L = np.zeros(nmom * t * a)
    check(KFDenseMomentsRigid(n, <PetscReal*>cK.data, <PetscReal*>cM.data, a, <PetscReal*>cG.data, t, <PetscReal*>cH.data,
                              <PetscInt>cP.shape[1], <PetscReal*>cP.data, nmom, <PetscReal*>L.data))
    return L.reshape(nmom, a, t).transpose(0, 2, 1).copy()


def modal_frf(lam, HPhi, PhiG, double zeta, omegas, double rigid_tol=1e-8):
    """T(w) = sum_i H phi_i phi_i^T G / (lambda_i - w^2 + 2 i zeta sqrt(lambda_i) w): complex (nw, t, a)."""
    cdef cnp.ndarray[double, ndim=1] cl = fortran(lam, 1, "lambda")
    cdef cnp.ndarray[double, ndim=2] cH = fortran(HPhi, 2, "HPhi")
    cdef cnp.ndarray[double, ndim=2] cG = fortran(PhiG, 2, "PhiG")
    cdef cnp.ndarray[double, ndim=1] cw = fortran(omegas, 1, "omegas")
    n = cl.shape[0]
    if cH.shape[1] != n or cG.shape[0] != n:
        raise ValueError("inconsistent sizes for the frequency response")
    t, a, nw = cH.shape[0], cG.shape[1], cw.shape[0]
    cdef cnp.ndarray[double, ndim=1] re = np.zeros(nw * t * a)
    cdef cnp.ndarray[double, ndim=1] im = np.zeros(nw * t * a)
    check(KFModalFRF(n, <PetscReal*>cl.data, t, <PetscReal*>cH.data, a, <PetscReal*>cG.data, zeta, rigid_tol, nw,
                     <PetscReal*>cw.data, <PetscReal*>re.data, <PetscReal*>im.data))
    T = (re + 1j * im).reshape(nw, a, t).transpose(0, 2, 1)
    return T.copy()


def joint_rotation(axis, double alpha, R0=None):
    cdef cnp.ndarray[double, ndim=1] cax = np.ascontiguousarray(axis, dtype=np.float64).ravel()
    cdef cnp.ndarray[double, ndim=1] cR0
    cdef cnp.ndarray[double, ndim=1] R = np.zeros(9)
    if cax.shape[0] != 3:
        raise ValueError("axis needs 3 components")
    if R0 is None:
        check(KFJointRotation(<PetscReal*>cax.data, NULL, alpha, <PetscReal*>R.data))
    else:
        cR0 = np.ascontiguousarray(np.asarray(R0, dtype=np.float64).T.ravel())
        check(KFJointRotation(<PetscReal*>cax.data, <PetscReal*>cR0.data, alpha, <PetscReal*>R.data))
    return R.reshape(3, 3).T.copy()


def reassemble(bodies, joints, angles_rad, int ninputs, int noutputs, double rtol=1e-10):
    """Reassembly at one configuration (eq. 20-24) from reduced bodies alone.

    bodies: list of dicts with M, K, G, H, iface; joints: list of dicts with type, parent, parent_interface
    (index), child, child_interface (index), axis, R0 (3x3 or None). Returns (Mh, Kh, Gh, Hh, rank, sigma_ratio)."""
    nb, nj = len(bodies), len(joints)
    if nb == 0:
        raise ValueError("no reduced bodies")
    cdef KFReducedBody *cb = <KFReducedBody*>PyMem_Malloc(sizeof(KFReducedBody) * nb)
    cdef KFJointDef *cj = <KFJointDef*>PyMem_Malloc(sizeof(KFJointDef) * max(nj, 1))
    keep = []
    cdef cnp.ndarray[double, ndim=2] tmp
    cdef cnp.ndarray[double, ndim=1] ang = np.ascontiguousarray(np.atleast_1d(angles_rad) if len(np.atleast_1d(angles_rad)) else np.zeros(1), dtype=np.float64)
    try:
        n = 0
        for i, b in enumerate(bodies):
            arrays = [fortran(b[k], 2, "body %d %s" % (i, k)) for k in ("M", "K", "G", "H", "iface")]
            has_rigid = b.get("rigid") is not None
            if has_rigid:
                arrays.append(fortran(b["rigid"], 2, "body %d rigid" % i))
            v = arrays[0].shape[0]
            shapes = [tuple(x.shape[:2]) for x in arrays]
            if shapes[0] != (v, v) or shapes[1] != (v, v) or shapes[2] != (v, ninputs) \
                    or shapes[3] != (noutputs, v) or shapes[4][1] != v or shapes[4][0] % 6:
                raise ValueError("reduced body %d has inconsistent array sizes" % i)
            keep.append(arrays)
            cb[i].v = v
            tmp = arrays[0]; cb[i].M = <PetscReal*>tmp.data
            tmp = arrays[1]; cb[i].K = <PetscReal*>tmp.data
            tmp = arrays[2]; cb[i].G = <PetscReal*>tmp.data
            tmp = arrays[3]; cb[i].H = <PetscReal*>tmp.data
            tmp = arrays[4]; cb[i].iface = <PetscReal*>tmp.data
            cb[i].rigid = NULL
            if has_rigid:
                if tuple(arrays[5].shape[:2]) != (v, 6):
                    raise ValueError("reduced body %d: rigid must be %d x 6" % (i, v))
                tmp = arrays[5]; cb[i].rigid = <PetscReal*>tmp.data
            cb[i].ninterfaces = arrays[4].shape[0] // 6
            n += v
        nrev = 0
        children = set()
        if nj != nb - 1:
            raise ValueError("%d bodies need %d joints to form a tree, got %d" % (nb, nb - 1, nj))
        for j, J in enumerate(joints):
            kind = J["type"]
            if kind not in ("revolute", "fixed"):
                raise ValueError("joint %d: type %r is not 'revolute' or 'fixed'" % (j, kind))
            cj[j].type = KF_JOINT_REVOLUTE if kind == "revolute" else KF_JOINT_FIXED
            nrev += kind == "revolute"
            for key in ("parent", "child"):
                if not 0 <= J[key] < nb:
                    raise ValueError("joint %d: %s body %r does not exist" % (j, key, J[key]))
            cj[j].parent, cj[j].child = J["parent"], J["child"]
            cj[j].parent_interface, cj[j].child_interface = J["parent_interface"], J["child_interface"]
            if not 0 <= J["parent_interface"] < cb[J["parent"]].ninterfaces or not 0 <= J["child_interface"] < cb[J["child"]].ninterfaces:
                raise ValueError("joint %d: interface index out of range" % j)
            ax = np.asarray(J.get("axis", (0, 0, 1)), dtype=np.float64).ravel()
            R0 = np.eye(3) if J.get("R0") is None else np.asarray(J["R0"], dtype=np.float64)
            if ax.shape != (3,) or not np.all(np.isfinite(ax)):
                raise ValueError("joint %d: axis must be 3 finite numbers, got %r" % (j, J.get("axis")))
            if R0.shape != (3, 3) or not np.all(np.isfinite(R0)):
                raise ValueError("joint %d: R0 must be a finite 3x3 matrix" % j)
            if J["child"] in children:
                raise ValueError("joint %d: body %d is already the child of another joint: the joints must form a tree" % (j, J["child"]))
            children.add(J["child"])
            for k in range(3):
                cj[j].axis[k] = ax[k]
            for r in range(3):
                for c in range(3):
                    cj[j].R0[r + 3 * c] = R0[r, c]
        if not np.all(np.isfinite(np.atleast_1d(angles_rad))):
            raise ValueError("angles must be finite numbers, got %r" % (angles_rad,))
        if len(np.atleast_1d(angles_rad)) != nrev:
            raise ValueError("%d revolute joint(s) need %d angle(s), got %d" % (nrev, nrev, len(np.atleast_1d(angles_rad))))
        Mh = np.zeros(n * n); Kh = np.zeros(n * n); Gh = np.zeros(n * ninputs); Hh = np.zeros(noutputs * n)
        Pr = np.zeros(n * n)
        out = self_reassemble(nb, cb, nj, cj, ang, ninputs, noutputs, rtol, Mh, Kh, Gh, Hh, Pr)
    finally:
        PyMem_Free(cb)
        PyMem_Free(cj)
    return out


cdef object self_reassemble(int nb, KFReducedBody *cb, int nj, KFJointDef *cj, cnp.ndarray ang, int a, int t, double rtol,
                            cnp.ndarray Mh, cnp.ndarray Kh, cnp.ndarray Gh, cnp.ndarray Hh, cnp.ndarray Pr):
    cdef PetscInt h, rank, nrigid
    cdef PetscReal ratio
    check(KFReassemble(nb, cb, nj, cj, <PetscReal*>ang.data, a, t, rtol, &h, <PetscReal*>Mh.data, <PetscReal*>Kh.data,
                       <PetscReal*>Gh.data, <PetscReal*>Hh.data, &rank, &ratio, &nrigid, <PetscReal*>Pr.data))
    M = Mh[:h * h].reshape(h, h, order="F").copy()
    K = Kh[:h * h].reshape(h, h, order="F").copy()
    G = Gh[:h * a].reshape(h, a, order="F").copy()
    H = Hh[:t * h].reshape(t, h, order="F").copy()
    P = Pr[:h * nrigid].reshape(h, nrigid, order="F").copy() if nrigid >= 0 else None
    return M, K, G, H, rank, ratio, P
