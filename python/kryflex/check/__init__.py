"""A model health report before any reduction (`kryflex check SCENE`, and warnings of `kryflex reduce`).

Per body and for the assembled system at the scene's first configuration:
  - the geometric rigid-body and mechanism modes (derived by the C library from geometry, joints and boundary
    conditions) and the energy K carries in them: the Rayleigh quotients of Phi^T K Phi against Phi^T M Phi, in Hz
    (an exported stiffness rounded to 8 digits gives its rigid modes a little energy);
  - the symmetry defect ||A - A^T||_F / ||A||_F of K and M;
  - M's zero-diagonal (massless) dofs, and on models up to DENSE_MAX dofs M's rank (a null space beyond the zero
    diagonal: lumped masses without rotary inertia), K's near-zero eigenvalues against the geometric count (the null
    pivots a factorization would meet), the condition estimate of K on its flexible part, and the full-order modes the
    verification would need (below 3 x the band's top).
The sparse products run on PETSc's distributed matrices (every rank takes part); the dense spectra are computed on
every rank from a gathered copy, only for models up to DENSE_MAX dofs (said so in the report above it).
Each finding carries what it does to a reduction and the fix. Nothing here changes the model.
"""
import dataclasses

import numpy as np

DENSE_MAX = 3000          # dofs: dense spectra (rank of M, null pivots, condition, verification modes) up to this
REDUCE_DENSE_MAX = 600    # dofs: the same inside kryflex reduce (cubic: 14 s of a 17 s bare reduction at 2,760 dofs,
                          # 0.3 s at 1,000; every dense finding there is a note or one the reduction refuses itself)
SYMMETRY_WARN = 1e-10     # relative Frobenius asymmetry reported above this
RIGID_ENERGY_RTOL = 1e-11 # a rigid mode's Rayleigh quotient above this x ||K||_F / ||M||_F is reported: round-off
                          # leaves ~1e-16 of it, a stiffness rounded to 8 digits ~1e-9
NULL_RTOL = 1e-12         # eigenvalues of K below this x the largest count as zero (null pivots), or below
RIGID_MARGIN = 100.0      # this x the largest rigid-mode Rayleigh quotient (a rounded export's rigid energy)


@dataclasses.dataclass
class Finding:
    where: str            # 'system' or "body 'name'"
    what: str             # the measured fact
    effect: str           # what it does to a reduction
    fix: str              # the option or the fix that applies
    severity: str = "warning"   # 'warning' or 'note'
    refused: bool = False       # the reduction refuses this model itself, with its own message (kryflex reduce
                                # then leaves the warning out: one error line)

    def text(self):
        return "%s: %s; %s; %s" % (self.where, self.what, self.effect, self.fix)

    def as_dict(self):
        return dataclasses.asdict(self)


def _asymmetry(A, exact=False):
    """||A - A^T||_F / ||A||_F (0 for an exactly symmetric A; exact: A is known to be, from the scene's set-up)."""
    from petsc4py import PETSc
    if exact:
        # the scene's set-up compared every entry with its partner already (src/scene/setup.c): comparing the matrix
        # with its transpose again took 0.1 s of kryflex reduce's model check at 57k dofs
        return 0.0
    try:
        if A.isSymmetric(0.0):
            # exactly symmetric (most exports): the measure is 0, found without forming A^T and A - A^T, which cost
            # 5 times as much (a fifth of kryflex reduce's model check at 57k dofs)
            return 0.0
    except PETSc.Error:     # a matrix type without the test: measured below
        pass
    At = A.transpose(PETSc.Mat())
    D = A.copy()
    D.axpy(-1.0, At, structure=PETSc.Mat.Structure.DIFFERENT_NONZERO_PATTERN)
    At.destroy()    # now: dropped, they would wait in PETSc's garbage (2 copies of each body matrix, 7 GB at 2M dofs)
    na = A.norm(PETSc.NormType.FROBENIUS)
    nd = D.norm(PETSc.NormType.FROBENIUS)
    D.destroy()
    return float(nd / na) if na > 0 else 0.0


def _quotients(K, M, X, products=(None, None)):
    """X^T K X and X^T M X for the columns of a dense PETSc Mat X (None: no column), small dense, the same on every
    rank: two sparse-dense products and the local blocks' products summed over ranks (a product and a dot per pair of
    vectors, from Python, took 0.1 s of kryflex reduce's model check at 57k dofs). products: K X and M X where they
    are made already (the system's rigid modes: CSystem.rigid_products), used as they are."""
    if X is None or X.getSize()[1] == 0:
        return np.zeros((0, 0)), np.zeros((0, 0))
    comm = X.getComm().tompi4py()
    x = X.getDenseArray()
    KX, MX = (P if P is not None else A.matMult(X) for P, A in zip(products, (K, M)))
    kr = comm.allreduce(x.T @ KX.getDenseArray())
    mr = comm.allreduce(x.T @ MX.getDenseArray())
    for P, made in zip(products, (KX, MX)):
        if P is None:
            made.destroy()
    return 0.5 * (kr + kr.T), 0.5 * (mr + mr.T)


def rigid_hz(kr, mr):
    """Signed frequencies (Hz) of the pencil (kr, mr): sign(lambda) sqrt(|lambda|) / 2 pi, ascending."""
    if not len(kr):
        return np.zeros(0)
    # the columns may be dependent (a body sees the system's rigid and mechanism modes as fewer motions): the pencil
    # on the range of mr
    wm, V = np.linalg.eigh(mr)
    V = V[:, wm > 1e-10 * max(wm.max(), 1e-300)] / np.sqrt(wm[wm > 1e-10 * max(wm.max(), 1e-300)])
    lam = np.linalg.eigvalsh(V.T @ kr @ V) if V.shape[1] else np.zeros(0)
    return np.sign(lam) * np.sqrt(np.abs(lam)) / (2 * np.pi)


def _dense(A):
    """A distributed PETSc Mat as a dense NumPy array on every rank."""
    comm = A.getComm().tompi4py()
    ai, aj, av = A.getValuesCSR()
    r0, _ = A.getOwnershipRange()
    n, m = A.getSize()
    rows = np.repeat(np.arange(len(ai) - 1), np.diff(ai)) + r0
    parts = comm.allgather((rows, np.asarray(aj), np.asarray(av)))
    D = np.zeros((n, m))
    for rr, cc, vv in parts:
        np.add.at(D, (rr, cc), vv)
    return D


def _diagonal_zeros(M):
    d = M.getDiagonal()
    comm = M.getComm().tompi4py()
    lo, _ = d.getOwnershipRange()
    local = [lo + i for i in np.flatnonzero(d.getArray() <= 0)]
    return sorted(sum(comm.allgather(local), []))


def factor_pivots(K):
    """(null pivots, negative pivots) of a MUMPS Cholesky (LDL^T) factorization of K with null-pivot detection
    (ICNTL(24) = 1, threshold CNTL(3) = 1e-9 x the matrix norm's scale), on K's communicator: the counts a
    factorization of the unsupported system meets. None when MUMPS refuses to factor."""
    from petsc4py import PETSc
    A = K.duplicate(copy=True)
    ksp = PETSc.KSP().create(K.getComm())
    try:
        ksp.setOperators(A)
        ksp.setType("preonly")
        pc = ksp.getPC()
        pc.setType("cholesky")
        pc.setFactorSolverType("mumps")
        pc.setFactorSetUpSolverType()
        F = pc.getFactorMatrix()
        F.setMumpsIcntl(24, 1)
        F.setMumpsCntl(3, 1e-9)
        try:
            ksp.setUp()
        except PETSc.Error:
            return None
        return int(F.getMumpsInfog(28)), int(F.getMumpsInfog(12))
    finally:
        ksp.destroy()
        A.destroy()


def _scale(K, M):
    from petsc4py import PETSc
    nm = M.norm(PETSc.NormType.FROBENIUS)
    return float(K.norm(PETSc.NormType.FROBENIUS) / nm) if nm > 0 else 0.0


def _rigid_findings(where, f_hz, scale, f_ref, findings):
    worst = float(np.max(np.abs(f_hz))) if len(f_hz) else 0.0
    if (2 * np.pi * worst) ** 2 > RIGID_ENERGY_RTOL * scale:
        findings.append(Finding(
            where, "the stiffness carries energy in its geometric rigid-body modes: Rayleigh frequencies %s Hz (%.1e of "
            "%.4g Hz)" % (", ".join("%.3g" % x for x in f_hz), worst / f_ref, f_ref),
            "the flexible frequencies then shift by about that much and the block solves stay above the refinement "
            "threshold (a stiffness rounded when exported, e.g. to 8 digits in a Nastran punch, or a support the "
            "scene does not declare)",
            "export K with full precision (OUTPUT4 binary, Matrix Market with 17 digits), or project the energy out: "
            "K := P^T K P with P = I - M Phi Phi^T (Phi the M-orthonormal rigid modes); a real support: declare it "
            "(constraints, springs)"))
    return worst


def check_scene(scene, system=None, factor=True, dense_max=DENSE_MAX):
    """The health report of a loaded Scene: (facts: dict for JSON, findings: [Finding]). Collective. factor=False
    leaves out the MUMPS factorization of K (kryflex reduce: its own factorizations follow); the dense spectra are
    computed up to dense_max system dofs (kryflex reduce: REDUCE_DENSE_MAX)."""
    from .. import _core
    band = list(scene.band)
    if system is None:
        system = _core.CSystem(scene.cscene)
        system.set_angles(scene.angles_rad(scene.configurations[0]))
    Phi, residual = system.rigid_modes()[:2]
    nrigid = Phi.getSize()[1] if Phi is not None and Phi.handle else 0
    Ms, Ks = system.matrices()[:2]
    findings, bodies, rigid_b = [], [], []
    n_sys = Ks.getSize()[0]
    for b, name in enumerate(scene.body_names):
        where = "body '%s'" % name
        M, K = scene.cscene.body_matrices(b)[:2]
        Xb = system.body_map(b).matMult(Phi) if nrigid else None
        kr, mr = _quotients(K, M, Xb)
        if Xb is not None:
            Xb.destroy()
        f_b = rigid_hz(kr, mr)
        exact_m, exact_k = scene.cscene.body_symmetric(b)
        asym = {"K": _asymmetry(K, exact_k), "M": _asymmetry(M, exact_m)}
        zeros = _diagonal_zeros(M)
        fact = dict(name=name, dofs=K.getSize()[0], rigid_hz=f_b.tolist(), asymmetry=asym, massless_dofs=len(zeros))
        rigid_b.append((where, f_b, _scale(K, M)))
        for key, val in asym.items():
            if val > SYMMETRY_WARN:
                findings.append(Finding(where, "%s is not symmetric: ||%s - %s^T||_F / ||%s||_F = %.2e" % (key, key, key, key, val),
                                        "kryflex symmetrizes nothing: a reduction refuses it or reduces (A + A^T)/2",
                                        "fix the export (both triangles, the same precision), or symmetrize if it is "
                                        "round-off"))
        if zeros:
            findings.append(Finding(where, "%d massless dofs (zero diagonal of M; body dofs %s%s)" % (
                len(zeros), ", ".join(str(z) for z in zeros[:8]), ", ..." if len(zeros) > 8 else ""),
                "accepted: the Krylov recurrence does not need them; the verification condenses them statically",
                "nothing to do, unless a dof should carry mass (rotary inertia, a lumped mass)", "note"))
        bodies.append(fact)
    # K_S Phi and M_S Phi as the C library formed them (its rigid residual, its projections: the reduction that
    # starts from this system uses M_S Phi again), the same products
    kr, mr = _quotients(Ks, Ms, Phi if nrigid else None, system.rigid_products() if nrigid else (None, None))
    f_sys = rigid_hz(kr, mr)
    facts = dict(system_dofs=n_sys, rigid_modes=nrigid, rigid_residual=float(residual), rigid_hz=f_sys.tolist(),
                 bodies=bodies, band_hz=band, dense=n_sys <= dense_max)
    dense = []
    pivots = factor_pivots(Ks) if factor else None
    if pivots is not None:
        facts.update(factor_null_pivots=pivots[0], factor_negative_pivots=pivots[1])
    if n_sys <= dense_max:
        lam_r = float(np.max(np.abs(2 * np.pi * f_sys) ** 2)) if len(f_sys) else 0.0
        _dense_findings(_dense(Ms), _dense(Ks), nrigid, lam_r, band, facts, dense)
    else:
        facts["dense_skipped"] = "the system has %d dofs > %d: M's rank, K's spectrum (its condition) and the " \
                                 "verification's mode count were not computed%s" % (
                                     n_sys, dense_max, " (kryflex check computes them up to %d dofs)" % DENSE_MAX
                                     if dense_max < DENSE_MAX and n_sys <= DENSE_MAX else "")
        # no finding from the factorization's counts alone: MUMPS' null-pivot detection depends on its threshold and
        # ordering (a mechanism's soft pivot may or may not count; measured on a 20k-dof frame: 6 of 7 on 1 rank,
        # 7 on 2), so they are reported as facts, a cross-check of the geometric count
    f_ref = max(facts.get("first_flexible_hz") or band[1] / 10, band[0])
    _rigid_findings("system", f_sys, _scale(Ks, Ms), f_ref, findings)
    for where, f_b, scale in (rigid_b if len(rigid_b) > 1 else []):   # one body: the system's finding says it
        _rigid_findings(where, f_b, scale, f_ref, findings)
    return facts, findings + dense


def _dense_findings(M, K, nrigid, lam_r, band, facts, findings):
    import scipy.linalg as sl
    wm = np.linalg.eigvalsh(0.5 * (M + M.T))
    mtop = max(abs(wm).max(), 1e-300)
    null_m = int(np.sum(wm <= NULL_RTOL * mtop))
    zero_diag = int(np.sum(np.diag(M) <= 0))
    wk = np.linalg.eigvalsh(0.5 * (K + K.T))
    ktop = max(abs(wk).max(), 1e-300)
    zero = max(NULL_RTOL * ktop, RIGID_MARGIN * lam_r)
    nnull = int(np.sum(np.abs(wk) <= zero))
    # a rounded stiffness gives its rigid modes small eigenvalues of either sign: that is rigid-body energy (reported
    # from the Rayleigh quotients); indefinite is a larger negative one, or more of them than rigid modes
    negative = float(wk[0]) if wk[0] < -zero else None
    flex = wk[nrigid:] if nrigid < len(wk) else np.zeros(0)
    cond = float(ktop / flex[0]) if len(flex) and flex[0] > 0 else None    # None: K singular on its flexible part
    facts.update(mass_rank=len(wm) - null_m, mass_null=null_m, mass_zero_diagonal=zero_diag, stiffness_null=nnull,
                 stiffness_condition=cond)
    if null_m > zero_diag:
        findings.append(Finding("system", "M is singular beyond its zero diagonal: rank %d of %d, %d null directions of "
                                "which %d are zero-diagonal dofs" % (len(wm) - null_m, len(wm), null_m, zero_diag),
                                "massless motions (lumped masses without rotary inertia, offsets); the verification "
                                "condenses M's whole null space", "nothing to do if intended", "note"))
    if negative is not None:
        findings.append(Finding("system", "K is indefinite: smallest eigenvalue %.3e (%.1e of the largest)"
                                % (negative, negative / ktop), "a reduction fails at the factorization (negative pivot)",
                                "check the export: signs, units, a constraint eliminated wrongly", refused=True))
    elif nnull != nrigid:
        findings.append(Finding("system", "K has %d near-zero eigenvalues (null pivots of a factorization) but the "
                                "geometry gives %d rigid-body and mechanism modes" % (nnull, nrigid),
                                "more: an undeclared mechanism, refused by the held-dof factorization; fewer: a support "
                                "K holds that the scene does not declare, refused by the rigid check",
                                "declare the supports (constraints, springs, a joint to ground) or fix the model",
                                refused=True))
    # the verification's modes: below 3 x the band's top, from K + s M (s > 0 keeps it definite on the rigid modes)
    s = (2 * np.pi * band[1]) ** 2 * 1e-3
    try:
        mu = sl.eigh(M, K + s * M, eigvals_only=True)
        lam = 1.0 / mu[mu > 1e-14 * max(mu.max(), 1e-300)] - s
        # the geometric rigid modes are the nrigid lowest (their computed values carry the shift's round-off), and
        # any further null pivot is an undeclared mechanism, not a flexible mode
        first = np.sort(lam)[max(nrigid, nnull):]
        need = int(np.sum(first <= (2 * np.pi * 3 * band[1]) ** 2))
        facts.update(verification_modes=need, first_flexible_hz=float(np.sqrt(first.min()) / (2 * np.pi))
                     if len(first) else None)
    except (np.linalg.LinAlgError, ValueError):
        facts.update(verification_modes=None, first_flexible_hz=None)
