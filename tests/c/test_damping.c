/* KFDampedModalFRF (src/damping/frf.c) against a complex Gaussian elimination written here, in modal coordinates
   (M = I, K = diag(lambda), two rigid modes): a random symmetric PSD viscous matrix, modal damping per band,
   Rayleigh, structural damping, and velocity/acceleration outputs; and the diagonal path against KFModalFRF. */
#include <complex.h>
#include "kftest.h"

static unsigned long long rng_state = 7046029254386353131ULL;
static PetscReal          Rand(void) /* uniform in [-1, 1], identical on every rank */
{
  rng_state ^= rng_state << 13;
  rng_state ^= rng_state >> 7;
  rng_state ^= rng_state << 17;
  return 2.0 * (PetscReal)(rng_state % 1000003ULL) / 1000003.0 - 1.0;
}

#define N  6
#define NA 2
#define NT 3

/* x = Z^-1 b, Z n x n complex (overwritten), Gaussian elimination with partial pivoting */
static void Solve(PetscInt n, double complex Z[N][N], double complex b[N])
{
  for (PetscInt k = 0; k < n; k++) {
    PetscInt p = k;
    for (PetscInt i = k + 1; i < n; i++)
      if (cabs(Z[i][k]) > cabs(Z[p][k])) p = i;
    for (PetscInt j = 0; j < n; j++) {
      double complex tmp = Z[k][j];
      Z[k][j]            = Z[p][j];
      Z[p][j]            = tmp;
    }
    double complex tb = b[k];
    b[k]              = b[p];
    b[p]              = tb;
    for (PetscInt i = k + 1; i < n; i++) {
      double complex f = Z[i][k] / Z[k][k];
      for (PetscInt j = k; j < n; j++) Z[i][j] -= f * Z[k][j];
      b[i] -= f * b[k];
    }
  }
  for (PetscInt k = n - 1; k >= 0; k--) {
    for (PetscInt j = k + 1; j < n; j++) b[k] -= Z[k][j] * b[j];
    b[k] /= Z[k][k];
  }
}

int main(int argc, char **argv)
{
  const PetscReal lambda[N] = {0, 0, 4.0, 39.0, 40.0, 900.0}, w[4] = {0.7, 2.1, 6.3, 31.0};
  const PetscInt  quantity[NT] = {KF_QUANTITY_DISPLACEMENT, KF_QUANTITY_VELOCITY, KF_QUANTITY_ACCELERATION};
  PetscReal       C[N * N], A[N * 3], G[N * NA], H[NT * N], Tre[4 * NT * NA], Tim[4 * NT * NA], Ure[4 * NT * NA], Uim[4 * NT * NA];
  KFDamping       d;
  PetscReal       err = 0, top = 0;

  PetscFunctionBeginUser;
  PetscCall(PetscInitialize(&argc, &argv, NULL, NULL));
  for (PetscInt i = 0; i < N * 3; i++) A[i] = Rand();
  for (PetscInt i = 0; i < N; i++)
    for (PetscInt j = 0; j < N; j++) {
      C[i + j * N] = 0;
      for (PetscInt k = 0; k < 3; k++) C[i + j * N] += 0.3 * A[i + k * N] * A[j + k * N];
    }
  for (PetscInt i = 0; i < N * NA; i++) G[i] = Rand();
  for (PetscInt i = 0; i < NT * N; i++) H[i] = Rand();
  PetscCall(PetscMemzero(&d, sizeof(d)));
  d.nbands     = 2;
  d.fmax_hz[0] = 1.0; /* lambda 4 and 39 (0.32, 0.99 Hz) */
  d.zeta[0]    = 0.02;
  d.fmax_hz[1] = 3.0; /* lambda 40 (1.007 Hz) and 900 (4.8 Hz: above the last band, its ratio) */
  d.zeta[1]    = 0.005;
  d.alpha      = 0.03;
  d.beta       = 1e-3;
  d.g          = 0.02;
  PetscCall(KFDampedModalFRF(N, lambda, NT, H, NA, G, &d, C, N, quantity, 1e-12, 4, w, Tre, Tim));
  for (PetscInt f = 0; f < 4; f++)
    for (PetscInt j = 0; j < NA; j++) {
      double complex Z[N][N], x[N];
      for (PetscInt r = 0; r < N; r++) {
        const PetscReal fr = PetscSqrtReal(lambda[r]) / (2 * PETSC_PI), z = lambda[r] > 0 ? (fr <= 1.0 ? 0.02 : 0.005) : 0;
        for (PetscInt c = 0; c < N; c++) Z[r][c] = I * w[f] * C[r + c * N];
        Z[r][r] += lambda[r] * (1 + I * d.g) - w[f] * w[f] + I * w[f] * (2 * z * PetscSqrtReal(lambda[r]) + d.alpha + d.beta * lambda[r]);
        x[r] = G[r + j * N];
      }
      Solve(N, Z, x);
      for (PetscInt i = 0; i < NT; i++) {
        double complex y = 0, s = i == 0 ? 1 : (i == 1 ? I * w[f] : -w[f] * w[f]);
        for (PetscInt r = 0; r < N; r++) y += H[i + r * NT] * x[r];
        y *= s;
        const PetscInt e = f * NT * NA + i + j * NT;
        err = PetscMax(err, cabs(y - (Tre[e] + I * Tim[e])));
        top = PetscMax(top, cabs(y));
      }
    }
  PetscCall(Check("coupled viscous + bands + Rayleigh + structural + v/a outputs vs complex elimination", err / top, 1e-12));

  /* no viscous matrix, uniform modal damping, displacements: the diagonal path is KFModalFRF */
  PetscCall(KFDampingSetUniform(&d, 0.01));
  PetscCall(KFDampedModalFRF(N, lambda, NT, H, NA, G, &d, NULL, 0, NULL, 1e-12, 4, w, Tre, Tim));
  PetscCall(KFModalFRF(N, lambda, NT, H, NA, G, 0.01, 1e-12, 4, w, Ure, Uim));
  err = top = 0;
  for (PetscInt e = 0; e < 4 * NT * NA; e++) {
    err = PetscMax(err, PetscHypotReal(Tre[e] - Ure[e], Tim[e] - Uim[e]));
    top = PetscMax(top, PetscHypotReal(Ure[e], Uim[e]));
  }
  PetscCall(Check("uniform modal damping, no viscous matrix: equals KFModalFRF", err / top, 1e-14));

  /* bad damping: a clear error, not a number */
  {
    PetscErrorCode ierr;
    d.alpha = -1;
    PetscCall(PetscPushErrorHandler(PetscReturnErrorHandler, NULL));
    ierr = KFDampedModalFRF(N, lambda, NT, H, NA, G, &d, NULL, 0, NULL, 1e-12, 4, w, Tre, Tim);
    PetscCall(PetscPopErrorHandler());
    PetscCall(CheckTrue("negative Rayleigh alpha refused (PETSC_ERR_ARG_OUTOFRANGE)", (PetscBool)(ierr == PETSC_ERR_ARG_OUTOFRANGE)));
  }
  PetscCall(PetscFinalize());
  return nfail ? 1 : 0;
}
