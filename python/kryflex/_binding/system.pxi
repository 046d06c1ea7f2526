# The full-order stages on one configuration: CSystem (assembly, rigid modes, verification eigensolve), FlexSolver
# (K+, moments, Krylov bases), KrylovBasis (a slepc4py BV), BodyBasis (reduced bodies), tall dense products.
# Each object keeps the Python object it was built from, so its C data never outlives what it points into; the
# C destroy functions read nothing of their owners, so the cyclic GC may free them in any order.

cdef class CSystem:
    """The full-order system at one configuration (the C KFSystem)."""
    cdef KFSystem y
    cdef readonly CScene scene

    def __cinit__(self, CScene scene not None):
        self.scene = scene
        check(KFSystemCreate(scene.s, &self.y))

    def __dealloc__(self):
        if self.y != NULL:
            KFSystemDestroy(&self.y)

    def set_angles(self, angles_rad):
        cdef cnp.ndarray a = np.ascontiguousarray(np.atleast_1d(angles_rad), dtype=np.float64)
        nr = self.scene.info()["revolute"]
        if a.ndim != 1 or a.shape[0] != nr:
            raise ValueError("the scene has %d revolute joint(s): give %d angle(s), got %d" % (nr, nr, a.size))
        if not np.all(np.isfinite(a)):
            raise ValueError("angles must be finite numbers, got %r" % (angles_rad,))
        if nr == 0:
            a = np.zeros(1)
        check(KFSystemSetAngles(self.y, real_ptr(a)))

    def matrices(self):
        cdef PetscMat Ms, Ks, G, Ht
        check(KFSystemGetMatrices(self.y, &Ms, &Ks, &G, &Ht))
        return wrap_mat(Ms, True), wrap_mat(Ks, True), wrap_mat(G, True), wrap_mat(Ht, True)

    def body_map(self, PetscInt b):
        cdef PetscMat P
        check(KFSystemGetBodyMap(self.y, b, &P))
        return wrap_mat(P, True)

    def rigid_modes(self):
        cdef PetscMat Phi
        cdef PetscReal res
        check(KFSystemGetRigidModes(self.y, &Phi, &res))
        return wrap_mat(Phi, True), res

    def rigid_products(self):
        """(K_S Phi, M_S Phi) of the rigid modes, the products the C library forms for its rigid residual and its
        projections (None, None without rigid modes)."""
        cdef PetscMat KP = NULL, MP = NULL
        check(KFSystemGetRigidProducts(self.y, &KP, &MP))
        if KP == NULL or MP == NULL:
            return None, None
        return wrap_mat(KP, True), wrap_mat(MP, True)

    def factor_count(self):
        """Sparse factorizations made for the flexible solves on this system so far, all configurations (a
        body-wise solve factors each body once for all of them)."""
        cdef PetscInt n
        check(KFSystemGetFactorCount(self.y, &n))
        return int(n)

    def set_rigid_modes(self, Mat Phi not None):
        check(KFSystemSetRigidModes(self.y, Phi.mat))

    def rigid_io(self):
        """The rigid modes' participation: (H Phi_r (t x r), Phi_r^T G (r x a))."""
        cdef PetscInt r
        info = self.scene.info()
        t, a = info["outputs"], info["inputs"]
        check(KFSystemRigidIO(self.y, &r, NULL, NULL))
        cdef cnp.ndarray HPhi = np.zeros((t, r), order="F")
        cdef cnp.ndarray PhiG = np.zeros((r, a), order="F")
        check(KFSystemRigidIO(self.y, &r, real_ptr(HPhi), real_ptr(PhiG)))
        return HPhi, PhiG

    def eigen(self, PetscInt nev):
        """Lowest nev flexible modes: (omega^2, H Phi, Phi^T G)."""
        cdef PetscInt nconv = 0
        info = self.scene.info()
        t, a = info["outputs"], info["inputs"]
        if nev < 1:
            raise ValueError("nev must be >= 1")
        cdef cnp.ndarray w2 = np.zeros(nev)
        cdef cnp.ndarray HPhi = np.zeros((t, nev), order="F")
        cdef cnp.ndarray PhiG = np.zeros((nev, a), order="F")
        check(KFSystemEigen(self.y, nev, &nconv, real_ptr(w2), real_ptr(HPhi), real_ptr(PhiG)))
        return w2[:nconv].copy(), HPhi[:, :nconv].copy(), PhiG[:nconv, :].copy()

    def eigen_modes(self, PetscInt nev):
        """Lowest nev flexible modes: (omega^2, modes as a dense e x nconv petsc4py Mat). Fewer than nev (nconv, the
        length of omega^2) when the system has fewer flexible modes than nev, or fewer converged: what exists."""
        cdef PetscInt nconv = 0
        cdef PetscMat P
        if nev < 1:
            raise ValueError("nev must be >= 1")
        cdef cnp.ndarray w2 = np.zeros(nev)
        check(KFSystemEigenModes(self.y, nev, &nconv, real_ptr(w2), &P))
        modes = wrap_mat(P, False)
        # the C side sizes the modes for min(nev, the flexible modes' count), its first nconv columns filled
        p = modes.getSize()[1]
        if nconv < p:
            modes = combine(modes, np.eye(p)[:, :nconv])
        return w2[:nconv].copy(), modes

    def count_modes_below(self, freq_hz):
        """The flexible modes below freq_hz (Hz), counted from the inertia of one LDL^T factorization of
        K_S - (2 pi freq_hz)^2 M_S (Sylvester), without an eigensolve."""
        cdef PetscInt n = 0
        f = float(freq_hz)
        if not (np.isfinite(f) and f > 0):
            raise ValueError("freq_hz is a positive number of Hz, got %r" % (freq_hz,))
        check(KFSystemCountModesBelow(self.y, f, &n))
        return int(n)


cdef class KrylovBasis:
    """An M-orthonormal Krylov basis of one system: a slepc4py BV (.bv) and the system it spans."""
    cdef readonly BV bv
    cdef readonly CSystem system

    cdef SlepcBV handle(self) except NULL:
        if self.bv is None or self.bv.bv == NULL:
            raise ValueError("an empty KrylovBasis: get one from FlexSolver.krylov_basis")
        return self.bv.bv

    @property
    def size(self):
        cdef PetscInt l, k
        check(BVGetActiveColumns(self.handle(), &l, &k))
        return k - l

    def project(self):
        """The reduced system of eq. (10-11): Mr, Kr, Gr, Hr as NumPy arrays."""
        c = self.size
        info = self.system.scene.info()
        t, a = info["outputs"], info["inputs"]
        cdef cnp.ndarray Mr = np.zeros((c, c), order="F")
        cdef cnp.ndarray Kr = np.zeros((c, c), order="F")
        cdef cnp.ndarray Gr = np.zeros((c, a), order="F")
        cdef cnp.ndarray Hr = np.zeros((t, c), order="F")
        check(KFSystemProject(self.system.y, self.handle(), real_ptr(Mr), real_ptr(Kr), real_ptr(Gr), real_ptr(Hr)))
        return Mr, Kr, Gr, Hr

    def combine(self, C):
        """V C as a petsc4py dense Mat (system vectors)."""
        cdef cnp.ndarray cC = fortran(C, 2, "C")
        cdef PetscMat X
        if cC.shape[0] != self.size:
            raise ValueError("C must have %d rows (the basis size), got %d" % (self.size, cC.shape[0]))
        check(KFBVCombine(self.handle(), <PetscInt>cC.shape[1], real_ptr(cC), &X))
        return wrap_mat(X, False)


cdef class FlexSolver:
    """The flexible solve operator K+ of one system: one MUMPS factorization."""
    cdef KFFlexSolver f
    cdef readonly CSystem system

    def __cinit__(self, CSystem system not None, shift=None, type=None):
        cdef bytes tname
        self.system = system
        check(KFFlexSolverCreate(system.y, &self.f))
        if shift is not None:
            check(KFFlexSolverSetShift(self.f, float(shift)))
        if type is not None:
            types = ("auto", "monolithic", "bodywise")
            if type not in types:
                raise ValueError("type: give one of %s, got %r" % (", ".join(types), type))
            tname = cstr(type, "flexible solver type")
            check(KFFlexSolverSetType(self.f, tname))

    @property
    def type(self):
        """The implementation set up: "monolithic" or "bodywise" (-kf_flex_solver; sets the solver up)."""
        cdef KFFlexSolverType t
        check(KFFlexSolverSetUp(self.f))
        check(KFFlexSolverGetType(self.f, &t))
        return (<bytes>t).decode()

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

    def moments(self, PetscInt nmom):
        """L^k, k < nmom, as an array (nmom, t, a)."""
        info = self.system.scene.info()
        t, a = info["outputs"], info["inputs"]
        if nmom < 1:
            raise ValueError("nmom must be >= 1")
        cdef cnp.ndarray L = np.zeros(nmom * t * a)
        check(KFFlexSolverMoments(self.f, nmom, real_ptr(L)))
        return L.reshape(nmom, a, t).transpose(0, 2, 1).copy()

    def krylov_basis(self, PetscInt nin, PetscInt nout=1, PetscReal tol=1e-10):
        """Deflated block Krylov basis: (KrylovBasis, number of deflated columns)."""
        cdef KrylovBasis kb = KrylovBasis()
        cdef PetscInt ndefl = 0
        cdef SlepcBV V = NULL
        check(KFKrylovBasis(self.f, nin, nout, tol, &V, &ndefl))
        kb.bv = BV()
        kb.bv.bv = V
        kb.system = self.system
        return kb, ndefl

    def raw_basis(self, PetscInt nin, PetscInt nout=1):
        """The unorthogonalized recurrence of eq. (9): (Mat, condition number of its M-Gram matrix)."""
        cdef PetscMat P
        cdef PetscReal cond
        check(KFKrylovRawBasis(self.f, nin, nout, &P, &cond))
        return wrap_mat(P, False), cond


cdef class BodyBasis:
    """Reduced bodies from system vectors of one or more configurations (eq. 18-19)."""
    cdef KFBodyBasis bb
    cdef readonly CScene scene

    def __cinit__(self, CScene scene not None):
        self.scene = scene
        check(KFBodyBasisCreate(scene.s, &self.bb))

    def __dealloc__(self):
        if self.bb != NULL:
            KFBodyBasisDestroy(&self.bb)

    def add(self, CSystem system not None, Mat X not None):
        check(KFBodyBasisAdd(self.bb, system.y, X.mat))

    def finish(self, PetscReal tol=1e-10):
        check(KFBodyBasisFinish(self.bb, tol))

    def reduced(self, PetscInt b):
        """Reduced body b: dict with M, K (v x v), G (v x a), H (t x v), iface (6 n_if x v), rigid (v x 6), deflated."""
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

    def map(self, PetscInt b):
        cdef PetscMat Psi
        check(KFBodyBasisGetMap(self.bb, b, &Psi))
        return wrap_mat(Psi, True)


def combine(Mat X not None, C):
    """X C for a tall dense Mat X (N x p) and a small replicated C (p x m): a new tall dense Mat."""
    cdef cnp.ndarray cC = fortran(C, 2, "C")
    cdef PetscMat Y
    if cC.shape[0] != X.getSize()[1]:
        raise ValueError("C must have %d rows (the columns of X), got %d" % (X.getSize()[1], cC.shape[0]))
    check(KFMatCombine(X.mat, <PetscInt>cC.shape[1], real_ptr(cC), &Y))
    return wrap_mat(Y, False)


def inner(Mat A not None, Mat B not None):
    """A^T B for tall dense Mats with the same rows, replicated on every rank as a NumPy array."""
    if A.getSize()[0] != B.getSize()[0] or A.getLocalSize()[0] != B.getLocalSize()[0]:
        raise ValueError("A and B must have the same rows and row layout")
    p, q = A.getSize()[1], B.getSize()[1]
    cdef cnp.ndarray out = np.zeros((p, q), order="F")
    check(KFMatInner(A.mat, B.mat, real_ptr(out)))
    return out
