# CReducedModel (the C KFReducedModel, a reference-counted PETSc object), CReducedSystem (a KFReducedSystem: the
# model reassembled at one configuration, plain data with its modes) and CReassembly (a KFReassembly: the model's
# reassembly workspace, for reassembling at many angles). NumPy arrays returned here are copies or new arrays.

cdef class CReducedSystem:
    """The reduced system at one configuration: matrices, modes, frequencies, moments and frequency responses."""
    cdef KFReducedSystem y

    def __dealloc__(self):
        if self.y != NULL:
            KFReducedSystemDestroy(&self.y)

    cdef KFReducedSystem handle(self) except NULL:
        if self.y == NULL:
            raise ValueError("an empty CReducedSystem: get one from CReducedModel.reassemble")
        return self.y

    def matrices(self):
        """(M, K, G, H): n x n, n x n, n x a, t x n."""
        cdef PetscInt n, a, t
        cdef const PetscReal *M
        cdef const PetscReal *K
        cdef const PetscReal *G
        cdef const PetscReal *H
        check(KFReducedSystemGetMatrices(self.handle(), &n, &a, &t, &M, &K, &G, &H))
        return carray(M, n, n), carray(K, n, n), carray(G, n, a), carray(H, t, n)

    def modes(self):
        """(eigenvalues ascending, M-orthonormal modes n x n, rigid count, rigid modes n x r from the bodies' rigid
        motions or None)."""
        cdef PetscInt n, r
        cdef const PetscReal *lam
        cdef const PetscReal *Phi
        cdef const PetscReal *Phir
        check(KFReducedSystemGetMatrices(self.handle(), &n, NULL, NULL, NULL, NULL, NULL, NULL))
        check(KFReducedSystemGetModes(self.y, &lam, &Phi, &r, &Phir))
        return carray(lam, n, 1)[:, 0].copy(), carray(Phi, n, n), r, carray(Phir, n, r)

    def trim_info(self):
        """(modes taken out, limit in Hz (0: off), highest flexible frequency before trimming in Hz, feedthrough D
        t x a or None): KFReducedSystemTrim."""
        cdef PetscInt nt, a, t
        cdef PetscReal fmax, ftop
        cdef const PetscReal *D
        check(KFReducedSystemGetMatrices(self.handle(), NULL, &a, &t, NULL, NULL, NULL, NULL))
        check(KFReducedSystemGetTrim(self.y, &nt, &fmax, &ftop, &D))
        return int(nt), float(fmax), float(ftop), (carray(D, t, a) if D != NULL else None)

    def reassembly_info(self):
        """(rank of the interface constraints, sigma_min(kept) / sigma_max of their SVD)."""
        cdef PetscInt rank
        cdef PetscReal ratio
        check(KFReducedSystemGetReassemblyInfo(self.handle(), &rank, &ratio))
        return rank, ratio

    def frequencies_hz(self):
        cdef PetscInt nf
        cdef const PetscReal *f
        check(KFReducedSystemGetFrequencies(self.handle(), &nf, &f))
        return carray(f, nf, 1)[:, 0].copy()

    def moments(self, PetscInt nmom):
        """L^k, k < nmom, on the flexible subspace: (nmom, t, a)."""
        cdef PetscInt a, t
        if nmom < 1:
            raise ValueError("the number of moments must be >= 1, got %d" % nmom)
        check(KFReducedSystemGetMatrices(self.handle(), NULL, &a, &t, NULL, NULL, NULL, NULL))
        cdef cnp.ndarray L = np.zeros(nmom * t * a)
        check(KFReducedSystemMoments(self.y, nmom, real_ptr(L)))
        return L.reshape(nmom, a, t).transpose(0, 2, 1).copy()

    def frf(self, PetscReal zeta, omegas):
        """Frequency response with uniform modal damping zeta at omegas (rad/s): complex (nw, t, a)."""
        cdef PetscInt a, t
        cdef cnp.ndarray w = fortran(omegas, 1, "frequencies")
        if not 0 <= zeta < 1:
            raise ValueError("the modal damping ratio must lie in [0, 1), got %g" % zeta)
        check(KFReducedSystemGetMatrices(self.handle(), NULL, &a, &t, NULL, NULL, NULL, NULL))
        nw = w.shape[0]
        cdef cnp.ndarray re = np.zeros(nw * t * a)
        cdef cnp.ndarray im = np.zeros(nw * t * a)
        check(KFReducedSystemFRF(self.y, zeta, nw, real_ptr(w), real_ptr(re), real_ptr(im)))
        return (re + 1j * im).reshape(nw, a, t).transpose(0, 2, 1).copy()

    def response(self, omegas):
        """Frequency response with the model's damping (modal, Rayleigh, structural, the reassembled viscous matrix)
        and output quantities at omegas (rad/s): complex (nw, t, a)."""
        cdef PetscInt a, t
        cdef cnp.ndarray w = fortran(omegas, 1, "frequencies")
        check(KFReducedSystemGetMatrices(self.handle(), NULL, &a, &t, NULL, NULL, NULL, NULL))
        nw = w.shape[0]
        cdef cnp.ndarray re = np.zeros(nw * t * a)
        cdef cnp.ndarray im = np.zeros(nw * t * a)
        check(KFReducedSystemResponse(self.y, nw, real_ptr(w), real_ptr(re), real_ptr(im)))
        return (re + 1j * im).reshape(nw, a, t).transpose(0, 2, 1).copy()

    def rigid_response(self, omegas):
        """The rigid-body and mechanism part of response(omegas): the system's rigid modes with the same damping model
        (KFReducedSystemRigidResponse); response - rigid_response is the elastic response. Complex (nw, t, a)."""
        cdef PetscInt a, t
        cdef cnp.ndarray w = fortran(omegas, 1, "frequencies")
        check(KFReducedSystemGetMatrices(self.handle(), NULL, &a, &t, NULL, NULL, NULL, NULL))
        nw = w.shape[0]
        cdef cnp.ndarray re = np.zeros(nw * t * a)
        cdef cnp.ndarray im = np.zeros(nw * t * a)
        check(KFReducedSystemRigidResponse(self.y, nw, real_ptr(w), real_ptr(re), real_ptr(im)))
        return (re + 1j * im).reshape(nw, a, t).transpose(0, 2, 1).copy()

    def damping(self):
        """(viscous damping matrix n x n: the bodies' C_b reassembled + alpha M + beta K, or None; the damping dict)"""
        cdef PetscInt n
        cdef const PetscReal *C
        cdef KFDamping d
        check(KFReducedSystemGetMatrices(self.handle(), &n, NULL, NULL, NULL, NULL, NULL, NULL))
        check(KFReducedSystemGetDamping(self.y, &C, &d))
        return carray(C, n, n), damping_to_dict(&d)

    def view(self, Viewer viewer=None):
        check(KFReducedSystemView(self.handle(), NULL if viewer is None else viewer.vwr))


cdef class CReducedModel:
    """Reduced bodies, joints, input and output names and settings (the C KFReducedModel)."""
    cdef KFReducedModel m

    def __dealloc__(self):
        release(<PetscObject*>&self.m)

    cdef int adopt(self, KFReducedModel m, bint borrowed) except -1:
        """Holds m; a borrowed model gets its own reference."""
        if borrowed:
            check(PetscObjectReference(<PetscObject>m))
        self.m = m
        return 0

    @classmethod
    def from_body_basis(cls, CScene scene not None, BodyBasis basis not None, angles_rad, bint keep_maps):
        """From a finished body basis; angles_rad: the reduction configurations (one row of revolute angles each)."""
        nr = scene.info()["revolute"]
        cdef cnp.ndarray ang = np.ascontiguousarray(np.asarray(angles_rad, dtype=np.float64))
        cdef CReducedModel out = cls.__new__(cls)
        cdef KFReducedModel m = NULL
        if ang.size != len(angles_rad) * nr or not np.all(np.isfinite(ang)):
            raise ValueError("give one row of %d finite angles per reduction configuration" % nr)
        check(KFReducedModelCreateFromBodyBasis(scene.s, basis.bb, <PetscInt>ang.shape[0],
                                                real_ptr(ang) if ang.size else NULL,
                                                PETSC_TRUE if keep_maps else PETSC_FALSE, &m))
        out.adopt(m, False)
        return out

    def info(self):
        cdef PetscInt nb, nj, nr, a, t, r
        check(KFReducedModelGetInfo(self.m, &nb, &nj, &nr, &a, &t, &r))
        return dict(bodies=nb, joints=nj, revolute=nr, inputs=a, outputs=t, rigid=r)

    @property
    def scene_name(self):
        cdef const char *name
        cdef const char *fp
        check(KFReducedModelGetSceneName(self.m, &name, &fp))
        return name.decode()

    @property
    def fingerprint(self):
        cdef const char *name
        cdef const char *fp
        check(KFReducedModelGetSceneName(self.m, &name, &fp))
        return fp.decode()

    def body(self, PetscInt b):
        """Reduced body b: dict with name, full_dofs, interfaces (names), M, K, G, H, iface, rigid, map (or None)."""
        cdef const char *name
        cdef const char *iname
        cdef PetscInt n
        cdef KFReducedBody B
        cdef const PetscReal *Psi
        info = self.info()
        a, t = info["inputs"], info["outputs"]
        check(KFReducedModelGetBody(self.m, b, &name, &n, &B, &Psi))
        interfaces = []
        for i in range(B.ninterfaces):
            check(KFReducedModelGetInterfaceName(self.m, b, i, &iname))
            interfaces.append(iname.decode())
        cdef const PetscReal *Cb
        check(KFReducedModelGetBodyDamping(self.m, b, &Cb))
        return dict(name=name.decode(), full_dofs=n, interfaces=interfaces, M=carray(B.M, B.v, B.v),
                    damping_matrix=carray(Cb, B.v, B.v),
                    K=carray(B.K, B.v, B.v), G=carray(B.G, B.v, a), H=carray(B.H, t, B.v),
                    iface=carray(B.iface, 6 * B.ninterfaces, B.v), rigid=carray(B.rigid, B.v, 6),
                    map=carray(Psi, n, B.v))

    def coordinate_ties(self):
        """The coordinate ties between the bodies (shared directions): ms x n (n the sum of the bodies' sizes), rows D
        with D q = 0 on the stacked body coordinates, or None for a model without them."""
        cdef PetscInt ms, n
        cdef const PetscReal *D
        check(KFReducedModelGetTies(self.m, &ms, &n, &D))
        return carray(D, ms, n) if ms else None

    def joint(self, PetscInt j):
        """Joint j (revolute joints first, in the order of the angles): dict with name, type, parent, child (body
        indices), parent_interface, child_interface (interface indices), axis, R0 (3x3, rows)."""
        cdef const char *name
        cdef KFJointDef J
        check(KFReducedModelGetJoint(self.m, j, &name, &J))
        return dict(name=name.decode(), type="revolute" if J.type == KF_JOINT_REVOLUTE else "fixed",
                    parent=J.parent, child=J.child, parent_interface=J.parent_interface,
                    child_interface=J.child_interface, axis=[J.axis[k] for k in range(3)],
                    R0=carray(J.R0, 3, 3).tolist())

    def io_names(self, bint inputs):
        cdef const char *name
        info = self.info()
        names = []
        for i in range(info["inputs"] if inputs else info["outputs"]):
            check(KFReducedModelGetIOName(self.m, PETSC_TRUE if inputs else PETSC_FALSE, i, &name))
            names.append(name.decode())
        return names

    def reduction_angles(self):
        """The reduction configurations, (nangles, revolute joints), radians."""
        cdef PetscInt n
        cdef const PetscReal *ang
        nr = self.info()["revolute"]
        check(KFReducedModelGetReductionAngles(self.m, &n, &ang))
        return carray(ang, nr, n).T.copy() if nr else np.zeros((n, 0))

    def damping(self):
        """The model's damping: {modal, rayleigh: {alpha, beta}, structural} (the bodies' viscous damping matrices are
        body(b)["damping_matrix"])"""
        cdef KFDamping d
        check(KFReducedModelGetDamping(self.m, &d))
        return damping_to_dict(&d)

    def set_damping(self, d):
        cdef KFDamping cd
        damping_from_dict(d, &cd)
        check(KFReducedModelSetDamping(self.m, &cd))

    def output_quantities(self):
        cdef const PetscInt *q
        check(KFReducedModelGetOutputQuantities(self.m, &q))
        return [["displacement", "velocity", "acceleration"][q[i]] for i in range(self.info()["outputs"])]

    def set_setting(self, key, value):
        check(KFReducedModelSetSetting(self.m, cstr(key, "setting key"), cstr(value, "setting value")))

    def setting_strings(self):
        """The recorded settings, in order: {key: value string}."""
        cdef PetscInt n
        cdef const char * const *keys
        cdef const char * const *values
        check(KFReducedModelGetSettings(self.m, &n, &keys, &values))
        return {keys[k].decode(): values[k].decode() for k in range(n)}

    def reassemble(self, angles_rad):
        """The reduced system at one configuration (one angle per revolute joint, radians): a CReducedSystem."""
        cdef cnp.ndarray ang = np.ascontiguousarray(np.atleast_1d(np.asarray(angles_rad, dtype=np.float64)))
        cdef CReducedSystem out = CReducedSystem()
        nr = self.info()["revolute"]
        if ang.ndim != 1 or ang.shape[0] != nr:
            raise ValueError("the model has %d revolute joint(s): give %d angle(s), got %d" % (nr, nr, ang.size))
        check(KFReducedModelReassemble(self.m, real_ptr(ang) if nr else NULL, &out.y))
        return out

    def view(self, Viewer viewer=None):
        check(KFReducedModelView(self.m, NULL if viewer is None else viewer.vwr))

    def save(self, path):
        """HDF5, written under a temporary name and renamed into place (docs/guide/results.md: the reduced.h5 layout)."""
        check(KFReducedModelSave(self.m, cstr(path, "file name")))
        return path

    @classmethod
    def load(cls, path, comm=None):
        """A model read from an HDF5 file written by save, with checks of format, version and consistency."""
        cdef Comm c = as_comm(comm)
        cdef CReducedModel out = cls.__new__(cls)
        cdef KFReducedModel m = NULL
        check(KFReducedModelLoad(c.comm, cstr(path, "file name"), &m))
        out.adopt(m, False)
        return out


cdef class CReassembly:
    """The allocation-free reassembly of one reduced model (KFReducedModelCreateReassembly): apply() at each angle
    vector, eig() on what apply() returned when the modes are wanted. Holds copies of the model's arrays and settings
    as they were when it was made."""
    cdef KFReassembly r
    cdef readonly PetscInt n, a, t, nrevolute
    cdef readonly bint damped, rigid

    def __cinit__(self, CReducedModel model not None, bint svd=False):
        cdef PetscBool viscous, rigid
        cdef KFDamping d
        cdef PetscInt nb, nj
        check(KFReducedModelCreateReassembly(model.m, &self.r))
        check(KFReassemblySetUseSVD(self.r, PETSC_TRUE if svd else PETSC_FALSE))
        check(KFReassemblyGetSizes(self.r, &self.n, &self.a, &self.t, &viscous, &rigid))
        check(KFReducedModelGetInfo(model.m, &nb, &nj, &self.nrevolute, NULL, NULL, NULL))
        check(KFReducedModelGetDamping(model.m, &d))
        self.damped = viscous or d.alpha > 0 or d.beta > 0
        self.rigid = rigid

    def __dealloc__(self):
        if self.r != NULL:
            KFReassemblyDestroy(&self.r)

    @property
    def svd(self):
        """Whether apply() takes the SVD of the ties at each call (else the closed form of a tree of bodies)."""
        cdef PetscBool svd
        check(KFReassemblyGetUseSVD(self.r, &svd))
        return bool(svd)

    def apply(self, angles_rad, bint info=True, bint rigid=True):
        """The reassembled system at angles_rad (one per revolute joint, radians): (M, K, C or None, G, H, Phir or None,
        rank, sigma ratio), C the viscous damping (bodies' C_b + Rayleigh), Phir the rigid-body and mechanism modes.
        info False: rank and sigma ratio None (no SVD of the ties); rigid False: Phir None (no SVD of D R)."""
        cdef double[::1] ang = np.ascontiguousarray(angles_rad, dtype=np.float64)
        cdef PetscInt n = self.n, h = 0, rank = 0, nrigid = -1
        cdef PetscReal ratio = 0
        if ang.shape[0] != self.nrevolute or np.ndim(angles_rad) > 1:
            raise ValueError("the model has %d revolute joint(s): give %d angle(s), got %d"
                             % (self.nrevolute, self.nrevolute, np.size(angles_rad)))
        for i in range(ang.shape[0]):
            if not isfinite(ang[i]):
                raise ValueError("the angles must be finite numbers, got %s" % np.asarray(angles_rad))
        cdef bint want_rigid = rigid and self.rigid
        cdef cnp.ndarray M = np.empty(n * n)
        cdef cnp.ndarray K = np.empty(n * n)
        cdef cnp.ndarray G = np.empty(n * self.a + 1)
        cdef cnp.ndarray H = np.empty(self.t * n + 1)
        cdef cnp.ndarray C = np.empty(n * n) if self.damped else None
        cdef cnp.ndarray R = np.empty(n * n) if want_rigid else None
        check(KFReassemblyApply(self.r, &ang[0] if self.nrevolute else NULL, &h, real_ptr(M), real_ptr(K),
                                real_ptr(C) if self.damped else NULL, real_ptr(G), real_ptr(H),
                                &rank if info else NULL, &ratio if info else NULL,
                                &nrigid if want_rigid else NULL, real_ptr(R) if want_rigid else NULL))
        if h < 1:
            raise ValueError("the joints' interface ties leave no free coordinate in the reduced model: reduce again "
                             "with a larger body basis")
        hh = h * h
        return (M[:hh].reshape(h, h, order="F"), K[:hh].reshape(h, h, order="F"),
                C[:hh].reshape(h, h, order="F") if self.damped else None,
                G[:h * self.a].reshape(h, self.a, order="F"), H[:self.t * h].reshape(self.t, h, order="F"),
                R[:h * nrigid].reshape(h, nrigid, order="F") if nrigid >= 0 else None,
                rank if info else None, ratio if info else None)

    def eig(self, M, K, Phir=None):
        """(eigenvalues ascending, M-orthonormal modes) of what apply() returned; with Phir the rigid modes as given."""
        cdef cnp.ndarray Mf = np.asfortranarray(M, dtype=np.float64)
        cdef cnp.ndarray Kf = np.asfortranarray(K, dtype=np.float64)
        cdef cnp.ndarray Rf = None if Phir is None else np.asfortranarray(Phir, dtype=np.float64)
        cdef PetscInt h = Mf.shape[0], nr = -1 if Phir is None else Rf.shape[1]
        if Mf.ndim != 2 or Kf.ndim != 2 or Mf.shape[1] != h or Kf.shape[0] != h or Kf.shape[1] != h or \
                (Rf is not None and Rf.shape[0] != h):
            raise ValueError("eig takes M and K of one square size (and Phir with as many rows) as apply() returned")
        cdef cnp.ndarray lam = np.empty(h)
        cdef cnp.ndarray Phi = np.empty((h, h), order="F")
        check(KFReassemblyEig(self.r, h, real_ptr(Mf), real_ptr(Kf), nr, real_ptr(Rf) if Rf is not None else NULL,
                              real_ptr(lam), real_ptr(Phi)))
        return lam, Phi
