# CReducer: the whole reduction of a scene (the C KFReducer, a PETSc object in the manner of KSP). Setters take
# radians and NumPy arrays; results come back as NumPy copies, shaped as C records them (column-major over shape).
# The models it hands out hold their own reference, so they outlive the reducer.

METHODS = {"single-angle": KF_METHOD_SINGLE_ANGLE, "multi-angle": KF_METHOD_MULTI_ANGLE, "auto": KF_METHOD_AUTO}
REDUCER_TYPES = ("krylov", "eigen")


cdef class CReducer:
    """The reduction of a scene (the C KFReducer): create, set the scene and what the reduction must serve,
    set_from_options (every -kf_ option), setup, solve, then the models and the named results."""
    cdef KFReducer r
    cdef readonly CScene scene

    def __cinit__(self, comm=None):
        cdef Comm c = as_comm(comm)
        check(KFReducerCreate(c.comm, &self.r))

    def __dealloc__(self):
        release(<PetscObject*>&self.r)

    cdef PetscInt nrevolute(self) except -1:
        if self.scene is None:
            raise ValueError("set the scene first (CReducer.set_scene)")
        return self.scene.info()["revolute"]

    cdef tuple angle_rows(self, angles_rad, what):
        """(n, the rows of (n, nrevolute) finite radians as one contiguous array at least one entry long, for C)."""
        nr = self.nrevolute()
        arr = np.asarray(angles_rad, dtype=np.float64)
        if arr.ndim == 1 and nr <= 1:
            arr = arr.reshape(-1, 1) if nr else arr.reshape(1, 0)
        if arr.ndim != 2 or arr.shape[1] != nr:
            raise ValueError("%s: give one row of %d angle(s) (one per revolute joint) per configuration, got shape %s"
                             % (what, nr, arr.shape))
        if not np.all(np.isfinite(arr)):
            raise ValueError("%s: angles must be finite numbers" % what)
        return arr.shape[0], np.ascontiguousarray(arr.ravel() if arr.size else np.zeros(1))

    # ------------------------------------------------------------------ what the reduction must serve

    def set_type(self, kind):
        if kind not in REDUCER_TYPES:
            raise ValueError("reducer type %r is not one of %s" % (kind, ", ".join(REDUCER_TYPES)))
        check(KFReducerSetType(self.r, cstr(kind, "reducer type")))

    def get_type(self):
        cdef KFReducerType kind = NULL
        check(KFReducerGetType(self.r, &kind))
        return None if kind == NULL else (<bytes>kind).decode()

    def set_options_prefix(self, prefix):
        cdef bytes text = cstr(prefix or "", "options prefix")
        check(KFReducerSetOptionsPrefix(self.r, text))

    def set_scene(self, CScene scene not None):
        check(KFReducerSetScene(self.r, scene.s))
        self.scene = scene

    def set_system(self, CSystem system):
        """An assembled system of the scene (CSystem.set_angles) the next solve starts from: at the angles of its first
        configuration it takes the system's matrices and rigid modes instead of making them again
        (KFReducerSetSystem). The reducer holds the system until that solve ends and assembles it at its other
        configurations; None drops one given before."""
        check(KFReducerSetSystem(self.r, NULL if system is None else system.y))

    def set_angles(self, angles_rad):
        """The angles of interest: (nconfig, nrevolute) radians."""
        cdef cnp.ndarray a
        n, a = self.angle_rows(angles_rad, "angles of interest")
        if n < 1:
            raise ValueError("angles of interest: give at least one configuration")
        check(KFReducerSetAngles(self.r, <PetscInt>n, real_ptr(a)))

    def get_angles(self):
        """The angles of interest as the reducer has them (after set_from_options: -kf_angles): (nconfig, nrevolute)
        radians."""
        cdef PetscInt n = 0
        cdef const PetscReal *ang = NULL
        nr = self.nrevolute()
        check(KFReducerGetAngles(self.r, &n, &ang))
        if nr == 0 or n == 0 or ang == NULL:
            return np.zeros((n, 0))
        return carray(ang, nr, n).T.copy()

    def set_reduction_angle(self, angles_rad=None):
        """alpha_G of the single-angle model (nrevolute radians); None: chosen by the paper's rule."""
        cdef cnp.ndarray a
        if angles_rad is None:
            check(KFReducerSetReductionAngle(self.r, NULL))
            return
        n, a = self.angle_rows(np.reshape(np.asarray(angles_rad, dtype=np.float64), (1, -1)), "reduction angle")
        check(KFReducerSetReductionAngle(self.r, real_ptr(a)))

    def set_multi_angles(self, angles_rad=None):
        """The configurations of the multi-angle model ((n, nrevolute) radians); None: the angles of interest."""
        cdef cnp.ndarray a
        if angles_rad is None or len(angles_rad) == 0:
            check(KFReducerSetMultiAngles(self.r, 0, NULL))
            return
        n, a = self.angle_rows(angles_rad, "multi-angle configurations")
        check(KFReducerSetMultiAngles(self.r, <PetscInt>n, real_ptr(a)))

    def set_method(self, method):
        if method not in METHODS:
            raise ValueError("method %r is not one of %s" % (method, ", ".join(METHODS)))
        check(KFReducerSetMethod(self.r, METHODS[method]))

    def set_band(self, PetscReal fmin_hz, PetscReal fmax_hz):
        check(KFReducerSetBand(self.r, fmin_hz, fmax_hz))

    def set_damping(self, PetscReal zeta):
        check(KFReducerSetDamping(self.r, zeta))

    def set_damping_model(self, d):
        """{modal: zeta or [[f_max_hz, zeta], ...], rayleigh: {alpha, beta}, structural: g}; absent parts are zero"""
        cdef KFDamping cd
        damping_from_dict(d, &cd)
        check(KFReducerSetDampingModel(self.r, &cd))

    def damping_model(self):
        cdef KFDamping d
        check(KFReducerGetDampingModel(self.r, &d))
        return damping_to_dict(&d)

    def set_accuracy(self, PetscReal target):
        check(KFReducerSetAccuracy(self.r, target))

    def set_accuracy_measure(self, measure):
        """elastic (the response minus its rigid-body and mechanism part) or total: what the accuracy is stated on"""
        if measure not in ACCURACY_MEASURES:
            raise ValueError("accuracy_measure: give %s, got %r" % (" or ".join(ACCURACY_MEASURES), measure))
        check(KFReducerSetAccuracyMeasure(self.r, ACCURACY_MEASURES[measure]))

    def accuracy_measure(self):
        cdef KFAccuracyMeasure m
        check(KFReducerGetAccuracyMeasure(self.r, &m))
        return "elastic" if m == KF_ACCURACY_ELASTIC else "total"

    def set_moments(self, moments, PetscInt output_blocks=1):
        """moments: an integer, or "auto" (None): the accuracy search chooses"""
        cdef PetscInt c = -1 if moments in (None, "auto") else int(moments)   # -1: PETSC_DECIDE
        check(KFReducerSetMoments(self.r, c, output_blocks))

    def set_search(self, search, PetscInt moments_max=24):
        check(KFReducerSetSearch(self.r, PETSC_TRUE if search else PETSC_FALSE, moments_max))

    def set_compress(self, compress):
        check(KFReducerSetCompress(self.r, PETSC_TRUE if compress else PETSC_FALSE))

    def set_static_exact(self, exact):
        check(KFReducerSetStaticExact(self.r, PETSC_TRUE if exact else PETSC_FALSE))

    def set_cluster_tolerance(self, PetscReal rtol):
        check(KFReducerSetClusterTolerance(self.r, rtol))

    def set_importance(self, measure, PetscReal keep_threshold):
        if measure not in IMPORTANCE:
            raise ValueError("importance measure %r is not one of %s" % (measure, ", ".join(IMPORTANCE)))
        check(KFReducerSetImportance(self.r, IMPORTANCE[measure], keep_threshold))

    def set_static_correction(self, bint flag):
        check(KFReducerSetStaticCorrection(self.r, PETSC_TRUE if flag else PETSC_FALSE))

    def set_tolerances(self, PetscReal deflation_tol, PetscReal body_tol, PetscReal reassembly_rtol):
        check(KFReducerSetTolerances(self.r, deflation_tol, body_tol, reassembly_rtol))

    def set_max_frequency(self, value):
        """The trimming limit: None or "none" (off), a multiple of the band's top (3, "3x") or a frequency ("40 Hz"),
        parsed by KFParseMaxFrequency."""
        cdef PetscReal x
        cdef PetscBool hz
        cdef MPI_Comm comm
        text = "none" if value is None else ("%.17g" % value if isinstance(value, (int, float)) and not isinstance(value, bool) else str(value))
        b = text.encode()
        check(PetscObjectGetComm(<PetscObject>self.r, &comm))
        check(KFParseMaxFrequency(comm, b, &x, &hz))
        check(KFReducerSetMaxFrequency(self.r, x, hz))

    def get_max_frequency(self):
        """The trimming limit in Hz (0: off)."""
        cdef PetscReal f
        check(KFReducerGetMaxFrequency(self.r, &f))
        return float(f)

    def set_shift(self, PetscReal shift):
        check(KFReducerSetShift(self.r, shift))

    def set_save_maps(self, save_maps):
        """True, False, or None / "auto" (keep the maps while no body exceeds -kf_save_maps_max_dofs)."""
        cdef PetscInt value = -1   # PETSC_DECIDE
        if save_maps is True or save_maps is False:
            value = 1 if save_maps else 0
        elif save_maps not in (None, "auto"):
            raise ValueError("save_maps must be true, false or auto, got %r" % (save_maps,))
        check(KFReducerSetSaveMaps(self.r, value))

    def eigen_set_cover(self, PetscReal cover):
        check(KFReducerEigenSetCover(self.r, cover))

    def set_verification(self, full_order, modes=None, PetscInt frequency_points=400, PetscReal frf_floor_db=-60.0,
                         certified_min_dofs=None):
        """The verdict: full_order True (measured against the full order), False (estimated against the richest
        candidate) or "auto" (measured below certified_min_dofs system dofs, None: 50000; from there the estimate
        certified by the mode count); modes (None or "auto": cover 3 x the band's top), frequency points and the FRF
        error's floor (dB)."""
        cdef PetscInt nmodes = -1  # PETSC_DECIDE
        cdef PetscInt min_dofs = -1
        if modes not in (None, "auto"):
            nmodes = int(modes)
        auto = isinstance(full_order, str) and full_order == "auto"
        if isinstance(full_order, str) and not auto:
            raise ValueError("verify.full_order must be true, false or auto, got %r" % (full_order,))
        check(KFReducerSetVerification(self.r, PETSC_TRUE if (auto or full_order) else PETSC_FALSE, nmodes,
                                       frequency_points, frf_floor_db))
        if certified_min_dofs is not None:
            min_dofs = int(certified_min_dofs)
        if auto:
            check(KFReducerSetVerificationAuto(self.r, min_dofs))

    def verification_plan(self):
        """(measured, certified): whether the solve will measure its verdict against the full order, or estimate it
        and certify the estimate by the mode count (-kf_verify auto, resolved by the scene's size and the target;
        the count may still fall back to measuring). After setup()."""
        cdef PetscBool measured = PETSC_FALSE, certified = PETSC_FALSE
        check(KFReducerGetVerificationPlan(self.r, &measured, &certified))
        return bool(measured), bool(certified)

    def set_count_source(self, int fd):
        """The read end of the pipe a helper process writes the certificate's counts to (-1: counted in-process);
        the caller keeps it open until the solve ends and closes it."""
        check(KFReducerSetCountSource(self.r, fd))

    def certify_count_write(self, int fd):
        """The helper's side: the certificate's counts at every configuration, written to fd."""
        check(KFReducerCertifyCountWrite(self.r, fd))

    def set_from_options(self):
        check(KFReducerSetFromOptions(self.r))

    # ------------------------------------------------------------------ the reduction

    def setup(self):
        check(KFReducerSetUp(self.r))

    def solve(self):
        check(KFReducerSolve(self.r))

    def view(self, Viewer viewer=None):
        check(KFReducerView(self.r, NULL if viewer is None else viewer.vwr))

    # ------------------------------------------------------------------ what it made

    def models(self, cls=CReducedModel):
        """(the model of the chosen method, the single-angle model, the multi-angle model or None) as instances of cls
        (a CReducedModel class); the chosen one is the same object as the one of its method. Each holds its own
        reference to the C model, so it outlives the reducer."""
        cdef KFReducedModel single = NULL
        cdef KFReducedModel multi = NULL
        cdef KFReducedModel chosen = NULL
        if not (isinstance(cls, type) and issubclass(cls, CReducedModel)):
            raise TypeError("cls must be CReducedModel or a subclass of it")
        check(KFReducerGetReducedModels(self.r, &single, &multi))
        check(KFReducerGetReducedModel(self.r, &chosen))
        s, m = wrap_model(cls, single), wrap_model(cls, multi)
        if chosen != NULL and chosen == multi:
            return m, s, m
        if chosen != NULL and chosen != single:
            raise Error("the reducer's model is neither its single-angle nor its multi-angle model")
        return s, s, m

    def result_names(self, PetscInt config=-1):
        """The names of the results recorded for configuration config (an index into the angles of interest), or
        for the whole solve (-1)."""
        cdef PetscInt n = 0
        cdef const char * const *names = NULL
        check(KFReducerGetResultNames(self.r, config, &n, &names))
        return [(<bytes>names[k]).decode() for k in range(n)]

    def result(self, PetscInt config, name):
        """A named result as a NumPy array of C's shape (column-major data); NaN marks values not available."""
        cdef PetscInt ndim = 0
        cdef const PetscInt *shape = NULL
        cdef const PetscReal *data = NULL
        check(KFReducerGetResult(self.r, config, cstr(name, "result name"), &ndim, &shape, &data))
        dims = tuple(int(shape[k]) for k in range(ndim))
        out = np.empty(dims, order="F")
        count = out.size
        if count:
            if data == NULL:
                raise Error("result %r of configuration %d has no data" % (name, config))
            memcpy(cnp.PyArray_DATA(out), data, count * sizeof(PetscReal))
        return out

    def notes(self):
        cdef PetscInt n = 0
        cdef const char * const *notes = NULL
        check(KFReducerGetNotes(self.r, &n, &notes))
        return [(<bytes>notes[k]).decode(errors="replace") for k in range(n)]

    def rule(self):
        cdef const char *rule = NULL
        check(KFReducerGetReductionRule(self.r, &rule))
        return "" if rule == NULL else (<bytes>rule).decode(errors="replace")


cdef object wrap_model(cls, KFReducedModel m):
    """A borrowed C model in a new instance of cls, with its own reference; None for NULL."""
    cdef CReducedModel out
    if m == NULL:
        return None
    out = cls.__new__(cls)
    out.adopt(m, True)
    return out
