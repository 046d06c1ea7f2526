# The damping description (KFDamping) as a dict, and output quantities: the scene file's keys
#   {"modal": zeta or [[f_max_hz, zeta], ...], "rayleigh": {"alpha": a, "beta": b}, "structural": g}

QUANTITIES = {"displacement": KF_QUANTITY_DISPLACEMENT, "velocity": KF_QUANTITY_VELOCITY,
              "acceleration": KF_QUANTITY_ACCELERATION}


cdef int damping_from_dict(d, KFDamping *out) except -1:
    """Fills out from a dict (keys modal, rayleigh, structural; absent ones are zero); the C library checks values."""
    memset(out, 0, sizeof(KFDamping))
    unknown = set(d) - {"modal", "rayleigh", "structural"}
    if unknown:
        raise ValueError("damping: unknown key(s) %s; use modal, rayleigh, structural" % ", ".join(sorted(unknown)))
    modal = d.get("modal")
    if modal is not None:
        if np.ndim(modal) == 0:
            out.nbands = 1
            out.fmax_hz[0] = np.inf
            out.zeta[0] = float(modal)
        else:
            bands = np.asarray(modal, dtype=float)
            if bands.ndim != 2 or bands.shape[1] != 2 or not 1 <= bands.shape[0] <= KF_MAX_DAMPING_BANDS:
                raise ValueError("damping.modal: give a ratio or a list of 1 to %d pairs [f_max_hz, zeta], got %r"
                                 % (KF_MAX_DAMPING_BANDS, modal))
            out.nbands = bands.shape[0]
            for k in range(bands.shape[0]):
                out.fmax_hz[k] = bands[k, 0]
                out.zeta[k] = bands[k, 1]
    ray = d.get("rayleigh")
    if ray is not None:
        if not isinstance(ray, dict) or set(ray) - {"alpha", "beta"}:
            raise ValueError("damping.rayleigh: give a mapping {alpha: a, beta: b}, got %r" % (ray,))
        out.alpha = float(ray.get("alpha", 0.0))
        out.beta = float(ray.get("beta", 0.0))
    if d.get("structural") is not None:
        out.g = float(d["structural"])
    return 0


cdef object damping_to_dict(const KFDamping *d):
    if d.nbands == 1 and d.fmax_hz[0] >= 1e300:   # infinity (PETSC_INFINITY in C)
        modal = float(d.zeta[0])
    else:
        modal = [[float(d.fmax_hz[k]), float(d.zeta[k])] for k in range(d.nbands)]
    return dict(modal=modal, rayleigh=dict(alpha=float(d.alpha), beta=float(d.beta)), structural=float(d.g))


def modal_ratios(d, freqs_hz):
    """The modal damping ratio of each frequency (Hz) under the damping description d (KFDampingModalRatio)."""
    cdef KFDamping c
    damping_from_dict(d, &c)
    return np.array([KFDampingModalRatio(&c, float(f)) for f in np.ravel(freqs_hz)])


cdef KFQuantity quantity_code(q, PetscInt i) except *:
    if q not in QUANTITIES:
        raise ValueError("output %d: quantity %r is not one of %s" % (i, q, ", ".join(QUANTITIES)))
    return QUANTITIES[q]
