/* The damped input chain of the Krylov basis (issue 12; the seed paper's second item of future work): the moments of
   the damped second-order system M x'' + C x' + K x = G u about s = 0 are matched by the span of
     x_0 = K+ G, x_1 = -K+ C x_0, x_k = -K+ (C x_{k-1} + M x_{k-2}).
   The raw recurrence loses rank like eq. (9); it is generated instead as the block Arnoldi process of its
   linearization L [u; v] = [-K+ (g C u + g^2 M v); u], whose blocks' u halves span the x_k (g: a frequency scale,
   so that consecutive blocks have comparable norms; it does not change the spans). Both halves are orthonormalized
   together in the M-inner product (<z, z'> = u^T M u' + v^T M v'), twice, with the columns whose norm drops below
   tol deflated. C = sum_b P_b^T C_b P_b + alpha M + beta K is applied body by body, never assembled. */
#include <kryflex/krylovimpl.h>

/* Y = C X for the system's viscous damping (X, Y: e x p dense; Y created) */
static PetscErrorCode KFSystemApplyViscous(KFSystem sys, PetscReal alpha, PetscReal beta, Mat X, Mat *Y)
{
  KFScene s = sys->scene;

  PetscFunctionBegin;
  PetscCall(MatDuplicate(X, MAT_DO_NOT_COPY_VALUES, Y));
  PetscCall(MatZeroEntries(*Y));
  for (PetscInt b = 0; b < s->nb; b++) {
    Mat Xb, CXb, T;

    if (!s->bodies[b].C) continue;
    PetscCall(MatMatMult(sys->P[b], X, MAT_INITIAL_MATRIX, PETSC_DEFAULT, &Xb));
    PetscCall(MatMatMult(s->bodies[b].C, Xb, MAT_INITIAL_MATRIX, PETSC_DEFAULT, &CXb));
    PetscCall(MatTransposeMatMult(sys->P[b], CXb, MAT_INITIAL_MATRIX, PETSC_DEFAULT, &T));
    PetscCall(MatAXPY(*Y, 1.0, T, SAME_NONZERO_PATTERN));
    PetscCall(MatDestroy(&T));
    PetscCall(MatDestroy(&CXb));
    PetscCall(MatDestroy(&Xb));
  }
  if (alpha != 0 || beta != 0) {
    Mat T;
    PetscCall(MatMatMult(sys->Ms, X, MAT_INITIAL_MATRIX, PETSC_DEFAULT, &T));
    PetscCall(MatAXPY(*Y, alpha, T, SAME_NONZERO_PATTERN));
    PetscCall(MatDestroy(&T));
    PetscCall(MatMatMult(sys->Ks, X, MAT_INITIAL_MATRIX, PETSC_DEFAULT, &T));
    PetscCall(MatAXPY(*Y, beta, T, SAME_NONZERO_PATTERN));
    PetscCall(MatDestroy(&T));
  }
  PetscFunctionReturn(0);
}

/* x <- x - Phi Phi^T M x: the chain stays on the flexible subspace, as the undamped blocks do */
static PetscErrorCode KFDampedRemoveRigid(KFSystem sys, Vec x)
{
  Vec Mx, c, Pc;

  PetscFunctionBegin;
  PetscCall(MatCreateVecs(sys->Phi, &c, &Pc));
  PetscCall(VecDuplicate(x, &Mx));
  PetscCall(MatMult(sys->Ms, x, Mx));
  PetscCall(MatMultTranspose(sys->Phi, Mx, c));
  PetscCall(MatMult(sys->Phi, c, Pc));
  PetscCall(VecAXPY(x, -1.0, Pc));
  PetscCall(VecDestroy(&Mx));
  PetscCall(VecDestroy(&c));
  PetscCall(VecDestroy(&Pc));
  PetscFunctionReturn(0);
}

/* sqrt(u^T M u + v^T M v) */
static PetscErrorCode KFDampedNorm(KFSystem sys, Vec u, Vec v, PetscReal *n)
{
  Vec         Mx;
  PetscScalar a, b;

  PetscFunctionBegin;
  PetscCall(VecDuplicate(u, &Mx));
  PetscCall(MatMult(sys->Ms, u, Mx));
  PetscCall(VecDot(u, Mx, &a));
  PetscCall(MatMult(sys->Ms, v, Mx));
  PetscCall(VecDot(v, Mx, &b));
  PetscCall(VecDestroy(&Mx));
  *n = PetscSqrtReal(PetscMax(PetscRealPart(a) + PetscRealPart(b), 0));
  PetscFunctionReturn(0);
}

PetscErrorCode KFDampedChainCreate_Private(KFFlexSolver solver, const KFKrylovDamping *d, PetscInt maxcols, KFDampedChain *ch)
{
  KFSystem sys = KFFlexSolverSystem_Private(solver);
  KFScene  s   = sys->scene;

  PetscFunctionBegin;
  PetscCall(PetscMemzero(ch, sizeof(*ch)));
  ch->d = *d;
  for (int h = 0; h < 2; h++) {
    PetscCall(BVCreate(s->comm, &ch->Z[h]));
    PetscCall(BVSetSizes(ch->Z[h], s->nsys_local, s->nsys, PetscMax(maxcols, 1)));
    PetscCall(BVSetMatrix(ch->Z[h], sys->Ms, PETSC_FALSE));
    PetscCall(BVSetFromOptions(ch->Z[h]));
    PetscCall(BVSetActiveColumns(ch->Z[h], 0, 0));
  }
  PetscFunctionReturn(0);
}

PetscErrorCode KFDampedChainDestroy_Private(KFDampedChain *ch)
{
  PetscFunctionBegin;
  PetscCall(BVDestroy(&ch->Z[0]));
  PetscCall(BVDestroy(&ch->Z[1]));
  PetscFunctionReturn(0);
}

/* the next block of the chain: the first from B (the inputs: z = [K+ B; 0]), later ones L applied to the last
   orthonormalized block; U (e x p', p' >= 0 columns kept, NULL when none) receives its u halves */
PetscErrorCode KFDampedChainNext_Private(KFFlexSolver solver, KFDampedChain *ch, Mat B, PetscReal tol, Mat *U)
{
  KFSystem  sys = KFFlexSolverSystem_Private(solver);
  Mat       Wu, Wv = NULL;
  PetscInt  p, k = ch->k, k0 = ch->k;
  PetscReal g = ch->d.gamma;
  Vec       u, v;
  PetscScalar *h, *h2;

  PetscFunctionBegin;
  *U = NULL;
  if (!ch->nblocks) {
    PetscCall(MatDuplicate(B, MAT_DO_NOT_COPY_VALUES, &Wu));
    PetscCall(KFFlexSolverApply(solver, B, Wu));
  } else {
    Mat Ul, Vl, CU, MV, R;
    /* the last block's halves */
    PetscCall(BVSetActiveColumns(ch->Z[0], ch->last, ch->k));
    PetscCall(BVSetActiveColumns(ch->Z[1], ch->last, ch->k));
    PetscCall(BVGetMat(ch->Z[0], &R));
    PetscCall(MatDuplicate(R, MAT_COPY_VALUES, &Ul));
    PetscCall(BVRestoreMat(ch->Z[0], &R));
    PetscCall(BVGetMat(ch->Z[1], &R));
    PetscCall(MatDuplicate(R, MAT_COPY_VALUES, &Vl));
    PetscCall(BVRestoreMat(ch->Z[1], &R));
    PetscCall(KFSystemApplyViscous(sys, ch->d.alpha, ch->d.beta, Ul, &CU));
    PetscCall(MatMatMult(sys->Ms, Vl, MAT_INITIAL_MATRIX, PETSC_DEFAULT, &MV));
    PetscCall(MatScale(CU, -g));
    PetscCall(MatAXPY(CU, -g * g, MV, SAME_NONZERO_PATTERN));
    PetscCall(MatDuplicate(Ul, MAT_DO_NOT_COPY_VALUES, &Wu));
    PetscCall(KFFlexSolverApply(solver, CU, Wu));
    Wv = Ul;
    PetscCall(MatDestroy(&CU));
    PetscCall(MatDestroy(&MV));
    PetscCall(MatDestroy(&Vl));
  }
  PetscCall(MatGetSize(Wu, NULL, &p));
  PetscCall(MatCreateVecs(sys->Ms, &u, NULL));
  PetscCall(VecDuplicate(u, &v));
  PetscCall(PetscMalloc2(PetscMax(k + p, 1), &h, PetscMax(k + p, 1), &h2));
  for (PetscInt j = 0; j < p; j++) {
    PetscReal n0, n;

    PetscCall(MatGetColumnVector(Wu, u, j));
    if (Wv) PetscCall(MatGetColumnVector(Wv, v, j));
    else PetscCall(VecSet(v, 0.0));
    PetscCall(KFDampedRemoveRigid(sys, u));
    PetscCall(KFDampedRemoveRigid(sys, v));
    PetscCall(KFDampedNorm(sys, u, v, &n0));
    for (int pass = 0; pass < 2 && k > 0 && n0 > 0; pass++) { /* classical Gram-Schmidt, twice */
      PetscCall(BVSetActiveColumns(ch->Z[0], 0, k));
      PetscCall(BVSetActiveColumns(ch->Z[1], 0, k));
      PetscCall(BVDotVec(ch->Z[0], u, h));
      PetscCall(BVDotVec(ch->Z[1], v, h2));
      for (PetscInt i = 0; i < k; i++) h[i] += h2[i];
      PetscCall(BVMultVec(ch->Z[0], -1.0, 1.0, u, h));
      PetscCall(BVMultVec(ch->Z[1], -1.0, 1.0, v, h));
    }
    PetscCall(KFDampedNorm(sys, u, v, &n));
    if (n0 == 0 || n <= tol * n0) continue; /* dependent: deflated */
    PetscCall(VecScale(u, 1.0 / n));
    PetscCall(VecScale(v, 1.0 / n));
    PetscCall(BVInsertVec(ch->Z[0], k, u));
    PetscCall(BVInsertVec(ch->Z[1], k, v));
    k++;
  }
  PetscCall(PetscFree2(h, h2));
  PetscCall(VecDestroy(&u));
  PetscCall(VecDestroy(&v));
  PetscCall(MatDestroy(&Wu));
  PetscCall(MatDestroy(&Wv));
  ch->nblocks++;
  ch->last = k0;
  ch->k    = k;
  PetscCall(BVSetActiveColumns(ch->Z[0], 0, k));
  PetscCall(BVSetActiveColumns(ch->Z[1], 0, k));
  if (k > k0) {
    Mat R;
    PetscCall(BVSetActiveColumns(ch->Z[0], k0, k));
    PetscCall(BVGetMat(ch->Z[0], &R));
    PetscCall(MatDuplicate(R, MAT_COPY_VALUES, U));
    PetscCall(BVRestoreMat(ch->Z[0], &R));
    PetscCall(BVSetActiveColumns(ch->Z[0], 0, k));
  }
  PetscFunctionReturn(0);
}
