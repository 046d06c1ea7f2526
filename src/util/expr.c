#include <kryflex_impl.h>

/* Adds c * x_idx to an expression, merging a repeated dof (zero coefficients are kept: P's pattern must not
   depend on the angle, so that later angles reuse the symbolic products). */
PetscErrorCode KFExprAdd(KFExpr *e, PetscInt idx, PetscReal c)
{
  PetscFunctionBegin;
  for (PetscInt k = 0; k < e->n; k++)
    if (e->idx[k] == idx) {
      e->c[k] += c;
      PetscFunctionReturn(0);
    }
  PetscCheck(e->n < KF_MAX_TERMS, PETSC_COMM_SELF, PETSC_ERR_SUP, "an interface dof depends on more than %d system dofs: joint chains through the same node are too deep", KF_MAX_TERMS);
  e->idx[e->n] = idx;
  e->c[e->n]   = c;
  e->n++;
  PetscFunctionReturn(0);
}

PetscErrorCode KFExprAXPY(KFExpr *y, PetscReal a, const KFExpr *x)
{
  PetscFunctionBegin;
  for (PetscInt k = 0; k < x->n; k++) PetscCall(KFExprAdd(y, x->idx[k], a * x->c[k]));
  PetscFunctionReturn(0);
}
