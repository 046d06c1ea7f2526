/* Joint rotation R(alpha) = Rot(axis, alpha) R0 (Rodrigues). */
#include "dense_impl.h"

PetscErrorCode KFJointRotation(const PetscReal axis[3], const PetscReal R0[9], PetscReal alpha, PetscReal R[9])
{
  PetscReal k[3], len, c, s, C, Rot[9];

  PetscFunctionBegin;
  len = PetscSqrtReal(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
  PetscCheck(len > 0 && !PetscIsInfOrNanReal(len), PETSC_COMM_SELF, PETSC_ERR_ARG_WRONG, "KFJointRotation: the joint axis (%g, %g, %g) has no direction: give a nonzero axis vector in the parent's frame", (double)axis[0], (double)axis[1], (double)axis[2]);
  for (int i = 0; i < 3; i++) k[i] = axis[i] / len;
  c = PetscCosReal(alpha);
  s = PetscSinReal(alpha);
  C = 1 - c;
  /* Rot = c I + s [k]x + (1 - c) k k^T, column-major */
  Rot[0 + 3 * 0] = c + C * k[0] * k[0];
  Rot[1 + 3 * 0] = s * k[2] + C * k[1] * k[0];
  Rot[2 + 3 * 0] = -s * k[1] + C * k[2] * k[0];
  Rot[0 + 3 * 1] = -s * k[2] + C * k[0] * k[1];
  Rot[1 + 3 * 1] = c + C * k[1] * k[1];
  Rot[2 + 3 * 1] = s * k[0] + C * k[2] * k[1];
  Rot[0 + 3 * 2] = s * k[1] + C * k[0] * k[2];
  Rot[1 + 3 * 2] = -s * k[0] + C * k[1] * k[2];
  Rot[2 + 3 * 2] = c + C * k[2] * k[2];
  if (!R0) {
    for (int i = 0; i < 9; i++) R[i] = Rot[i];
    PetscFunctionReturn(0);
  }
  {
    PetscReal P[9]; /* R may alias R0 */
    for (int j = 0; j < 3; j++)
      for (int i = 0; i < 3; i++) P[i + 3 * j] = Rot[i + 0] * R0[0 + 3 * j] + Rot[i + 3] * R0[1 + 3 * j] + Rot[i + 6] * R0[2 + 3 * j];
    for (int i = 0; i < 9; i++) R[i] = P[i];
  }
  PetscFunctionReturn(0);
}

/* Two unit vectors spanning the plane perpendicular to the (unit) axis k: the rotation rows of a revolute
   joint. Any orthonormal pair gives the same constraint space; this one is well conditioned. */
void KFPerpendicularPair_Private(const PetscReal k[3], PetscReal e1[3], PetscReal e2[3])
{
  PetscReal c[3] = {0, 0, 0}, dot, len;
  int       imin = 0;

  for (int i = 1; i < 3; i++)
    if (PetscAbsReal(k[i]) < PetscAbsReal(k[imin])) imin = i;
  c[imin] = 1;
  dot     = k[imin];
  for (int i = 0; i < 3; i++) e1[i] = c[i] - dot * k[i];
  len = PetscSqrtReal(e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2]);
  for (int i = 0; i < 3; i++) e1[i] /= len;
  e2[0] = k[1] * e1[2] - k[2] * e1[1];
  e2[1] = k[2] * e1[0] - k[0] * e1[2];
  e2[2] = k[0] * e1[1] - k[1] * e1[0];
}
