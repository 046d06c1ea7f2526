/*
  The reference check without a factorization of its own: the truth at a check frequency w solved iteratively with
  the reference as the preconditioner. The reference is an approximate inverse of Z(w) = K_S - w^2 M_S + i B(w)
  (B: Rayleigh and structural damping, none undamped), on the flexible subspace (the rigid part is exact, added
  as in the direct check):

    R(w) = Phi D(w) Phi^T + s(w) (K+ - Phi Lambda^-1 Phi^T),   D_k = 1 / (omega_k^2 - w^2 + i (w alpha + h omega_k^2)),

  h = g + w beta, s = 1 / (1 + i h): the computed modes Phi (M-orthonormal) with their damping, and the static residual
  of the modes not computed (K+ the reduction's own factor, or the solver the reference's eigensolve used at a
  midpoint). Iterating X_{k+1} = X_k + R (P^T G - Z X_k), with the residual formed from the exact full-order operator
  (K_S X accumulated in double-double: K_S X is a small difference of large terms), converges to the truth
  P Z^-1 P^T G: on the computed modes I - R Z vanishes to the eigensolve's tolerance, on a mode not computed it is
  (w^2 - i w alpha) / (omega^2 (1 + i h)), at most (w / omega)^2 <= (1 / cover)^2 in size. A mode the reference MISSED
  below w makes it grow, one just above w makes it crawl: every step's correction must be at most
  KF_REFINED_CONTRACTION of the one before, else the point falls back to the direct solves (direct_check.c), which
  then find the reference wrong (exit 3). Converged, the last correction and the contraction seen bound the error
  left in the last iterate (KFRefinedIterate): it must be below KF_REFINED_STEP_RTOL of the solution, and that
  iterate's own backward error below the direct check's.

  The first step, X_1 = R P^T G, needs K+ P^T G, which the point's moments left (src/reducer/full_moments.c: their
  first solve, or V Kr^-1 Gr from the Krylov basis at an angle of interest): no block K+ for it.

  All check frequencies (and the real and imaginary halves) of a point go through K+ as one block: a hand-written
  block iteration, since PETSc's KSP with a shell preconditioner solves one column at a time, each a single-vector
  pass through the factor, where one block pass costs a fraction of its columns' one by one (the eigensolve's block
  purification: benchmarks/proof_cost/README.md). K+ is applied without the solver's own refinement (the iteration
  refines against K_S itself). The frequencies are chosen from this point's own resonances (no factorization to share
  between points), and the backward error is taken against a lower bound of ||Z||_F (never too lenient).
*/
#include <kryflex/reducerimpl.h>
#include <kryflex/flexsolverimpl.h>

#define KF_REFINED_STEP_RTOL  1e-12 /* the error left against the solution, Frobenius, per frequency */
#define KF_REFINED_CONTRACTION 0.5  /* the largest ratio of successive corrections taken as convergence */
#define KF_REFINED_Q_SAFETY   10.0 /* the contraction the error left is estimated with: this multiple of the largest
                                      ratio of successive corrections seen, at most KF_REFINED_CONTRACTION */
#define KF_REFINED_MAX_STEPS  40

typedef struct {
  KFSystem               sys;
  KFFlexSolver           solver;
  const KFFullReference *ref;
  KFDamping              d;
  PetscBool              cplx;   /* damped: the real and imaginary halves */
  PetscInt               npts, a, nca, ncol, nev; /* nca = npts a columns per half; ncol = all; nev = V's columns */
  const PetscReal       *w;
  Mat                    Gp;     /* P^T G, e x a */
  Mat                    kg;     /* K+ P^T G, e x a, left by the moments: the first step's K+ (NULL: solved) */
  const PetscBool       *done;   /* per frequency: certified, its columns of X final (KFRefinedIterate's) */
  PetscInt              *pos;    /* ncol: a column's place among those of the frequencies not done, -1 if done */
} KFRefined;

/* column c of X: its frequency */
static inline PetscInt KFRefinedFreq(const KFRefined *c, PetscInt col)
{
  return (col % c->nca) / c->a;
}

/* the places of the columns still iterated (c->pos) and their count: a frequency certified is left as it was
   certified, its columns out of the products and the block K+ that the others still need */
static PetscInt KFRefinedActive(const KFRefined *c)
{
  PetscInt n = 0;

  for (PetscInt col = 0; col < c->ncol; col++) c->pos[col] = c->done[KFRefinedFreq(c, col)] ? -1 : n++;
  return n;
}

/* S = the columns of A still iterated (nact of them, in order), or A itself (a reference) when every column is */
static PetscErrorCode KFRefinedPick(const KFRefined *c, PetscInt nact, Mat A, Mat *S)
{
  const PetscScalar *a;
  PetscScalar       *s;
  PetscInt           nl, N, lda, lds;

  PetscFunctionBegin;
  if (nact == c->ncol) {
    PetscCall(PetscObjectReference((PetscObject)A));
    *S = A;
    PetscFunctionReturn(0);
  }
  PetscCall(MatGetLocalSize(A, &nl, NULL));
  PetscCall(MatGetSize(A, &N, NULL));
  PetscCall(KFDenseCreateUninitialized(PetscObjectComm((PetscObject)A), nl, N, nact, S));
  PetscCall(MatDenseGetLDA(A, &lda));
  PetscCall(MatDenseGetLDA(*S, &lds));
  PetscCall(MatDenseGetArrayRead(A, &a));
  PetscCall(MatDenseGetArrayWrite(*S, &s));
  for (PetscInt col = 0; col < c->ncol; col++)
    if (c->pos[col] >= 0) PetscCall(PetscArraycpy(s + c->pos[col] * lds, a + col * lda, nl));
  PetscCall(MatDenseRestoreArrayWrite(*S, &s));
  PetscCall(MatDenseRestoreArrayRead(A, &a));
  PetscFunctionReturn(0);
}

/* A = S in the columns still iterated, zero in the others (S from KFRefinedPick's layout; nothing when S is A) */
static PetscErrorCode KFRefinedPut(const KFRefined *c, Mat S, Mat A)
{
  const PetscScalar *s;
  PetscScalar       *a;
  PetscInt           nl, lda, lds;

  PetscFunctionBegin;
  if (S == A) PetscFunctionReturn(0);
  PetscCall(MatGetLocalSize(A, &nl, NULL));
  PetscCall(MatDenseGetLDA(A, &lda));
  PetscCall(MatDenseGetLDA(S, &lds));
  PetscCall(MatDenseGetArrayRead(S, &s));
  PetscCall(MatDenseGetArrayWrite(A, &a));
  for (PetscInt col = 0; col < c->ncol; col++) {
    if (c->pos[col] >= 0) PetscCall(PetscArraycpy(a + col * lda, s + c->pos[col] * lds, nl));
    else PetscCall(PetscArrayzero(a + col * lda, nl));
  }
  PetscCall(MatDenseRestoreArrayWrite(A, &a));
  PetscCall(MatDenseRestoreArrayRead(S, &s));
  PetscFunctionReturn(0);
}

/* Y = S (e x a) in every frequency's real columns, the imaginary ones zero: the residual of X = 0 (S = P^T G), and
   K+ of it (S = K+ P^T G) */
static PetscErrorCode KFRefinedFill(const KFRefined *c, Mat S, Mat Y)
{
  const PetscScalar *g;
  PetscScalar       *y;
  PetscInt           nl, ldg, ldy;

  PetscFunctionBegin;
  PetscCall(MatGetLocalSize(Y, &nl, NULL));
  PetscCall(MatDenseGetLDA(S, &ldg));
  PetscCall(MatDenseGetLDA(Y, &ldy));
  PetscCall(MatDenseGetArrayRead(S, &g));
  PetscCall(MatDenseGetArrayWrite(Y, &y));
  for (PetscInt col = 0; col < c->ncol; col++)
    for (PetscInt i = 0; i < nl; i++) y[i + col * ldy] = col < c->nca ? g[i + (col % c->a) * ldg] : 0;
  PetscCall(MatDenseRestoreArrayWrite(Y, &y));
  PetscCall(MatDenseRestoreArrayRead(S, &g));
  PetscFunctionReturn(0);
}

/* the residual Rb = [P^T G; 0] - Z X, column block per frequency: Z = K (1 + i h) - w^2 M + i w alpha M */
static PetscErrorCode KFRefinedResidual(const KFRefined *c, Mat X, Mat Rb)
{
  Mat                KX, MX, Xa;
  const PetscScalar *kx, *mx, *g;
  PetscScalar       *rb;
  PetscInt           nl, ldk, ldm, ldg, ldr;

  PetscFunctionBegin;
  PetscCall(KFRefinedPick(c, KFRefinedActive(c), X, &Xa)); /* the products of the columns still iterated */
  PetscCall(KFMatMultExtended(c->sys->Ks, Xa, &KX));
  PetscCall(KFMatMultDense(c->sys->Ms, Xa, &MX));
  PetscCall(MatDestroy(&Xa));
  PetscCall(MatGetLocalSize(X, &nl, NULL));
  PetscCall(MatDenseGetLDA(KX, &ldk));
  PetscCall(MatDenseGetLDA(MX, &ldm));
  PetscCall(MatDenseGetLDA(c->Gp, &ldg));
  PetscCall(MatDenseGetLDA(Rb, &ldr));
  PetscCall(MatDenseGetArrayRead(KX, &kx));
  PetscCall(MatDenseGetArrayRead(MX, &mx));
  PetscCall(MatDenseGetArrayRead(c->Gp, &g));
  PetscCall(MatDenseGetArrayWrite(Rb, &rb));
  for (PetscInt col = 0; col < c->nca; col++) {
    const PetscInt  s = KFRefinedFreq(c, col), j = col % c->a, im = c->nca + col, pr = c->pos[col];
    const PetscInt  pi = c->cplx ? c->pos[im] : -1;
    const PetscReal w2 = c->w[s] * c->w[s], h = c->d.g + c->w[s] * c->d.beta, wa = c->w[s] * c->d.alpha;

    if (pr < 0) { /* certified: no residual needed, and a zero one adds nothing to the modal sums */
      PetscCall(PetscArrayzero(rb + col * ldr, nl));
      if (c->cplx) PetscCall(PetscArrayzero(rb + im * ldr, nl));
      continue;
    }
    for (PetscInt i = 0; i < nl; i++) {
      PetscReal re = g[i + j * ldg] - kx[i + pr * ldk] + w2 * mx[i + pr * ldm];

      if (c->cplx) {
        re += h * kx[i + pi * ldk] + wa * mx[i + pi * ldm];
        rb[i + im * ldr] = -kx[i + pi * ldk] + w2 * mx[i + pi * ldm] - h * kx[i + pr * ldk] - wa * mx[i + pr * ldm];
      }
      rb[i + col * ldr] = re;
    }
  }
  PetscCall(MatDenseRestoreArrayWrite(Rb, &rb));
  PetscCall(MatDenseRestoreArrayRead(c->Gp, &g));
  PetscCall(MatDenseRestoreArrayRead(MX, &mx));
  PetscCall(MatDenseRestoreArrayRead(KX, &kx));
  PetscCall(MatDestroy(&KX));
  PetscCall(MatDestroy(&MX));
  PetscFunctionReturn(0);
}

/* Y = R(w) Rb: one block K+ (every column at once), then the modal sums. With the static scale s = 1 / (1 + i h):
   Y = s K+ Rb + Phi [(D - s / omega^2) (Phi^T Rb)]. first: Rb is the residual of X = 0, whose K+ the moments left
   (c->kg) where they did */
static PetscErrorCode KFRefinedApply(const KFRefined *c, Mat Rb, PetscBool first, Mat Y)
{
  const KFFullReference *ref = c->ref;
  PetscReal             *q, *e;
  PetscScalar           *y;
  PetscInt               nl, ldy;
  const PetscInt         nact = KFRefinedActive(c);

  PetscFunctionBegin;
  if (first && c->kg) PetscCall(KFRefinedFill(c, c->kg, Y));
  else { /* K+ of the columns still iterated; a certified frequency's correction is zero */
    Mat Ra, Ya;

    PetscCall(KFRefinedPick(c, nact, Rb, &Ra));
    if (Ra == Rb) Ya = Y;
    else PetscCall(MatDuplicate(Ra, MAT_DO_NOT_COPY_VALUES, &Ya));
    PetscCall(KFFlexSolverApply(c->solver, Ra, Ya));
    PetscCall(KFRefinedPut(c, Ya, Y));
    if (Ya != Y) PetscCall(MatDestroy(&Ya));
    PetscCall(MatDestroy(&Ra));
  }
  PetscCall(PetscMalloc2(c->nev * c->ncol, &q, c->nev * c->ncol, &e));
  PetscCall(KFMatTransposeMatMultGather(ref->V, Rb, q)); /* nev x ncol */
  PetscCall(PetscArrayzero(e, c->nev * c->ncol));
  PetscCall(MatGetLocalSize(Y, &nl, NULL));
  PetscCall(MatDenseGetLDA(Y, &ldy));
  PetscCall(MatDenseGetArray(Y, &y));
  for (PetscInt col = 0; col < c->nca; col++) {
    const PetscInt  s = KFRefinedFreq(c, col), im = c->nca + col;
    const PetscReal w = c->w[s], h = c->cplx ? c->d.g + w * c->d.beta : 0, den = 1 + h * h, sr = 1 / den, si = -h / den;

    if (c->pos[col] < 0) continue; /* certified: no correction (e stays zero, Y's columns are) */
    if (c->cplx) /* s K+ Rb, column by column */
      for (PetscInt i = 0; i < nl; i++) {
        const PetscReal yr = y[i + col * ldy], yi = y[i + im * ldy];

        y[i + col * ldy] = sr * yr - si * yi;
        y[i + im * ldy]  = sr * yi + si * yr;
      }
    for (PetscInt k = 0; k < ref->n; k++) {
      const PetscReal o2 = ref->w2[k], dr = o2 - w * w, di = c->cplx ? w * c->d.alpha + h * o2 : 0, dd = dr * dr + di * di;
      const PetscReal fr = dr / dd - sr / o2, fi = -di / dd - si / o2; /* D_k - s / omega_k^2 */
      const PetscReal qr = q[k + col * c->nev], qi = c->cplx ? q[k + im * c->nev] : 0;

      e[k + col * c->nev] = fr * qr - fi * qi;
      if (c->cplx) e[k + im * c->nev] = fr * qi + fi * qr;
    }
  }
  PetscCall(MatDenseRestoreArray(Y, &y));
  PetscCall(KFDenseMultSmall(ref->V, c->nev, c->ncol, e, 1.0, Y));
  PetscCall(PetscFree2(q, e));
  PetscFunctionReturn(0);
}

/* per frequency: the Frobenius norms of the columns of X (both halves) squared, summed into nrm[npts] */
static PetscErrorCode KFRefinedNorms(const KFRefined *c, Mat X, PetscReal nrm[])
{
  PetscReal *cn;

  PetscFunctionBegin;
  PetscCall(PetscMalloc1(c->ncol, &cn));
  PetscCall(MatGetColumnNorms(X, NORM_2, cn));
  PetscCall(PetscArrayzero(nrm, c->npts));
  for (PetscInt col = 0; col < c->ncol; col++) nrm[KFRefinedFreq(c, col)] += cn[col] * cn[col];
  for (PetscInt s = 0; s < c->npts; s++) nrm[s] = PetscSqrtReal(nrm[s]);
  PetscCall(PetscFree(cn));
  PetscFunctionReturn(0);
}

/* a lower bound of ||Z(w_s)||_F for each s, from ||K||_F and ||M||_F alone (the exact norm needs K - w^2 M formed,
   a matrix copy per frequency): |x| ||K|| - |y| ||M|| <= ||x K + y M||, for the real part K - w^2 M and the imaginary
   part h K + w alpha M. A lower bound of the norm makes the backward error below an upper bound: never too lenient. */
static PetscErrorCode KFRefinedOperatorNorms(const KFRefined *c, PetscReal nz[])
{
  PetscReal nk, nm;

  PetscFunctionBegin;
  PetscCall(MatNorm(c->sys->Ks, NORM_FROBENIUS, &nk));
  PetscCall(MatNorm(c->sys->Ms, NORM_FROBENIUS, &nm));
  for (PetscInt s = 0; s < c->npts; s++) {
    const PetscReal w = c->w[s], h = c->cplx ? c->d.g + w * c->d.beta : 0, wa = c->cplx ? w * c->d.alpha : 0;
    const PetscReal re = PetscAbsReal(nk - w * w * nm), im = PetscAbsReal(PetscAbsReal(h) * nk - PetscAbsReal(wa) * nm);

    nz[s] = PetscSqrtReal(re * re + im * im);
  }
  PetscFunctionReturn(0);
}

/* The iteration. X (e x ncol) in: zero; out: the truth's flexible part. A frequency is done when the correction that
   made X bounds the error left in X below KF_REFINED_STEP_RTOL of it and X's own residual gives a backward error at
   most KF_CHECK_RESIDUAL: the last iterate is certified by its residual, no correction computed only to be measured.
   The error left after a correction d of a contraction q is at most d q / (1 - q); q is taken as KF_REFINED_Q_SAFETY
   times the largest ratio of successive corrections seen (at least two corrections), at most KF_REFINED_CONTRACTION,
   where every step must contract anyway (q 1/2: the error left below d itself, as a correction below the tolerance
   at the rounding floor is taken). On the 57k-dof solid the ratios are steady at about 1e-3 per step: 4 corrections
   instead of 5 at the top check frequency. *steps: the corrections made; *ok: converged at every frequency (else X
   is not the truth); *berr: the worst backward error taken. */
static PetscErrorCode KFRefinedIterate(KFRefined *c, Mat X, PetscInt *steps, PetscBool *ok, PetscReal *berr)
{
  Mat        Rb, dX;
  PetscReal *nz, *nr, *nx, *nd, *prev, *qmax, ng;
  PetscBool *done, *near, *contracted;

  PetscFunctionBegin;
  PetscCall(PetscMalloc6(c->npts, &nz, c->npts, &nr, c->npts, &nx, c->npts, &nd, c->npts, &prev, c->npts, &qmax));
  PetscCall(PetscMalloc3(c->npts, &done, c->npts, &near, c->npts, &contracted));
  PetscCall(KFRefinedOperatorNorms(c, nz));
  PetscCall(MatNorm(c->Gp, NORM_FROBENIUS, &ng));
  PetscCall(MatDuplicate(X, MAT_DO_NOT_COPY_VALUES, &Rb));
  PetscCall(MatDuplicate(X, MAT_DO_NOT_COPY_VALUES, &dX));
  c->done = done;
  for (PetscInt s = 0; s < c->npts; s++) {
    prev[s] = PETSC_MAX_REAL;
    qmax[s] = 0;
    nx[s]   = 0;
    done[s] = near[s] = PETSC_FALSE;
  }
  *ok    = PETSC_FALSE;
  *berr  = 0;
  *steps = 0;
  while (PETSC_TRUE) {
    PetscBool all = PETSC_TRUE, stall = PETSC_FALSE;

    if (*steps == 0) PetscCall(KFRefinedFill(c, c->Gp, Rb)); /* X = 0 */
    else PetscCall(KFRefinedResidual(c, X, Rb));
    PetscCall(KFRefinedNorms(c, Rb, nr));
    for (PetscInt s = 0; s < c->npts; s++) {
      if (!done[s] && near[s]) {
        const PetscReal be = nr[s] / (nz[s] * nx[s] + ng);

        if (be <= KF_CHECK_RESIDUAL) {
          done[s] = PETSC_TRUE;
          *berr   = PetscMax(*berr, be);
        } else if (!contracted[s]) stall = PETSC_TRUE; /* small corrections that no longer contract, inexact X */
      }
      all = (PetscBool)(all && done[s]);
    }
    if (all) {
      *ok = PETSC_TRUE;
      break;
    }
    if (stall || *steps == KF_REFINED_MAX_STEPS) break;
    PetscCall(KFRefinedApply(c, Rb, (PetscBool)(*steps == 0), dX));
    PetscCall(MatAXPY(X, 1.0, dX, SAME_NONZERO_PATTERN));
    (*steps)++;
    PetscCall(KFRefinedNorms(c, dX, nd));
    PetscCall(KFRefinedNorms(c, X, nx));
    for (PetscInt s = 0; s < c->npts; s++) {
      PetscCall(PetscInfo(NULL, "reference check, step %" PetscInt_FMT ", %g Hz: correction %.2e of the solution, backward error of the iterate it corrected %.2e\n", *steps, (double)(c->w[s] / (2 * PETSC_PI)), (double)(nd[s] / nx[s]), (double)(nr[s] / (nz[s] * nx[s] + ng))));
      if (done[s]) continue;
      contracted[s] = (PetscBool)(nd[s] <= KF_REFINED_CONTRACTION * prev[s]); /* NaN: false */
      near[s] = (PetscBool)(nd[s] <= KF_REFINED_STEP_RTOL * nx[s]); /* q 1/2, or the rounding floor */
      if (*steps > 1 && contracted[s]) {
        const PetscReal q = PetscMin(KF_REFINED_CONTRACTION, KF_REFINED_Q_SAFETY * (qmax[s] = PetscMax(qmax[s], nd[s] / prev[s])));

        near[s] = (PetscBool)(near[s] || nd[s] * q / (1 - q) <= KF_REFINED_STEP_RTOL * nx[s]);
      }
      if (!near[s] && !contracted[s]) stall = PETSC_TRUE;
      prev[s] = nd[s];
    }
    if (stall) break;
  }
  PetscCall(MatDestroy(&Rb));
  PetscCall(MatDestroy(&dX));
  PetscCall(PetscFree6(nz, nr, nx, nd, prev, qmax));
  PetscCall(PetscFree3(done, near, contracted));
  PetscFunctionReturn(0);
}

/* the truth from the flexible part X: H X and the rigid part exact, -H Phi_r Phi_r^T G / (w^2 - i w alpha), into
   p->chk_T and p->chk_Ti (t x a per frequency) */
static PetscErrorCode KFRefinedTruth(const KFRefined *c, Mat X, PetscInt t, KFEvalPoint *p)
{
  const KFFullReference *ref = c->ref;
  const PetscInt         ta = t * c->a;
  PetscReal             *hx;
  Mat                    Ht;

  PetscFunctionBegin;
  PetscCall(KFSystemGetMatrices(c->sys, NULL, NULL, NULL, &Ht));
  PetscCall(PetscMalloc1(t * c->ncol, &hx));
  PetscCall(KFMatTransposeMatMultGather(Ht, X, hx)); /* t x ncol: column s a + j is frequency s, input j */
  PetscCall(PetscArraycpy(p->chk_T, hx, c->npts * ta));
  if (c->cplx) PetscCall(PetscArraycpy(p->chk_Ti, hx + c->npts * ta, c->npts * ta));
  else PetscCall(PetscArrayzero(p->chk_Ti, c->npts * ta));
  for (PetscInt s = 0; s < c->npts; s++) {
    const PetscReal w = c->w[s], al = c->cplx ? c->d.alpha : 0, den = w * w * w * w + w * w * al * al;
    const PetscReal cre = -w * w / den, cim = -w * al / den;

    for (PetscInt j = 0; j < c->a; j++)
      for (PetscInt q = 0; q < t; q++)
        for (PetscInt k = 0; k < ref->r; k++) {
          const PetscReal hg = ref->HPr[q + k * t] * ref->PrG[k + j * ref->r];

          p->chk_T[s * ta + q + j * t] += cre * hg;
          p->chk_Ti[s * ta + q + j * t] += cim * hg;
        }
  }
  PetscCall(PetscFree(hx));
  PetscFunctionReturn(0);
}

/* the point's check frequencies: KFCheckFrequencies_Private on its own resonances (one point: no factorization to
   share between points) */
static PetscErrorCode KFRefinedFrequencies(KFReducer r, const KFFullReference *ref, PetscInt npts, PetscReal w[])
{
  PetscReal *f;

  PetscFunctionBegin;
  PetscCall(PetscMalloc1(ref->n + 1, &f));
  for (PetscInt k = 0; k < ref->n; k++) f[k] = PetscSqrtReal(PetscMax(ref->w2[k], 0)) / (2 * PETSC_PI);
  PetscCall(KFCheckFrequencies_Private(r, ref->n, f, npts, w));
  PetscCall(PetscFree(f));
  PetscFunctionReturn(0);
}

/* One point's check, iterated while its flexible solver and its modes (p->ref.V, released here) are alive: on
   success p->chk_* hold the truth and p->chk_done is set; otherwise the point is left to the direct solves
   (KFReducerDirectChecks_Private), with a progress line. */
PetscErrorCode KFEvalPointRefinedCheck_Private(KFReducer r, KFSystem sys, KFFlexSolver solver, KFEvalPoint *p)
{
  KFRefined        c;
  KFFlexSolverPerf perf;
  PetscInt         t, steps = 0, nl, refine;
  PetscBool        viscous, ok = PETSC_FALSE;
  PetscReal        berr = 0;
  PetscLogDouble   t0, t1;
  Mat              Ms, G, X;
  char             label[128];
  MPI_Comm         comm = PetscObjectComm((PetscObject)r);

  PetscFunctionBegin;
  if (!p->ref.V || solver->shift != 0) { /* no modes kept, or no K+ (a shifted factor): the direct solves */
    PetscCall(MatDestroy(&p->ref.V));
    PetscCall(MatDestroy(&p->kg));
    PetscFunctionReturn(0);
  }
  PetscCall(PetscTime(&t0));
  PetscCall(PetscMemzero(&c, sizeof(c)));
  c.sys    = sys;
  c.solver = solver;
  c.ref    = &p->ref;
  c.kg     = p->kg;
  c.npts   = r->verify_check_points;
  PetscCall(KFCheckDampingModel_Private(r, &c.d, &viscous));
  PetscCheck(!viscous, comm, PETSC_ERR_PLIB, "the iterative reference check does not take the bodies' damping matrices");
  c.cplx = (PetscBool)(c.d.alpha != 0 || c.d.beta != 0 || c.d.g != 0);
  PetscCall(KFSceneGetInfo(r->scene, NULL, NULL, NULL, NULL, &c.a, &t));
  c.nca  = c.npts * c.a;
  c.ncol = (c.cplx ? 2 : 1) * c.nca;
  PetscCall(MatGetSize(p->ref.V, NULL, &c.nev));
  PetscCall(PetscCalloc3(c.npts, &p->chk_w, c.npts * t * c.a, &p->chk_T, c.npts * t * c.a, &p->chk_Ti));
  PetscCall(KFRefinedFrequencies(r, &p->ref, c.npts, p->chk_w));
  c.w = p->chk_w;
  PetscCall(KFSystemGetMatrices(sys, &Ms, NULL, &G, NULL));
  PetscCall(MatConvert(G, MATDENSE, MAT_INITIAL_MATRIX, &c.Gp));
  if (p->ref.r) PetscCall(KFProjectFlexible(sys, c.Gp, PETSC_TRUE)); /* P^T G: the loads self-equilibrated */
  PetscCall(MatGetLocalSize(Ms, &nl, NULL));
  PetscCall(KFDenseCreate(comm, nl, r->scene->nsys, c.ncol, &X));
  PetscCall(MatZeroEntries(X));
  PetscCall(PetscMalloc1(c.ncol, &c.pos));
  PetscCall(KFFlexSolverGetPerf(solver, &perf)); /* the verification's solves are not the reduction's */
  refine         = solver->refine;
  solver->refine = 0; /* the iteration is itself a refinement against K_S: the solver's own would be wasted solves */
  PetscCall(KFRefinedIterate(&c, X, &steps, &ok, &berr));
  solver->refine = refine;
  PetscCall(KFFlexSolverSetPerf_Private(solver, &perf));
  PetscCall(KFReducerConfigPlace_Private(r->scene->nrevolute, p->angles, label, sizeof(label)));
  if (ok) {
    PetscCall(KFRefinedTruth(&c, X, t, p));
    PetscCall(KFCheckRigidEnergy_Private(r, sys, p));
    p->nchk     = c.npts;
    p->chk_done = PETSC_TRUE;
    r->verify_check_iter_points++;
    r->verify_check_iter_steps += steps;
    r->verify_check_iter_steps_max = PetscMax(r->verify_check_iter_steps_max, steps);
    r->verify_check_iter_residual = PetscMax(berr, r->verify_check_iter_residual);
  } else {
    PetscCall(PetscFree3(p->chk_w, p->chk_T, p->chk_Ti));
    r->verify_check_fallbacks++;
    PetscCall(KFProgress(comm, "reference check %s: the iteration from the reference did not contract in %" PetscInt_FMT " steps (a mode the reference lacks, or one near a check frequency): solved directly instead", label, steps));
  }
  PetscCall(MatDestroy(&X));
  PetscCall(PetscFree(c.pos));
  PetscCall(MatDestroy(&c.Gp));
  PetscCall(MatDestroy(&p->ref.V)); /* the modes served their one purpose */
  PetscCall(MatDestroy(&p->kg));
  PetscCall(PetscTime(&t1));
  r->verify_check_seconds += t1 - t0;
  if (ok) PetscCall(KFProgress(comm, "reference check %s: %" PetscInt_FMT " frequencies solved by %" PetscInt_FMT " steps from the reference (%" PetscInt_FMT " block K+, %s, no factorization), backward error %.1e, %.3g s", label, c.npts, steps, c.kg ? steps - 1 : steps, c.kg ? "the first step's from the moments" : "one per step", (double)berr, (double)(t1 - t0)));
  PetscFunctionReturn(0);
}
