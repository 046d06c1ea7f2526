# The error measures of src/measure (one definition everywhere: the reducer, the verification, scripts and tests),
# on NumPy arrays in the Python layouts: responses (frequencies, outputs, inputs), moments (k, outputs, inputs).
# Undefined values are NaN, as in C.

cdef cnp.ndarray blocks_ta(X, name):
    """(n, t, a) -> the C layout: n blocks of t x a column-major, as one contiguous float64 array."""
    arr = np.asarray(X, dtype=np.float64)
    if arr.ndim != 3:
        raise ValueError("%s must have 3 dimensions (count, outputs, inputs), got shape %s" % (name, arr.shape))
    return np.ascontiguousarray(arr.transpose(0, 2, 1))


def frf_errors(Tf, Tr, PetscReal floor_db=-60.0, rigid=None):
    """(hinf, pointwise) of a reduced response against the full one, per input/output pair (KFFRFElasticErrors):
    hinf = max over pairs of max_w |Tf - Tr| / max_w |Tf - rigid| (the relative H-infinity error the accuracy target
    applies to); pointwise = max over pairs and frequencies of |Tf - Tr| / max(|Tf - rigid|, 10^(floor_db/20) x the
    pair's peak). rigid: the rigid-body and mechanism part of Tf (the elastic measure), or None (the total response).
    Tf, Tr, rigid: complex (frequencies, outputs, inputs)."""
    full = np.asarray(Tf)
    red = np.asarray(Tr)
    if full.shape != red.shape or full.ndim != 3:
        raise ValueError("the full and reduced responses must have the same shape (frequencies, outputs, inputs), "
                         "got %s and %s" % (full.shape, red.shape))
    cdef cnp.ndarray fre = blocks_ta(full.real, "the full response")
    cdef cnp.ndarray fim = blocks_ta(np.imag(full), "the full response")
    cdef cnp.ndarray rre = blocks_ta(red.real, "the reduced response")
    cdef cnp.ndarray rim = blocks_ta(np.imag(red), "the reduced response")
    cdef cnp.ndarray gre, gim
    cdef PetscReal hinf = 0, pointwise = 0
    if rigid is None:
        check(KFFRFErrors(<PetscInt>full.shape[0], <PetscInt>full.shape[1], <PetscInt>full.shape[2], real_ptr(fre),
                          real_ptr(fim), real_ptr(rre), real_ptr(rim), floor_db, &hinf, &pointwise))
    else:
        g = np.asarray(rigid)
        if g.shape != full.shape:
            raise ValueError("the rigid part must have the full response's shape %s, got %s" % (full.shape, g.shape))
        gre = blocks_ta(g.real, "the rigid part")
        gim = blocks_ta(np.imag(g), "the rigid part")
        check(KFFRFElasticErrors(<PetscInt>full.shape[0], <PetscInt>full.shape[1], <PetscInt>full.shape[2],
                                 real_ptr(fre), real_ptr(fim), real_ptr(rre), real_ptr(rim), real_ptr(gre),
                                 real_ptr(gim), floor_db, &hinf, &pointwise))
    return float(hinf), float(pointwise)


FLOOR_KINDS = (None, "largest_pair", "own_total")


def frf_pair_floors(Tf, rigid=None):
    """Which floor each input/output pair's denominator in frf_errors is (KFFRFPairFloors), (outputs, inputs) of
    FLOOR_KINDS: None its own peak, "largest_pair" 1e-4 x the largest pair's peak (its own negligible against it),
    "own_total" 1e-6 x its own total peak (the elastic response within the rigid part's rounding; elastic only).
    Tf, rigid: complex (frequencies, outputs, inputs); rigid None: the total response."""
    full = np.asarray(Tf)
    if full.ndim != 3 or full.shape[0] < 1:
        raise ValueError("the full response must have shape (frequencies >= 1, outputs, inputs), got %s" % (full.shape,))
    nw, t, a = full.shape
    cdef cnp.ndarray fre = blocks_ta(full.real, "the full response")
    cdef cnp.ndarray fim = blocks_ta(np.imag(full), "the full response")
    cdef cnp.ndarray gre, gim
    cdef cnp.ndarray fl = np.zeros(max(t * a, 1), dtype=INT_DTYPE)
    if rigid is None:
        check(KFFRFPairFloors(<PetscInt>nw, <PetscInt>t, <PetscInt>a, real_ptr(fre), real_ptr(fim), NULL, NULL,
                              int_ptr(fl)))
    else:
        g = np.asarray(rigid)
        if g.shape != full.shape:
            raise ValueError("the rigid part must have the full response's shape %s, got %s" % (full.shape, g.shape))
        gre = blocks_ta(g.real, "the rigid part")
        gim = blocks_ta(np.imag(g), "the rigid part")
        check(KFFRFPairFloors(<PetscInt>nw, <PetscInt>t, <PetscInt>a, real_ptr(fre), real_ptr(fim), real_ptr(gre),
                              real_ptr(gim), int_ptr(fl)))
    codes = fl[:t * a].reshape(a, t).T      # t x a column-major
    return [[FLOOR_KINDS[int(codes[i, j])] for j in range(a)] for i in range(t)]


def moment_errors(Lall, PetscInt config, Lred, PetscReal negligible=1e-8):
    """(errors (k), ratios (k, outputs, inputs)) of the reduced moments Lred against the full ones of configuration
    config among Lall (configurations, k, outputs, inputs) (KFMomentErrors): normwise relative errors and entrywise
    ratios L_full / L_red, NaN where the full moment is negligible over the configurations."""
    full = np.asarray(Lall, dtype=np.float64)
    if full.ndim != 4:
        raise ValueError("Lall must have 4 dimensions (configurations, k, outputs, inputs), got shape %s" % (full.shape,))
    nconfig, nmom, t, a = full.shape
    if np.shape(Lred) != (nmom, t, a):
        raise ValueError("Lred must have shape %s, got %s" % ((nmom, t, a), np.shape(Lred)))
    if not 0 <= config < nconfig:
        raise ValueError("configuration %d is not among the %d given" % (config, nconfig))
    cdef cnp.ndarray cL = np.ascontiguousarray(full.transpose(0, 1, 3, 2))
    cdef cnp.ndarray cR = blocks_ta(Lred, "Lred")
    cdef cnp.ndarray errors = np.zeros(nmom)
    cdef cnp.ndarray ratios = np.zeros(nmom * t * a)
    check(KFMomentErrors(nmom, t, a, nconfig, real_ptr(cL), config, real_ptr(cR), negligible, real_ptr(errors),
                         real_ptr(ratios)))
    return errors, ratios.reshape(nmom, a, t).transpose(0, 2, 1).copy()


def rigid_tolerance(lam, PetscInt nrigid):
    """A relative tolerance separating the nrigid lowest eigenvalues from the rest (KFRigidTolerance)."""
    cdef cnp.ndarray cl = fortran(lam, 1, "eigenvalues")
    cdef PetscReal rtol = 0
    check(KFRigidTolerance(<PetscInt>cl.shape[0], real_ptr(cl) if cl.shape[0] else NULL, nrigid, &rtol))
    return float(rtol)


def frequency_grid(band, resonances_hz, PetscReal zeta, PetscInt npoints):
    """Log-spaced points over the band (Hz) plus 7 points around each resonance in it, sorted, unique
    (KFFrequencyGrid)."""
    lo, hi = [float(x) for x in band]
    cdef cnp.ndarray fres = fortran(np.atleast_1d(np.asarray(resonances_hz, dtype=np.float64)), 1, "resonances")
    if npoints < 0:
        raise ValueError("the number of points must be >= 0, got %d" % npoints)
    nres = fres.shape[0]
    cdef cnp.ndarray f = np.zeros(max(npoints + 7 * nres, 1))
    cdef PetscInt nf = 0
    check(KFFrequencyGrid(lo, hi, npoints, nres, real_ptr(fres) if nres else NULL, zeta, &nf, real_ptr(f)))
    return f[:nf].copy()
