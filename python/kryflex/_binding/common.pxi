# Errors, argument conversion and the small helpers every wrapper uses.

class Error(RuntimeError):
    """A kryflex or PETSc error, with the message of the call that failed."""


class Interrupted(Error):
    """Long C work stopped by SIGINT or SIGTERM (after interrupt_catch()): signal is the signal's number, the same on
    every rank (the C check is collective)."""

    def __init__(self, msg, signal):
        super().__init__(msg)
        self.signal = signal


cdef int check(PetscErrorCode ierr) except -1:
    """Turns a failed C call into an Error carrying the recorder's message (Interrupted for KFInterruptCheck's)."""
    if ierr != 0:
        msg = KFLastError().decode(errors="replace") or "PETSc error %d" % ierr
        KFClearError()
        if ierr == KF_ERR_INTERRUPTED:
            raise Interrupted(msg, KFInterruptSignal())
        raise Error(msg)
    return 0


def interrupt_catch():
    """Installs the C library's SIGINT/SIGTERM handlers (KFInterruptCatch): a signal is noted, and the reducer stops at
    its next stage boundary with Interrupted. For a command; Python's KeyboardInterrupt no longer fires after it."""
    check(KFInterruptCatch())


def interrupt_signal():
    """The signal noted by the handlers of interrupt_catch() on this rank (0: none)."""
    return KFInterruptSignal()


def interrupt_check(comm=None):
    """Collective: raises Interrupted on every rank if any rank noted a signal (KFInterruptCheck)."""
    cdef Comm c = as_comm(comm)
    check(KFInterruptCheck(c.comm))


def unused_options():
    """The options in PETSc's database that nothing has read yet, as (name without the dash, value or None)."""
    cdef PetscInt n = 0
    cdef char **names = NULL
    cdef char **values = NULL
    check(PetscOptionsLeftGet(NULL, &n, &names, &values))
    out = []
    try:
        for i in range(n):
            out.append((names[i].decode(errors="replace"),
                        values[i].decode(errors="replace") if values[i] != NULL else None))
    finally:
        check(PetscOptionsLeftRestore(NULL, &n, &names, &values))
    return out


# The recorder keeps the first message of a failed call instead of PETSc's traceback on stderr. It is pushed when the
# binding is first used (this module is imported lazily), and KFInitialize registers the library's log events.
check(KFPushErrorRecorder())
check(KFInitialize())

# The C API's index and real arrays are handed over as NumPy buffers: their dtypes must have PETSc's sizes.
INT_DTYPE = np.dtype(PETSc.IntType)
if INT_DTYPE.itemsize != sizeof(PetscInt) or np.dtype(PETSc.RealType) != np.dtype(np.float64) \
        or sizeof(PetscReal) != 8:
    raise ImportError("kryflex was compiled for another PETSc (PetscInt of %d bytes, PetscReal of %d) than petsc4py's "
                      "(%s, %s): rebuild it with scripts/setup" % (sizeof(PetscInt), sizeof(PetscReal),
                                                                    INT_DTYPE, np.dtype(PETSc.RealType)))


cdef void release(PetscObject *obj) nogil:
    """Releases the binding's reference to a kryflex PETSc object (KFScene, KFReducer, KFReducedModel) from a
    __dealloc__, as petsc4py releases its own objects: nothing after PetscFinalize; on one rank, destroyed now; on
    several, through PETSc's garbage (PetscObjectDelayedDestroy). Python's garbage collector frees an object at
    different times on different ranks (a frame kept in a reference cycle on one rank only, say), and an object that
    lives on one rank and not on another leaves its communicator alive on one rank only: the next collective
    communicator duplication (petsc4py's PetscGarbageCleanup at exit, a new object) then waits forever.
    PetscGarbageCleanup (at exit, or PETSc.garbage_cleanup()) destroys what every rank has released."""
    cdef MPI_Comm comm
    cdef int size = 1
    cdef PetscObject o = obj[0]
    obj[0] = NULL
    if o == NULL or not <int>PetscInitializeCalled or <int>PetscFinalizeCalled:
        return
    if PetscObjectGetComm(o, &comm) == 0:
        MPI_Comm_size(comm, &size)
    if size > 1:
        PetscObjectDelayedDestroy(&o)
    else:
        PetscObjectDestroy(&o)


cdef inline PetscReal *real_ptr(cnp.ndarray a):
    return <PetscReal*>cnp.PyArray_DATA(a)


cdef inline PetscInt *int_ptr(cnp.ndarray a):
    return <PetscInt*>cnp.PyArray_DATA(a)


cdef cnp.ndarray fortran(a, int ndim, name):
    """A column-major float64 copy with the expected number of dimensions and finite values."""
    arr = np.asarray(a, dtype=np.float64)
    if arr.ndim != ndim:
        raise ValueError("%s must have %d dimension(s), got shape %s" % (name, ndim, arr.shape))
    if not np.all(np.isfinite(arr)):
        raise ValueError("%s holds non-finite values" % name)
    return np.asfortranarray(arr)


cdef cnp.ndarray index_array(a, name):
    """A contiguous 1-D array of PetscInt from integers (a value PetscInt cannot hold is an error, not a wrap)."""
    arr = np.asarray(a)
    if arr.ndim != 1:
        arr = arr.ravel()
    if arr.size and arr.dtype.kind not in "iu":
        as_int = arr.astype(np.int64)
        if not np.array_equal(as_int, arr):
            raise ValueError("%s must hold integers, got %s" % (name, arr[:4]))
        arr = as_int
    info = np.iinfo(INT_DTYPE)
    if arr.size and (arr.min() < info.min or arr.max() > info.max):
        raise ValueError("%s holds a value outside PETSc's index range [%d, %d]" % (name, info.min, info.max))
    return np.ascontiguousarray(arr, dtype=INT_DTYPE)


cdef object carray(const PetscReal *p, Py_ssize_t m, Py_ssize_t n):
    """A NumPy copy (m x n) of a column-major C array; None for an array the C library does not have."""
    if p == NULL:
        return None
    out = np.empty((m, n), order="F")
    if m * n:
        memcpy(cnp.PyArray_DATA(out), p, m * n * sizeof(PetscReal))
    return out


cdef Mat wrap_mat(PetscMat m, bint borrowed):
    """A petsc4py Mat around a C Mat; a borrowed one gets its own reference."""
    cdef Mat out = Mat()
    if borrowed:
        check(PetscObjectReference(<PetscObject>m))
    out.mat = m
    return out


cdef Comm as_comm(comm):
    if comm is None:
        return PETSc.COMM_WORLD
    if isinstance(comm, Comm):
        return comm
    return PETSc.Comm(comm)


cdef bytes cstr(value, what):
    """A Python string as bytes for C; an embedded NUL would silently cut the name."""
    text = str(value).encode()
    if b"\0" in text:
        raise ValueError("%s %r contains a NUL character" % (what, value))
    return text


def progress(msg, comm=None):
    """A progress line on rank 0 with the elapsed time, on the C library's clock (-kf_quiet silences it)."""
    cdef Comm c = as_comm(comm)
    cdef bytes text = str(msg).encode()
    cdef const char *ctext = text
    check(KFProgress(c.comm, "%s", ctext))


def load_matrix(path, comm=None):
    """Loads a body matrix (PETSc binary or Matrix Market) in parallel."""
    cdef PetscMat m = NULL
    cdef Comm c = as_comm(comm)
    check(KFMatLoadFile(c.comm, cstr(path, "file name"), &m))
    return wrap_mat(m, False)
