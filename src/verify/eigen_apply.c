/* What the verification's eigensolves with a flexible solver's factor share (src/verify/eigen.c, Krylov-Schur;
   src/verify/block_eigen.c, block Krylov): K+ applications with their residual sampled, modes M-normalized, and
   the count of massless dofs (the dense path condenses them) and whether M is singular (the block path starts
   differently then). */
#include <kryflex_impl.h>
#include <kryflex/flexsolverimpl.h> /* the solver's refinement steps, off for the unsampled applications */
#include "eigen_impl.h"

/* The shift-and-invert step x -> K+ (M x) with a flexible solver's factor: the eigensolve shares the reduction's
   factorization instead of making its own. K+ is M-self-adjoint on the flexible subspace and
   maps the rigid modes to zero, so with target 0 the rigid modes never come out and need no deflation space.
   The flexible solver measures the residual of every block it solves (an extended-precision K_S product) to decide
   its refinement; for an eigensolve's one-vector applications that product costs a fifth of the factor's solve. A
   factor whose solves need no refinement is accurate to rounding whatever the right-hand side, so the residual is
   sampled: the first application and every KF_EPS_CHECK_EVERY-th after it are checked (and refined if above
   -kf_refine_rtol), the others solved once; a sampled one that needed refinement turns the check on for every
   application left. The purification block (KFEPSPurifyBlock) is always checked, and the reference itself is
   checked against direct solves of the full system (src/verify/direct_check.c). */
#define KF_EPS_CHECK_EVERY 8

/* X = K+ B with the residual checked or not (KFFlexPCApply's sampling; the block eigensolve's blocks the same) */
PetscErrorCode KFFlexPCApplySampled(KFFlexPCCtx *ctx, Mat B, Mat X)
{
  KFFlexSolver solver = ctx->solver;
  PetscInt     refined, refine = solver->refine;
  PetscBool    check = (PetscBool)(ctx->check_all || ctx->applications % KF_EPS_CHECK_EVERY == 0);

  PetscFunctionBegin;
  refined = solver->perf.blocks_refined;
  if (!check) solver->refine = 0; /* one solve, no residual (KFFlexSolverApply checks only with refinement steps) */
  PetscCall(KFFlexSolverApply(solver, B, X));
  solver->refine = refine;
  if (check && solver->perf.blocks_refined > refined) ctx->check_all = PETSC_TRUE;
  ctx->checked += check;
  ctx->applications++;
  PetscFunctionReturn(0);
}

/* The columns of P scaled to unit M-norm, with one block product M P (a sparse product per column would read M once
   per mode) */
PetscErrorCode KFEPSNormalizeBlock(KFSystem sys, Mat P)
{
  Mat       MP;
  PetscInt  m;
  PetscReal *nrm;

  PetscFunctionBegin;
  PetscCall(MatGetSize(P, NULL, &m));
  PetscCall(KFMatMultDense(sys->Ms, P, &MP));
  PetscCall(PetscMalloc1(m, &nrm));
  for (PetscInt i = 0; i < m; i++) {
    Vec         p, q;
    PetscScalar dot;

    PetscCall(MatDenseGetColumnVecRead(P, i, &p));
    PetscCall(MatDenseGetColumnVecRead(MP, i, &q));
    PetscCall(VecDot(p, q, &dot));
    PetscCall(MatDenseRestoreColumnVecRead(MP, i, &q));
    PetscCall(MatDenseRestoreColumnVecRead(P, i, &p));
    nrm[i] = PetscSqrtReal(PetscRealPart(dot));
  }
  for (PetscInt i = 0; i < m; i++) {
    Vec p;

    PetscCall(MatDenseGetColumnVecWrite(P, i, &p));
    PetscCall(VecScale(p, 1.0 / nrm[i]));
    PetscCall(MatDenseRestoreColumnVecWrite(P, i, &p));
  }
  PetscCall(PetscFree(nrm));
  PetscCall(MatDestroy(&MP));
  PetscFunctionReturn(0);
}

/* System dofs whose row of M_S is zero (massless: rotations of a lumped-mass model): they carry infinite
   eigenvalues, which a dense generalized eigensolver cannot take (LAPACK sygv needs M positive definite) */
PetscErrorCode KFSystemMasslessCount(KFSystem sys, PetscInt *n0)
{
  Vec                v;
  const PetscScalar *x;
  PetscInt           nl, c = 0;

  PetscFunctionBegin;
  PetscCall(MatCreateVecs(sys->Ms, NULL, &v));
  PetscCall(MatGetRowMaxAbs(sys->Ms, v, NULL));
  PetscCall(VecGetLocalSize(v, &nl));
  PetscCall(VecGetArrayRead(v, &x));
  for (PetscInt i = 0; i < nl; i++) c += PetscAbsScalar(x[i]) == 0;
  PetscCall(VecRestoreArrayRead(v, &x));
  PetscCall(VecDestroy(&v));
  PetscCall(MPIU_Allreduce(&c, n0, 1, MPIU_INT, MPI_SUM, sys->scene->comm));
  PetscFunctionReturn(0);
}

/* a row of M_S with at most this many nonzeros throughout: lumped masses (at a node, offset from it, or moved onto an
   independent node with the rigid elements eliminated: one node's six dofs, twelve where a rigid element's mass spans
   two nodes), whose factor fills in little beyond its own blocks; consistent masses (81 per row on the hex8 solid) have
   more, and their factor would cost about what K's does */
#define KF_LUMPED_ROW_NNZ 12

/* Whether M_S is singular: a zero row (a massless dof), or, for a lumped mass (KF_LUMPED_ROW_NNZ), null pivots of its
   factor (KFSystemMassNullPivots). Offset masses and rigid elements eliminated into the
   independent nodes (M = T^T M T) leave M as singular as its massless rotations made it, yet with no zero diagonal.
   A mass with more couplings per row (consistent element masses) is taken as assembled: definite. */
PetscErrorCode KFSystemMassSingular(KFSystem sys, PetscBool *singular)
{
  PetscInt n0, rstart, rend, most = 0;

  PetscFunctionBegin;
  PetscCall(KFSystemMasslessCount(sys, &n0));
  *singular = (PetscBool)(n0 > 0);
  if (*singular) PetscFunctionReturn(0);
  PetscCall(MatGetOwnershipRange(sys->Ms, &rstart, &rend));
  for (PetscInt i = rstart; i < rend; i++) {
    PetscInt nz;

    PetscCall(MatGetRow(sys->Ms, i, &nz, NULL, NULL));
    most = PetscMax(most, nz);
    PetscCall(MatRestoreRow(sys->Ms, i, &nz, NULL, NULL));
  }
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &most, 1, MPIU_INT, MPI_MAX, sys->scene->comm));
  if (most <= KF_LUMPED_ROW_NNZ) {
    PetscInt nnull;

    PetscCall(KFSystemMassNullPivots(sys, &nnull));
    *singular = (PetscBool)(nnull > 0);
  }
  PetscFunctionReturn(0);
}

/* The null pivots of M_S's sparse LDL^T (MUMPS null-pivot detection, a pivot below KF_MASS_NULL_RTOL of the largest
   entry counting as a null direction): the dimension of M's null space without a dense eigensolve. M_S is scaled
   first to a unit diagonal, D^-1/2 M_S D^-1/2 (massless dofs left as they are), so that the threshold is relative to
   the masses a direction's own dofs carry, as in the dense test (KFMassEig): a light body is not a null space. */
PetscErrorCode KFSystemMassNullPivots(KFSystem sys, PetscInt *nnull)
{
  Mat           F, Md;
  Vec           d;
  MatFactorInfo info;
  IS            rp, cp;
  PetscInt      nullp, lo, hi;
  PetscScalar  *v;

  PetscFunctionBegin;
  PetscCall(MatDuplicate(sys->Ms, MAT_COPY_VALUES, &Md));
  PetscCall(MatCreateVecs(Md, &d, NULL));
  PetscCall(MatGetDiagonal(Md, d));
  PetscCall(VecGetOwnershipRange(d, &lo, &hi));
  PetscCall(VecGetArray(d, &v));
  for (PetscInt i = 0; i < hi - lo; i++) v[i] = PetscAbsScalar(v[i]) > 0 ? 1 / PetscSqrtReal(PetscAbsScalar(v[i])) : 1;
  PetscCall(VecRestoreArray(d, &v));
  PetscCall(MatDiagonalScale(Md, d, d));
  PetscCall(VecDestroy(&d));
  PetscCall(MatGetFactor(Md, MATSOLVERMUMPS, MAT_FACTOR_CHOLESKY, &F));
  PetscCall(MatMumpsSetIcntl(F, 24, 1));
  PetscCall(MatMumpsSetCntl(F, 3, KF_MASS_NULL_RTOL));
  PetscCall(MatGetOrdering(Md, MATORDERINGNATURAL, &rp, &cp));
  PetscCall(MatFactorInfoInitialize(&info));
  PetscCall(MatCholeskyFactorSymbolic(F, Md, rp, &info));
  PetscCall(MatCholeskyFactorNumeric(F, Md, &info));
  PetscCall(MatMumpsGetInfog(F, 28, &nullp));
  *nnull = nullp;
  PetscCall(ISDestroy(&rp));
  PetscCall(ISDestroy(&cp));
  PetscCall(MatDestroy(&F));
  PetscCall(MatDestroy(&Md));
  PetscFunctionReturn(0);
}
