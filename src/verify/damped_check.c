/*
  The direct check under the damping in use. The complex system (K_S - w^2 M_S + i B) X = G with
  B = w (C_S + alpha M_S + beta K_S) + g K_S (the bodies' viscous matrices C_S = sum_b P_b^T C_b P_b, Rayleigh,
  structural) is solved in its real 2 x 2 block form (the Debian PETSc is real), by one MUMPS factorization per check
  frequency, refined twice against the block matrix. Without a rigid border it is written symmetric,
  [A B; B -A] [Xr; -Xi] = [G; 0], and factored LDL^T (SYM=2: the unsymmetric form's LU took 8 GB at 57k dofs with
  Rayleigh damping); with the border (below) it is [A -B; B A] [Xr; Xi] = [G; 0] and an LU: the bordered symmetric
  form, a saddle point with a zero diagonal block, factored wrongly on 2 ranks.

  Modal ratios are the one damping defined by the modes themselves: their equivalent viscous matrix is
  M Phi diag(2 zeta_k w_k) Phi^T M on the reference's own modes Phi, whose inverse update (Sherman-Morrison-Woodbury
  on exact eigenvectors) adds to the response exactly the reference's modal term. Truth and reference then differ by
  what they differ without the ratios, so the comparison is made with the ratios out on both sides
  (KFCheckDampingModel) and costs no extra solve when they are the only damping (the undamped direct solve).

  Without bodies' matrices the damping does not couple the rigid modes to the flexible ones (Phi_r^T M P = 0,
  K_S Phi_r = 0): the rigid part is exact, -H Phi_r Phi_r^T G / (w^2 - i w alpha), and the flexible part
  P X of the projected loads P^T G, as in the undamped check. With them (they may damp rigid motion and couple it),
  the whole system is solved with the model's stiffness P^T K_S P, the rounded K_S bordered by its rigid correction
  (KFRigidBorder): the geometric rigid modes are its exact null space, as in the reference and the reduced models.
*/
#include <kryflex/reducerimpl.h>

/* the damping the direct check solves: the model in use without its modal ratios */
PetscErrorCode KFCheckDampingModel_Private(KFReducer r, KFDamping *d, PetscBool *viscous)
{
  KFScene s = r->scene;

  PetscFunctionBegin;
  *d            = r->damping;
  d->nbands     = 1;
  d->fmax_hz[0] = PETSC_MAX_REAL;
  d->zeta[0]    = 0;
  *viscous      = PETSC_FALSE;
  for (PetscInt b = 0; b < s->nb; b++)
    if (s->bodies[b].C) *viscous = PETSC_TRUE;
  PetscFunctionReturn(0);
}

/* C_S = sum_b P_b^T C_b P_b (e x e, sparse), or NULL */
static PetscErrorCode KFSystemDampingMatrix(KFSystem sys, Mat *Cs)
{
  KFScene s = sys->scene;

  PetscFunctionBegin;
  *Cs = NULL;
  for (PetscInt b = 0; b < s->nb; b++) {
    Mat Cb;

    if (!s->bodies[b].C) continue;
    PetscCall(MatPtAP(s->bodies[b].C, sys->P[b], MAT_INITIAL_MATRIX, PETSC_DEFAULT, &Cb));
    if (!*Cs) *Cs = Cb;
    else {
      PetscCall(MatAXPY(*Cs, 1.0, Cb, DIFFERENT_NONZERO_PATTERN));
      PetscCall(MatDestroy(&Cb));
    }
  }
  PetscFunctionReturn(0);
}

/* The block form as one AIJ matrix (MatNest's layout: on each rank its rows of each block row in turn). Without a
   border, [A B; B -A] (symmetric; unknowns [Xr; -Xi]). With a border W (e x 2r) and E^-1 (2r x 2r),
   [A -B W 0; B A 0 W; W^T 0 -E^-1 0; 0 W^T 0 -E^-1] (unknowns [Xr; Xi; ...]): eliminating the border gives
   A + W E W^T in both diagonal blocks */
static PetscErrorCode KFBlockForm(Mat A, Mat B, Mat W, Mat Einv, Mat *S)
{
  Mat       mX, N, blocks[16] = {NULL}, Wt = NULL, mE = NULL;
  PetscInt  nb = W ? 4 : 2;

  PetscFunctionBegin;
  PetscCall(MatDuplicate(W ? B : A, MAT_COPY_VALUES, &mX));
  PetscCall(MatScale(mX, -1.0));
  blocks[0 * nb + 0] = A;
  blocks[0 * nb + 1] = W ? mX : B;
  blocks[1 * nb + 0] = B;
  blocks[1 * nb + 1] = W ? A : mX;
  if (W) {
    PetscCall(MatTranspose(W, MAT_INITIAL_MATRIX, &Wt));
    PetscCall(MatDuplicate(Einv, MAT_COPY_VALUES, &mE));
    PetscCall(MatScale(mE, -1.0));
    blocks[0 * nb + 2] = W;
    blocks[1 * nb + 3] = W;
    blocks[2 * nb + 0] = Wt;
    blocks[3 * nb + 1] = Wt;
    blocks[2 * nb + 2] = mE;
    blocks[3 * nb + 3] = mE;
  }
  PetscCall(MatCreateNest(PetscObjectComm((PetscObject)A), nb, NULL, nb, NULL, blocks, &N));
  PetscCall(MatConvert(N, MATAIJ, MAT_INITIAL_MATRIX, S));
  if (!W) PetscCall(MatSetOption(*S, MAT_SYMMETRIC, PETSC_TRUE));
  PetscCall(MatDestroy(&N));
  PetscCall(MatDestroy(&mX));
  PetscCall(MatDestroy(&Wt));
  PetscCall(MatDestroy(&mE));
  PetscFunctionReturn(0);
}

/* X (the block layout) <-> its real and imaginary halves (e x a each, dense), rank by rank: on each rank the block
   layout holds its rows of Xr, then of Xi, then (with a border) its rows of the border's unknowns, zero here */
static PetscErrorCode KFBlockSplit(Mat X, PetscBool join, Mat Xr, Mat Xi)
{
  PetscInt     nl, nb, a, ldx, ldr, ldi;
  PetscScalar *x, *xr, *xi;

  PetscFunctionBegin;
  PetscCall(MatGetLocalSize(Xr, &nl, NULL));
  PetscCall(MatGetSize(Xr, NULL, &a));
  PetscCall(MatGetLocalSize(X, &nb, NULL));
  PetscCheck(nb >= 2 * nl, PETSC_COMM_SELF, PETSC_ERR_PLIB, "damped check: block layout %" PetscInt_FMT " rows for %" PetscInt_FMT, nb, nl);
  if (join) PetscCall(MatZeroEntries(X));
  PetscCall(MatDenseGetLDA(X, &ldx));
  PetscCall(MatDenseGetLDA(Xr, &ldr));
  PetscCall(MatDenseGetLDA(Xi, &ldi));
  PetscCall(MatDenseGetArray(X, &x));
  PetscCall(MatDenseGetArray(Xr, &xr));
  PetscCall(MatDenseGetArray(Xi, &xi));
  for (PetscInt j = 0; j < a; j++)
    for (PetscInt i = 0; i < nl; i++) {
      if (join) {
        x[i + j * ldx]      = xr[i + j * ldr];
        x[nl + i + j * ldx] = xi[i + j * ldi];
      } else {
        xr[i + j * ldr] = x[i + j * ldx];
        xi[i + j * ldi] = x[nl + i + j * ldx];
      }
    }
  PetscCall(MatDenseRestoreArray(X, &x));
  PetscCall(MatDenseRestoreArray(Xr, &xr));
  PetscCall(MatDenseRestoreArray(Xi, &xi));
  PetscFunctionReturn(0);
}

/* one damped solve at w: X = (A + W E W^T + i B)^-1 Gd in the block form (W NULL: no border), refined twice; Xr, Xi
   (e x a) out */
static PetscErrorCode KFDampedSolve(Mat A, Mat B, Mat W, Mat Einv, Mat Gd, Mat Xr, Mat Xi)
{
  Mat           S, F, R, X, dX, Zero;
  MatFactorInfo info;
  IS            rp, cp;
  PetscInt      m, a;

  PetscFunctionBegin;
  PetscCall(KFBlockForm(A, B, W, Einv, &S));
  PetscCall(MatGetLocalSize(S, &m, NULL));
  PetscCall(MatGetSize(Gd, NULL, &a));
  PetscCall(MatCreateDense(PetscObjectComm((PetscObject)S), m, PETSC_DECIDE, PETSC_DETERMINE, a, NULL, &R));
  PetscCall(MatDuplicate(Gd, MAT_DO_NOT_COPY_VALUES, &Zero));
  PetscCall(MatZeroEntries(Zero));
  PetscCall(KFBlockSplit(R, PETSC_TRUE, Gd, Zero)); /* the right-hand side [G; 0] */
  PetscCall(MatGetOrdering(S, MATORDERINGNATURAL, &rp, &cp));
  PetscCall(MatFactorInfoInitialize(&info));
  if (W) {
    PetscCall(MatGetFactor(S, MATSOLVERMUMPS, MAT_FACTOR_LU, &F));
    PetscCall(MatLUFactorSymbolic(F, S, rp, cp, &info));
    PetscCall(MatLUFactorNumeric(F, S, &info));
  } else {
    PetscCall(MatGetFactor(S, MATSOLVERMUMPS, MAT_FACTOR_CHOLESKY, &F)); /* indefinite: MUMPS SYM=2 */
    PetscCall(MatCholeskyFactorSymbolic(F, S, rp, &info));
    PetscCall(MatCholeskyFactorNumeric(F, S, &info));
  }
  PetscCall(MatDuplicate(R, MAT_DO_NOT_COPY_VALUES, &X));
  PetscCall(MatMatSolve(F, R, X));
  for (PetscInt it = 0; it < 2; it++) { /* near the band's bottom A is nearly singular on the rigid modes */
    Mat SX;

    PetscCall(MatMatMult(S, X, MAT_INITIAL_MATRIX, PETSC_DEFAULT, &SX));
    PetscCall(MatAYPX(SX, -1.0, R, SAME_NONZERO_PATTERN));
    PetscCall(MatDuplicate(X, MAT_DO_NOT_COPY_VALUES, &dX));
    PetscCall(MatMatSolve(F, SX, dX));
    PetscCall(MatAXPY(X, 1.0, dX, SAME_NONZERO_PATTERN));
    PetscCall(MatDestroy(&dX));
    PetscCall(MatDestroy(&SX));
  }
  PetscCall(KFBlockSplit(X, PETSC_FALSE, Xr, Xi));
  if (!W) PetscCall(MatScale(Xi, -1.0)); /* the symmetric form's second unknown is -Xi */
  PetscCall(MatDestroy(&X));
  PetscCall(MatDestroy(&Zero));
  PetscCall(MatDestroy(&R));
  PetscCall(ISDestroy(&rp));
  PetscCall(ISDestroy(&cp));
  PetscCall(MatDestroy(&F));
  PetscCall(MatDestroy(&S));
  PetscFunctionReturn(0);
}

/* The model's stiffness P^T K_S P (P = I - Phi_r Phi_r^T M_S: the geometric rigid modes its exact null space) is
   K_S + W E W^T with W = [M Phi_r, K_S Phi_r] and E = [K_r -I; -I 0], K_r = Phi_r^T K_S Phi_r (K_S Phi_r in
   double-double: a small difference of large terms); E^-1 = [0 -I; -I -K_r]. W as AIJ (e x 2r, its columns and
   E^-1's rows on the first rank) */
static PetscErrorCode KFRigidBorder(KFSystem sys, Mat *W, Mat *Einv)
{
  Mat                Phi, MPhi, KPhi;
  PetscInt           r, nl, r0, r1, lc;
  PetscMPIInt        rank;
  PetscReal         *Kr;
  const PetscScalar *m, *k;
  PetscInt           ldm, ldk;
  MPI_Comm           comm = sys->scene->comm;

  PetscFunctionBegin;
  PetscCall(KFSystemGetRigidModes(sys, &Phi, NULL));
  PetscCall(MatGetSize(Phi, NULL, &r));
  PetscCall(MatMatMult(sys->Ms, Phi, MAT_INITIAL_MATRIX, PETSC_DEFAULT, &MPhi));
  PetscCall(KFMatMultExtended(sys->Ks, Phi, &KPhi));
  PetscCall(PetscMalloc1(r * r, &Kr));
  PetscCall(KFMatTransposeMatMultGather(Phi, KPhi, Kr));
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  lc = rank ? 0 : 2 * r;
  PetscCall(MatGetLocalSize(Phi, &nl, NULL));
  PetscCall(MatGetOwnershipRange(Phi, &r0, &r1));
  PetscCall(MatCreateAIJ(comm, nl, lc, PETSC_DETERMINE, 2 * r, rank ? 0 : 2 * r, NULL, 2 * r, NULL, W));
  PetscCall(MatDenseGetLDA(MPhi, &ldm));
  PetscCall(MatDenseGetLDA(KPhi, &ldk));
  PetscCall(MatDenseGetArrayRead(MPhi, &m));
  PetscCall(MatDenseGetArrayRead(KPhi, &k));
  for (PetscInt i = 0; i < nl; i++)
    for (PetscInt j = 0; j < r; j++) {
      PetscCall(MatSetValue(*W, r0 + i, j, m[i + j * ldm], INSERT_VALUES));
      PetscCall(MatSetValue(*W, r0 + i, r + j, k[i + j * ldk], INSERT_VALUES));
    }
  PetscCall(MatDenseRestoreArrayRead(MPhi, &m));
  PetscCall(MatDenseRestoreArrayRead(KPhi, &k));
  PetscCall(MatAssemblyBegin(*W, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(*W, MAT_FINAL_ASSEMBLY));
  PetscCall(MatCreateAIJ(comm, lc, lc, 2 * r, 2 * r, 2 * r, NULL, 0, NULL, Einv));
  if (!rank)
    for (PetscInt i = 0; i < r; i++) {
      PetscCall(MatSetValue(*Einv, i, r + i, -1.0, INSERT_VALUES));
      PetscCall(MatSetValue(*Einv, r + i, i, -1.0, INSERT_VALUES));
      for (PetscInt j = 0; j < r; j++) PetscCall(MatSetValue(*Einv, r + i, r + j, -Kr[i + j * r], INSERT_VALUES));
    }
  PetscCall(MatAssemblyBegin(*Einv, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(*Einv, MAT_FINAL_ASSEMBLY));
  PetscCall(PetscFree(Kr));
  PetscCall(MatDestroy(&MPhi));
  PetscCall(MatDestroy(&KPhi));
  PetscFunctionReturn(0);
}

/* the damped truth at the check frequencies p->chk_w: p->chk_T (real) and p->chk_Ti (imaginary parts), t x a each */
PetscErrorCode KFEvalPointDampedSolves_Private(KFReducer r, KFSystem sys, KFEvalPoint *p, const KFDamping *d, PetscBool viscous)
{
  PetscInt  a, t, ta;
  Mat       Ms, Ks, G, Ht, Cs, Gd, A, B, Xr, Xi, W = NULL, Einv = NULL;
  PetscBool project = (PetscBool)(!viscous && p->ref.r);

  PetscFunctionBegin;
  PetscCall(KFSceneGetInfo(r->scene, NULL, NULL, NULL, NULL, &a, &t));
  ta = t * a;
  PetscCall(KFSystemGetMatrices(sys, &Ms, &Ks, &G, &Ht));
  PetscCall(KFSystemDampingMatrix(sys, &Cs));
  PetscCall(MatConvert(G, MATDENSE, MAT_INITIAL_MATRIX, &Gd));
  if (project) PetscCall(KFProjectFlexible(sys, Gd, PETSC_TRUE)); /* P^T G */
  else if (p->ref.r) PetscCall(KFRigidBorder(sys, &W, &Einv));
  for (PetscInt s = 0; s < p->nchk; s++) {
    const PetscReal w = p->chk_w[s];

    PetscCall(MatDuplicate(Ks, MAT_COPY_VALUES, &A));
    PetscCall(MatAXPY(A, -w * w, Ms, DIFFERENT_NONZERO_PATTERN));
    PetscCall(MatDuplicate(Ks, MAT_COPY_VALUES, &B));
    PetscCall(MatScale(B, w * d->beta + d->g));
    PetscCall(MatAXPY(B, w * d->alpha, Ms, DIFFERENT_NONZERO_PATTERN));
    if (Cs) PetscCall(MatAXPY(B, w, Cs, DIFFERENT_NONZERO_PATTERN));
    PetscCall(MatDuplicate(Gd, MAT_DO_NOT_COPY_VALUES, &Xr));
    PetscCall(MatDuplicate(Gd, MAT_DO_NOT_COPY_VALUES, &Xi));
    PetscCall(KFDampedSolve(A, B, W, Einv, Gd, Xr, Xi));
    if (project) {
      PetscCall(KFProjectFlexible(sys, Xr, PETSC_FALSE));
      PetscCall(KFProjectFlexible(sys, Xi, PETSC_FALSE));
    }
    PetscCall(KFMatTransposeMatMultGather(Ht, Xr, &p->chk_T[s * ta]));
    PetscCall(KFMatTransposeMatMultGather(Ht, Xi, &p->chk_Ti[s * ta]));
    if (project) { /* the rigid part, exact: -H Phi_r Phi_r^T G / (w^2 - i w alpha) */
      const PetscReal den = w * w * w * w + w * w * d->alpha * d->alpha, cre = -w * w / den, cim = -w * d->alpha / den;

      for (PetscInt j = 0; j < a; j++)
        for (PetscInt q = 0; q < t; q++)
          for (PetscInt k = 0; k < p->ref.r; k++) {
            const PetscReal hg = p->ref.HPr[q + k * t] * p->ref.PrG[k + j * p->ref.r];

            p->chk_T[s * ta + q + j * t] += cre * hg;
            p->chk_Ti[s * ta + q + j * t] += cim * hg;
          }
    }
    PetscCall(MatDestroy(&Xr));
    PetscCall(MatDestroy(&Xi));
    PetscCall(MatDestroy(&A));
    PetscCall(MatDestroy(&B));
  }
  PetscCall(MatDestroy(&Gd));
  PetscCall(MatDestroy(&Cs));
  PetscCall(MatDestroy(&W));
  PetscCall(MatDestroy(&Einv));
  PetscFunctionReturn(0);
}
