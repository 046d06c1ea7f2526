/* KFArraySkinnyTransposeMult (src/util/dense.c, internal: the test compiles that file in): out += A^T X over local
   rows for a tall A and a block X of a few columns, by the file's own kernel (at most 8 columns of X) or BLAS (more).
   Reference: each entry's sum in long double, computed here with plain loops. Shapes cover row counts that are not a
   multiple of the kernel's 4 rows or of the 2048-row chunk, column counts of A that leave a partial group of 4, odd
   column counts of X, and X past the kernel's width; leading dimensions larger than the row and column counts, with
   the padding checked untouched. The AVX2 kernel and the generic one must agree to rounding. Every rank runs the same
   serial data. */
#include "kftest.h"
#include "../../src/util/dense.c"

static unsigned long long rng_state = 88172645463325252ULL;
static PetscReal          Rand(void) /* uniform in [-1, 1] */
{
  rng_state ^= rng_state << 13;
  rng_state ^= rng_state >> 7;
  rng_state ^= rng_state << 17;
  return 2.0 * (PetscReal)(rng_state >> 11) / 9007199254740992.0 - 1.0;
}

/* the largest |out - ref| / (sum |a| |x|) over the entries, and whether the padding (rows nc..ldo-1) kept its value */
static PetscErrorCode Case(PetscInt nl, PetscInt nc, PetscInt p, PetscReal *err, PetscBool *pad_ok)
{
  const PetscInt lda = nl + 3, ldx = nl + 5, ldo = nc + 2;
  PetscReal     *a, *x, *out, *out0;

  PetscFunctionBegin;
  PetscCall(PetscMalloc4(lda * nc, &a, ldx * p, &x, ldo * p, &out, ldo * p, &out0));
  for (PetscInt i = 0; i < lda * nc; i++) a[i] = Rand();
  for (PetscInt i = 0; i < ldx * p; i++) x[i] = Rand();
  for (PetscInt i = 0; i < ldo * p; i++) out[i] = out0[i] = Rand(); /* accumulated into, not overwritten */
  PetscCall(KFArraySkinnyTransposeMult(nl, nc, a, lda, p, x, ldx, out, ldo));
  *err    = 0;
  *pad_ok = PETSC_TRUE;
  for (PetscInt q = 0; q < p; q++) {
    for (PetscInt j = 0; j < nc; j++) {
      long double s = out0[j + q * ldo], m = PetscAbsReal(out0[j + q * ldo]);

      for (PetscInt i = 0; i < nl; i++) {
        s += (long double)a[i + j * lda] * x[i + q * ldx];
        m += PetscAbsReal(a[i + j * lda] * x[i + q * ldx]);
      }
      *err = PetscMax(*err, (PetscReal)(fabsl((long double)out[j + q * ldo] - s) / m));
    }
    for (PetscInt j = nc; j < ldo; j++)
      if (out[j + q * ldo] != out0[j + q * ldo]) *pad_ok = PETSC_FALSE;
  }
  PetscCall(PetscFree4(a, x, out, out0));
  PetscFunctionReturn(0);
}

int main(int argc, char **argv)
{
  const PetscInt rows[] = {1, 3, 4, 2047, 4101}, cols[] = {1, 3, 4, 5, 9}, blocks[] = {1, 2, 3, 8, 9};
  PetscReal      worst = 0;
  PetscBool      pads = PETSC_TRUE;

  PetscCall(PetscInitialize(&argc, &argv, NULL, NULL));
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "skinny transposed products A^T X\n"));
  for (size_t r = 0; r < sizeof(rows) / sizeof(rows[0]); r++)
    for (size_t c = 0; c < sizeof(cols) / sizeof(cols[0]); c++)
      for (size_t b = 0; b < sizeof(blocks) / sizeof(blocks[0]); b++) {
        PetscReal err    = 0;
        PetscBool pad_ok = PETSC_FALSE;

        PetscCall(Case(rows[r], cols[c], blocks[b], &err, &pad_ok));
        worst = PetscMax(worst, err);
        pads  = (PetscBool)(pads && pad_ok);
      }
  PetscCall(Check("A^T X against long double sums, 125 shapes (max error / sum |a x|)", worst, 1e-14));
  PetscCall(CheckTrue("entries past the block's columns (leading-dimension padding) untouched", pads));
#if defined(KF_SKINNY_TN_OWN)
  { /* the kernel this CPU runs against the generic one (FMA or not: they agree to rounding, not to the bit) */
    const PetscInt nl = 5003, nc = 7, p = 3;
    PetscReal     *a, *x, *o1, *o2, diff = 0, scale = 0;

    PetscCall(PetscMalloc4(nl * nc, &a, nl * p, &x, nc * p, &o1, nc * p, &o2));
    for (PetscInt i = 0; i < nl * nc; i++) a[i] = Rand();
    for (PetscInt i = 0; i < nl * p; i++) x[i] = Rand();
    for (PetscInt i = 0; i < nc * p; i++) o1[i] = o2[i] = 0;
    KFSkinnyTNSelect()(nl, nc, a, nl, p, x, nl, o1, nc);
    KFSkinnyTNGeneric(nl, nc, a, nl, p, x, nl, o2, nc);
    for (PetscInt i = 0; i < nc * p; i++) {
      diff  = PetscMax(diff, PetscAbsReal(o1[i] - o2[i]));
      scale = PetscMax(scale, PetscAbsReal(o2[i]));
    }
    PetscCall(Check("this CPU's kernel against the generic one (max |difference| / max |entry|)", diff / scale, 1e-13));
    PetscCall(PetscFree4(a, x, o1, o2));
  }
#endif
  PetscCall(PetscFinalize());
  return nfail ? 1 : 0;
}
