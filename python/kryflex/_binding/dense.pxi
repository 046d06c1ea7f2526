# The small dense algebra of src/dense, on NumPy arrays: the kernels the tests cross-check against NumPy.

def dense_eig(K, M):
    """K phi = lambda M phi: (lambda ascending, Phi M-orthonormal)."""
    cdef cnp.ndarray cK = fortran(K, 2, "K")
    cdef cnp.ndarray cM = fortran(M, 2, "M")
    n = cK.shape[0]
    if cK.shape[1] != n or cM.shape[0] != n or cM.shape[1] != n:
        raise ValueError("K and M must be square and of the same size")
    cdef cnp.ndarray lam = np.zeros(n)
    cdef cnp.ndarray Phi = np.zeros((n, n), order="F")
    check(KFDenseEig(n, real_ptr(cK), real_ptr(cM), real_ptr(lam), real_ptr(Phi)))
    return lam, Phi


IMPORTANCE = {"h2": KF_IMPORTANCE_H2, "hinf": KF_IMPORTANCE_HINF, "static": KF_IMPORTANCE_STATIC,
              "band": KF_IMPORTANCE_BAND}
ACCURACY_MEASURES = {"elastic": KF_ACCURACY_ELASTIC, "total": KF_ACCURACY_TOTAL}


def mode_importance(lam, Phi, G, H, PetscReal zeta, measure="h2", PetscReal rigid_tol=1e-8):
    cdef cnp.ndarray cl = fortran(lam, 1, "lambda")
    cdef cnp.ndarray cP = fortran(Phi, 2, "Phi")
    cdef cnp.ndarray cG = fortran(G, 2, "G")
    cdef cnp.ndarray cH = fortran(H, 2, "H")
    n = cl.shape[0]
    if measure not in IMPORTANCE:
        raise ValueError("importance measure %r is not one of %s" % (measure, ", ".join(IMPORTANCE)))
    if measure == "band":
        raise ValueError("the band measure needs the band and a cluster tolerance: use mode_importance_band")
    if cP.shape[0] != n or cP.shape[1] != n or cG.shape[0] != n or cH.shape[1] != n:
        raise ValueError("inconsistent sizes: lambda %d, Phi %s, G %s, H %s" % (n, (cP.shape[0], cP.shape[1]), (cG.shape[0], cG.shape[1]), (cH.shape[0], cH.shape[1])))
    if zeta <= 0:
        raise ValueError("damping ratio must be > 0, got %g" % zeta)
    cdef cnp.ndarray out = np.zeros(n)
    check(KFDenseModeImportance(n, real_ptr(cl), real_ptr(cP), <PetscInt>cG.shape[1], real_ptr(cG),
                                <PetscInt>cH.shape[0], real_ptr(cH), zeta, IMPORTANCE[measure], rigid_tol,
                                real_ptr(out)))
    return out


def mode_importance_band(lam, Phi, G, H, PetscReal zeta, band_hz, PetscReal cluster_rtol=1e-3, PetscReal rigid_tol=1e-8):
    """Band-aware, cluster-invariant importance (KFDenseModeImportanceBand): (importance normalized to the largest,
    cluster id per mode: 0, 1, ... in ascending frequency, -1 for rigid modes). band_hz: (fmin, fmax) in Hz."""
    cdef cnp.ndarray cl = fortran(lam, 1, "lambda")
    cdef cnp.ndarray cP = fortran(Phi, 2, "Phi")
    cdef cnp.ndarray cG = fortran(G, 2, "G")
    cdef cnp.ndarray cH = fortran(H, 2, "H")
    cdef cnp.ndarray cb = fortran(band_hz, 1, "band_hz")
    n = cl.shape[0]
    if cP.shape[0] != n or cP.shape[1] != n or cG.shape[0] != n or cH.shape[1] != n:
        raise ValueError("inconsistent sizes: lambda %d, Phi %s, G %s, H %s" % (n, (cP.shape[0], cP.shape[1]), (cG.shape[0], cG.shape[1]), (cH.shape[0], cH.shape[1])))
    if cb.shape[0] != 2 or not 0 <= cb[0] <= cb[1]:
        raise ValueError("band_hz must be (fmin, fmax) with 0 <= fmin <= fmax, got %r" % (band_hz,))
    if not zeta >= 0:
        raise ValueError("damping ratio must be >= 0, got %g" % zeta)
    if not 0 <= cluster_rtol < 1:
        raise ValueError("cluster_rtol must be in [0, 1), got %g" % cluster_rtol)
    if not rigid_tol >= 0:
        raise ValueError("rigid_tol must be >= 0, got %g" % rigid_tol)
    cdef cnp.ndarray out = np.zeros(n)
    cdef cnp.ndarray ids = np.zeros(n, dtype=INT_DTYPE)
    check(KFDenseModeImportanceBand(n, real_ptr(cl), real_ptr(cP), <PetscInt>cG.shape[1], real_ptr(cG),
                                    <PetscInt>cH.shape[0], real_ptr(cH), zeta, real_ptr(cb), cluster_rtol, rigid_tol,
                                    real_ptr(out), int_ptr(ids)))
    return out, ids


def modal_hankel_singular_values(w2, HPhi, PhiG, PetscReal zeta):
    """Hankel singular values of the damped modal system (KFModalHankelSingularValues): 2n values, descending."""
    cdef cnp.ndarray cw = fortran(w2, 1, "w2")
    cdef cnp.ndarray cH = fortran(HPhi, 2, "HPhi")
    cdef cnp.ndarray cG = fortran(PhiG, 2, "PhiG")
    n = cw.shape[0]
    if cH.shape[1] != n or cG.shape[0] != n:
        raise ValueError("inconsistent sizes: w2 %d, HPhi %s, PhiG %s" % (n, (cH.shape[0], cH.shape[1]), (cG.shape[0], cG.shape[1])))
    if not zeta > 0:
        raise ValueError("damping ratio must be > 0 for finite Gramians, got %g" % zeta)
    if n and not np.all(cw > 0):
        raise ValueError("w2 must hold flexible modes only (all > 0), got min %g" % cw.min())
    cdef cnp.ndarray hsv = np.zeros(2 * n)
    check(KFModalHankelSingularValues(n, real_ptr(cw), <PetscInt>cH.shape[0], real_ptr(cH), <PetscInt>cG.shape[1],
                                      real_ptr(cG), zeta, real_ptr(hsv)))
    return hsv


def static_correction(Phid, lamd, G):
    cdef cnp.ndarray cP = fortran(Phid, 2, "Phid")
    cdef cnp.ndarray cl = fortran(lamd, 1, "lambdad")
    cdef cnp.ndarray cG = fortran(G, 2, "G")
    n, d = cP.shape[0], cP.shape[1]
    if cl.shape[0] != d or cG.shape[0] != n:
        raise ValueError("inconsistent sizes for the static correction")
    cdef cnp.ndarray S = np.zeros((n, cG.shape[1]), order="F")
    check(KFDenseStaticCorrection(n, d, real_ptr(cP), real_ptr(cl), <PetscInt>cG.shape[1], real_ptr(cG), real_ptr(S)))
    return S


def null_space(D, PetscReal rtol=1e-10):
    """(N, rank, smallest kept / largest singular value)."""
    cdef cnp.ndarray cD = fortran(D, 2, "D")
    m, n = cD.shape[0], cD.shape[1]
    cdef cnp.ndarray N = np.zeros((n, n), order="F")
    cdef PetscInt h, rank
    cdef PetscReal ratio
    check(KFDenseNullSpace(m, n, real_ptr(cD), rtol, &h, real_ptr(N), &rank, &ratio))
    return N[:, :h].copy(), rank, ratio


def dense_moments(K, M, G, H, PetscInt nmom, PetscReal rigid_tol=1e-8):
    """Moments on the flexible subspace: array (nmom, t, a)."""
    cdef cnp.ndarray cK = fortran(K, 2, "K")
    cdef cnp.ndarray cM = fortran(M, 2, "M")
    cdef cnp.ndarray cG = fortran(G, 2, "G")
    cdef cnp.ndarray cH = fortran(H, 2, "H")
    n = cK.shape[0]
    if cM.shape[0] != n or cG.shape[0] != n or cH.shape[1] != n:
        raise ValueError("inconsistent sizes for the moments")
    t, a = cH.shape[0], cG.shape[1]
    cdef cnp.ndarray L = np.zeros(nmom * t * a)
    check(KFDenseMoments(n, real_ptr(cK), real_ptr(cM), a, real_ptr(cG), t, real_ptr(cH),
                         rigid_tol, nmom, real_ptr(L)))
    return L.reshape(nmom, a, t).transpose(0, 2, 1).copy()


def dense_moments_rigid(K, M, G, H, Phir, PetscInt nmom):
    """Moments with known rigid modes (n x r), by solves: array (nmom, t, a)."""
    cdef cnp.ndarray cK = fortran(K, 2, "K")
    cdef cnp.ndarray cM = fortran(M, 2, "M")
    cdef cnp.ndarray cG = fortran(G, 2, "G")
    cdef cnp.ndarray cH = fortran(H, 2, "H")
    cdef cnp.ndarray cP = fortran(Phir, 2, "Phir")
    n = cK.shape[0]
    if cM.shape[0] != n or cG.shape[0] != n or cH.shape[1] != n or cP.shape[0] != n:
        raise ValueError("inconsistent sizes for the moments")
    t, a = cH.shape[0], cG.shape[1]
    cdef cnp.ndarray L = np.zeros(nmom * t * a)
    check(KFDenseMomentsRigid(n, real_ptr(cK), real_ptr(cM), a, real_ptr(cG), t, real_ptr(cH),
                              <PetscInt>cP.shape[1], real_ptr(cP), nmom, real_ptr(L)))
    return L.reshape(nmom, a, t).transpose(0, 2, 1).copy()


def modal_frf(lam, HPhi, PhiG, PetscReal zeta, omegas, PetscReal rigid_tol=1e-8):
    """T(w) = sum_i H phi_i phi_i^T G / (lambda_i - w^2 + 2 i zeta sqrt(lambda_i) w): complex (nw, t, a)."""
    cdef cnp.ndarray cl = fortran(lam, 1, "lambda")
    cdef cnp.ndarray cH = fortran(HPhi, 2, "HPhi")
    cdef cnp.ndarray cG = fortran(PhiG, 2, "PhiG")
    cdef cnp.ndarray cw = fortran(omegas, 1, "omegas")
    n = cl.shape[0]
    if cH.shape[1] != n or cG.shape[0] != n:
        raise ValueError("inconsistent sizes for the frequency response")
    t, a, nw = cH.shape[0], cG.shape[1], cw.shape[0]
    cdef cnp.ndarray re = np.zeros(nw * t * a)
    cdef cnp.ndarray im = np.zeros(nw * t * a)
    check(KFModalFRF(n, real_ptr(cl), t, real_ptr(cH), a, real_ptr(cG), zeta, rigid_tol, nw,
                     real_ptr(cw), real_ptr(re), real_ptr(im)))
    T = (re + 1j * im).reshape(nw, a, t).transpose(0, 2, 1)
    return T.copy()


def joint_rotation(axis, PetscReal alpha, R0=None):
    """R(alpha) = Rot(axis, alpha) R0 as a 3x3 array."""
    cdef cnp.ndarray cax = axis_vector(axis, "joint rotation")
    cdef cnp.ndarray cR0 = None if R0 is None else column_major_3x3(R0, "R0")
    cdef cnp.ndarray R = np.zeros(9)
    check(KFJointRotation(real_ptr(cax), NULL if cR0 is None else real_ptr(cR0), alpha, real_ptr(R)))
    return R.reshape(3, 3).T.copy()


def reassemble(bodies, joints, angles_rad, PetscInt ninputs, PetscInt noutputs, PetscReal rtol=1e-10):
    """Reassembly at one configuration (eq. 20-24) from reduced bodies alone.

    bodies: list of dicts with M, K, G, H, iface; joints: list of dicts with type, parent, parent_interface
    (index), child, child_interface (index), axis, R0 (3x3 or None). Returns (Mh, Kh, Gh, Hh, rank, sigma_ratio)."""
    nb, nj = len(bodies), len(joints)
    if nb == 0:
        raise ValueError("no reduced bodies")
    cdef KFReducedBody *cb = <KFReducedBody*>PyMem_Malloc(sizeof(KFReducedBody) * nb)
    cdef KFJointDef *cj = <KFJointDef*>PyMem_Malloc(sizeof(KFJointDef) * max(nj, 1))
    keep = []
    cdef cnp.ndarray tmp
    cdef cnp.ndarray ang = np.ascontiguousarray(np.atleast_1d(angles_rad) if len(np.atleast_1d(angles_rad)) else np.zeros(1), dtype=np.float64)
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
            tmp = arrays[0]; cb[i].M = real_ptr(tmp)
            tmp = arrays[1]; cb[i].K = real_ptr(tmp)
            tmp = arrays[2]; cb[i].G = real_ptr(tmp)
            tmp = arrays[3]; cb[i].H = real_ptr(tmp)
            tmp = arrays[4]; cb[i].iface = real_ptr(tmp)
            cb[i].rigid = NULL
            if has_rigid:
                if tuple(arrays[5].shape[:2]) != (v, 6):
                    raise ValueError("reduced body %d: rigid must be %d x 6" % (i, v))
                tmp = arrays[5]; cb[i].rigid = real_ptr(tmp)
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


cdef object self_reassemble(PetscInt nb, KFReducedBody *cb, PetscInt nj, KFJointDef *cj, cnp.ndarray ang, PetscInt a,
                            PetscInt t, PetscReal rtol,
                            cnp.ndarray Mh, cnp.ndarray Kh, cnp.ndarray Gh, cnp.ndarray Hh, cnp.ndarray Pr):
    cdef PetscInt h, rank, nrigid
    cdef PetscReal ratio
    check(KFReassemble(nb, cb, nj, cj, real_ptr(ang), a, t, rtol, &h, real_ptr(Mh), real_ptr(Kh),
                       real_ptr(Gh), real_ptr(Hh), &rank, &ratio, &nrigid, real_ptr(Pr)))
    M = Mh[:h * h].reshape(h, h, order="F").copy()
    K = Kh[:h * h].reshape(h, h, order="F").copy()
    G = Gh[:h * a].reshape(h, a, order="F").copy()
    H = Hh[:t * h].reshape(t, h, order="F").copy()
    P = Pr[:h * nrigid].reshape(h, nrigid, order="F").copy() if nrigid >= 0 else None
    return M, K, G, H, rank, ratio, P
