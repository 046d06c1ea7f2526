/* Closed-form reassembly of a tree of bodies (eq. 20-24 without an SVD per angle). A revolute joint ties the child's
   interface rows to the parent's through the joint rotation only: A_p x_p = U(alpha) At x_c with A_p = diag(I3, E),
   At = diag(R0, E R0) and U = diag(Rot, E Rot E^T), Rot = k k^T + c (I - k k^T) + s [k]x (c, s: cos, sin alpha). Each
   body's coordinates are split once, in its own frame, into the rows it is tied by as a child (w), the rows its
   children are tied to (u, kept as coordinates) and the rest (z): phi_b = P^w w + P^u u + Z z, P = pinv of the stacked
   rows. A child's w is U^T of its parent's u, so phi_b = L_b(alpha) y_b with L_b affine in (c, s), and the body's
   share of M, K, C is a fixed combination of five matrices with the weights 1, c, s, s^2, c s, made here once (K in
   long double, as the SVD path forms it). The null space is the SVD path's; its basis is not orthonormal: the
   reassembled matrices are the SVD path's up to a congruence (same eigenvalues, same transfer function). */
#include "reassemble_impl.h"
#include <petscblaslapack.h>

#define KF_NTERM 5 /* weights 1, c, s, s^2, c s */

typedef struct {
  PetscInt     irev;   /* the revolute index of the joint whose child this body is; -1: a root or a fixed joint */
  PetscInt     cw, ru; /* rows tied as a child (0, 5 or 6); rows its children are tied to (its first ru coordinates) */
  PetscInt     l, nt;  /* local coordinates (the parent's u, then its own); terms (1 or KF_NTERM) */
  PetscInt    *idx;    /* l: the local coordinates' places in the system's */
  PetscReal   *Mt, *Ct, *Gt, *Ht, *Lq;
  long double *Kt;
  PetscReal   *Rinv; /* ru x ru: the body's u from its orthonormalized coordinates */
  PetscReal   *Pw;   /* v x cw: the pseudo-inverse's columns of the child rows (made at creation, then freed) */
  PetscInt     juoff; /* as a child: the place of its joint's rows among the parent's u rows */
} KFPrimalBody;

struct _n_KFPrimal {
  KFPrimalBody *b;
  PetscInt      h, nb;
  PetscReal    *work; /* l x l of the largest body */
  long double  *workl;
};

/* U_k (k = 0, 1, 2: constant, cos, sin parts) of a revolute joint, cw = 5, column-major */
static void JointU(const PetscReal k[3], const PetscReal E[2][3], PetscInt which, PetscReal U[25])
{
  PetscReal Rk[9], ER[2][3];

  for (int i = 0; i < 25; i++) U[i] = 0;
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 3; j++) {
      const PetscReal kk = k[i] * k[j];
      const PetscReal cross[9] = {0, k[2], -k[1], -k[2], 0, k[0], k[1], -k[0], 0}; /* [k]x column-major */
      Rk[i + 3 * j]            = which == 0 ? kk : which == 1 ? (i == j) - kk : cross[i + 3 * j];
    }
  for (int i = 0; i < 3; i++)
    for (int j = 0; j < 3; j++) U[i + 5 * j] = Rk[i + 3 * j];
  for (int q = 0; q < 2; q++)
    for (int j = 0; j < 3; j++) ER[q][j] = E[q][0] * Rk[0 + 3 * j] + E[q][1] * Rk[1 + 3 * j] + E[q][2] * Rk[2 + 3 * j];
  for (int q = 0; q < 2; q++)
    for (int p = 0; p < 2; p++) U[3 + q + 5 * (3 + p)] = ER[q][0] * E[p][0] + ER[q][1] * E[p][1] + ER[q][2] * E[p][2];
}

/* The unit axis and the rows across it of joint J */
static void JointFrame(const KFJointDef *J, PetscReal k[3], PetscReal E[2][3])
{
  const PetscReal len = PetscSqrtReal(J->axis[0] * J->axis[0] + J->axis[1] * J->axis[1] + J->axis[2] * J->axis[2]);
  for (int i = 0; i < 3; i++) k[i] = J->axis[i] / len;
  KFPerpendicularPair_Private(k, E[0], E[1]);
}

/* rows (nr x v, leading dimension ld) = S X_if, S (nr x 6, row-wise) on interface ifc of body B */
static void InterfaceRows(const KFReducedBody *B, PetscInt ifc, PetscInt nr, const PetscReal S[][6], PetscReal rows[], PetscInt ld)
{
  const PetscInt ldx = 6 * B->ninterfaces;
  for (PetscInt col = 0; col < B->v; col++) {
    const PetscReal *x = B->iface + col * ldx + 6 * ifc;
    for (PetscInt q = 0; q < nr; q++) {
      PetscReal sum = 0;
      for (int c = 0; c < 6; c++) sum += S[q][c] * x[c];
      rows[q + col * ld] = sum;
    }
  }
}

/* The tie rows of joint J (6 wide): on the parent side diag(I3, E), on the child side diag(R0, E R0); nr 5 or 6 */
static void TieSelectors(const KFJointDef *J, PetscReal Sp[6][6], PetscReal Sc[6][6], PetscInt *nr)
{
  PetscReal k[3], E[2][3];
  for (int i = 0; i < 6; i++)
    for (int j = 0; j < 6; j++) Sp[i][j] = Sc[i][j] = 0;
  for (int i = 0; i < 3; i++) {
    Sp[i][i] = 1;
    for (int j = 0; j < 3; j++) Sc[i][j] = J->R0[i + 3 * j];
  }
  if (J->type == KF_JOINT_REVOLUTE) {
    JointFrame(J, k, E);
    for (int q = 0; q < 2; q++)
      for (int j = 0; j < 3; j++) {
        Sp[3 + q][3 + j] = E[q][j];
        Sc[3 + q][3 + j] = E[q][0] * J->R0[0 + 3 * j] + E[q][1] * J->R0[1 + 3 * j] + E[q][2] * J->R0[2 + 3 * j];
      }
    *nr = 5;
  } else {
    for (int i = 0; i < 3; i++) {
      Sp[3 + i][3 + i] = 1;
      for (int j = 0; j < 3; j++) Sc[3 + i][3 + j] = J->R0[i + 3 * j];
    }
    *nr = 6;
  }
}

/* Orthonormal Q (v x r, in place of A) and upper-triangular R with A = Q R, by Gram-Schmidt twice; PETSC_FALSE when
   A is rank deficient */
static PetscBool GramSchmidt(PetscInt v, PetscInt r, PetscReal A[], PetscReal R[])
{
  for (PetscInt i = 0; i < r * r; i++) R[i] = 0;
  for (PetscInt j = 0; j < r; j++) {
    PetscReal *a = A + j * v, norm0 = 0, norm = 0;
    for (PetscInt i = 0; i < v; i++) norm0 += a[i] * a[i];
    for (int pass = 0; pass < 2; pass++)
      for (PetscInt q = 0; q < j; q++) {
        PetscReal d = 0;
        for (PetscInt i = 0; i < v; i++) d += A[i + q * v] * a[i];
        for (PetscInt i = 0; i < v; i++) a[i] -= d * A[i + q * v];
        R[q + j * r] += d;
      }
    for (PetscInt i = 0; i < v; i++) norm += a[i] * a[i];
    if (!(norm > 1e-20 * norm0) || !(norm0 > 0)) return PETSC_FALSE;
    norm          = PetscSqrtReal(norm);
    R[j + j * r] = norm;
    for (PetscInt i = 0; i < v; i++) a[i] /= norm;
  }
  return PETSC_TRUE;
}

/* The split of body b: stacked rows W (its child rows, then its children's joints' in joint order), their SVD, P^w,
   the orthonormalized P^u (Q, with u = Rinv u~), Z; O = [Q Z] (v x hb) and Lq (hb x v: the own coordinates of a
   phi_b). ok PETSC_FALSE when the rows are dependent to the relative tolerance */
static PetscErrorCode SplitBody(KFReassembly r, PetscInt b, PetscInt pjoint, KFPrimalBody *pb, PetscReal **O, PetscBool *ok)
{
  const KFReducedBody *B = &r->bodies[b];
  const PetscInt       v = B->v;
  PetscInt             q = 0, row = 0, hb;
  PetscReal           *W, *A, *s, *U, *VT, *work, *P, *Rb, Sp[6][6], Sc[6][6];
  PetscBLASInt         bq, bv, lwork, info = 0;

  PetscFunctionBegin;
  *ok = PETSC_FALSE;
  for (PetscInt j = 0; j < r->nj; j++) q += (r->joints[j].parent == b || r->joints[j].child == b) ? (r->joints[j].type == KF_JOINT_REVOLUTE ? 5 : 6) : 0;
  if (q > v || (q && !B->iface)) PetscFunctionReturn(0);
  lwork = (PetscBLASInt)(5 * (q + v) + 64);
  PetscCall(PetscCalloc5(q * v + 1, &W, q * v + 1, &A, q + 1, &s, q * q + 1, &U, v * v + 1, &VT));
  PetscCall(PetscMalloc3(lwork, &work, v * q + 1, &P, q * q + 1, &Rb));
  pb->cw = 0;
  if (pjoint >= 0) {
    TieSelectors(&r->joints[pjoint], Sp, Sc, &pb->cw);
    InterfaceRows(B, r->joints[pjoint].child_interface, pb->cw, (const PetscReal(*)[6])Sc, W, q);
    row = pb->cw;
  }
  for (PetscInt j = 0; j < r->nj; j++) {
    PetscInt nr;
    if (r->joints[j].parent != b) continue;
    TieSelectors(&r->joints[j], Sp, Sc, &nr);
    InterfaceRows(B, r->joints[j].parent_interface, nr, (const PetscReal(*)[6])Sp, W + row, q);
    row += nr;
  }
  pb->ru = q - pb->cw;
  hb     = v - pb->cw;
  PetscCall(PetscMalloc1(v * hb + 1, O));
  PetscCall(PetscMalloc1(hb * v + 1, &pb->Lq));
  PetscCall(PetscMalloc2(pb->ru * pb->ru + 1, &pb->Rinv, v * pb->cw + 1, &pb->Pw));
  if (q) {
    PetscCall(PetscArraycpy(A, W, q * v));
    PetscCall(PetscBLASIntCast(q, &bq));
    PetscCall(PetscBLASIntCast(v, &bv));
    PetscCall(PetscFPTrapPush(PETSC_FP_TRAP_OFF));
    PetscCallBLAS("LAPACKgesvd", LAPACKgesvd_("A", "A", &bq, &bv, A, &bq, s, U, &bq, VT, &bv, work, &lwork, &info));
    PetscCall(PetscFPTrapPop());
    PetscCheck(info == 0, PETSC_COMM_SELF, PETSC_ERR_LIB, "KFReassemblyCreate: the SVD of body %" PetscInt_FMT "'s %" PetscInt_FMT " interface rows did not converge (LAPACK gesvd info %d)", b, q, (int)info);
    if (!(s[q - 1] > 1e3 * r->rtol * s[0])) goto done; /* dependent rows: the SVD path decides the rank */
  } else
    for (PetscInt i = 0; i < v; i++) VT[i + i * v] = 1; /* a body in no joint: its own coordinates as they are */
  /* P = V1 S^-1 U^T (v x q) */
  for (PetscInt c = 0; c < q; c++)
    for (PetscInt i = 0; i < v; i++) {
      PetscReal sum = 0;
      for (PetscInt k = 0; k < q; k++) sum += VT[k + i * v] / s[k] * U[c + k * q];
      P[i + c * v] = sum;
    }
  PetscCall(PetscArraycpy(pb->Pw, P, v * pb->cw));
  /* O = [Q Z]: Q from P^u, Z the right singular vectors beyond q */
  PetscCall(PetscArraycpy(*O, P + v * pb->cw, v * pb->ru));
  if (!GramSchmidt(v, pb->ru, *O, Rb)) goto done;
  for (PetscInt j = 0; j < v - q; j++)
    for (PetscInt i = 0; i < v; i++) (*O)[i + (pb->ru + j) * v] = VT[(q + j) + i * v];
  /* Rinv = Rb^-1 (upper triangular) */
  for (PetscInt j = 0; j < pb->ru; j++)
    for (PetscInt i = pb->ru - 1; i >= 0; i--) {
      PetscReal sum = (i == j);
      for (PetscInt k = i + 1; k < pb->ru; k++) sum -= Rb[i + k * pb->ru] * pb->Rinv[k + j * pb->ru];
      pb->Rinv[i + j * pb->ru] = sum / Rb[i + i * pb->ru];
    }
  /* Lq: u~ = Rb W^u phi, z = Z^T phi */
  for (PetscInt c = 0; c < v; c++) {
    for (PetscInt i = 0; i < pb->ru; i++) {
      PetscReal sum = 0;
      for (PetscInt k = i; k < pb->ru; k++) sum += Rb[i + k * pb->ru] * W[pb->cw + k + c * q];
      pb->Lq[i + c * hb] = sum;
    }
    for (PetscInt j = 0; j < v - q; j++) pb->Lq[pb->ru + j + c * hb] = VT[(q + j) + c * v];
  }
  *ok = PETSC_TRUE;
done:
  PetscCall(PetscFree5(W, A, s, U, VT));
  PetscCall(PetscFree3(work, P, Rb));
  PetscFunctionReturn(0);
}

/* The nt terms of S (v x v) on L_0..L_2 (v x l each): weights 1, c, s, s^2, c s (c^2 = 1 - s^2) */
static PetscErrorCode BodyTerms(PetscInt v, PetscInt l, PetscInt nt, const PetscReal S[], PetscReal *const L[3], long double out[])
{
  long double *X, *T;
  const PetscInt ll = l * l;

  PetscFunctionBegin;
  PetscCall(PetscMalloc2(v * l + 1, &X, 9 * ll + 1, &T));
  for (PetscInt a = 0; a < (nt > 1 ? 3 : 1); a++)
    for (PetscInt c = 0; c < (nt > 1 ? 3 : 1); c++) KFDenseCongruenceL_Private(v, l, S, L[a], v, L[c], v, X, T + (3 * a + c) * ll);
  for (PetscInt e = 0; e < ll; e++) {
    const long double *T00 = T, *T01 = T + 1 * ll, *T02 = T + 2 * ll, *T10 = T + 3 * ll, *T11 = T + 4 * ll, *T12 = T + 5 * ll, *T20 = T + 6 * ll, *T21 = T + 7 * ll, *T22 = T + 8 * ll;
    out[e] = T00[e];
    if (nt == 1) continue;
    out[e] += T11[e];
    out[e + 1 * ll] = T01[e] + T10[e];
    out[e + 2 * ll] = T02[e] + T20[e];
    out[e + 3 * ll] = T22[e] - T11[e];
    out[e + 4 * ll] = T12[e] + T21[e];
  }
  PetscCall(PetscFree2(X, T));
  PetscFunctionReturn(0);
}

/* Body b's local bases L_k and its terms of M, K, C, G, H */
static PetscErrorCode BodyBases(KFReassembly r, PetscInt b, PetscInt pjoint, const PetscInt qoff[], PetscReal *const O[])
{
  KFPrimal             pr = r->primal;
  KFPrimalBody        *pb = &pr->b[b], *pp = pjoint >= 0 ? &pr->b[r->joints[pjoint].parent] : NULL;
  const KFReducedBody *B  = &r->bodies[b];
  const PetscInt       v = B->v, hb = v - pb->cw, rp = pp ? pp->ru : 0, l = rp + hb, a = r->a, t = r->t;
  PetscReal           *L[3], Uk[36], k[3], E[2][3];
  long double         *tmp;

  PetscFunctionBegin;
  pb->l  = l;
  pb->nt = (pjoint >= 0 && r->joints[pjoint].type == KF_JOINT_REVOLUTE) ? KF_NTERM : 1;
  PetscCall(PetscMalloc1(l, &pb->idx));
  for (PetscInt i = 0; i < rp; i++) pb->idx[i] = qoff[r->joints[pjoint].parent] + i;
  for (PetscInt i = 0; i < hb; i++) pb->idx[rp + i] = qoff[b] + i;
  PetscCall(PetscCalloc3(v * l + 1, &L[0], v * l + 1, &L[1], v * l + 1, &L[2]));
  PetscCall(PetscArraycpy(L[0] + v * rp, O[b], v * hb));
  if (pjoint >= 0) { /* C_k = P^w U_k^T Rinv_p(rows of the joint, :) */
    const PetscInt cw = pb->cw;
    if (pb->nt > 1) JointFrame(&r->joints[pjoint], k, E);
    for (PetscInt kk = 0; kk < (pb->nt > 1 ? 3 : 1); kk++) {
      if (pb->nt > 1) JointU(k, (const PetscReal(*)[3])E, kk, Uk);
      else
        for (PetscInt i = 0; i < 36; i++) Uk[i] = (i % 7) == 0;
      for (PetscInt c = 0; c < rp; c++)
        for (PetscInt i = 0; i < v; i++) {
          PetscReal sum = 0;
          for (PetscInt x = 0; x < cw; x++) {
            PetscReal y = 0; /* (U_k^T Rinv_p)(x, c) */
            for (PetscInt z = 0; z < cw; z++) y += Uk[z + x * cw] * pp->Rinv[pb->juoff + z + c * rp];
            sum += pb->Pw[i + x * v] * y;
          }
          L[kk][i + c * v] = sum;
        }
    }
  }
  {
    const PetscInt nt = pb->nt, ng = nt > 1 ? 3 : 1;
    PetscCall(PetscMalloc1(nt * l * l + 1, &tmp));
    PetscCall(PetscMalloc5(nt * l * l, &pb->Mt, nt * l * l, &pb->Kt, B->C ? nt * l * l : 1, &pb->Ct, ng * l * a + 1, &pb->Gt, ng * t * l + 1, &pb->Ht));
    PetscCall(BodyTerms(v, l, nt, B->M, L, tmp));
    for (PetscInt e = 0; e < nt * l * l; e++) pb->Mt[e] = (PetscReal)tmp[e];
    PetscCall(BodyTerms(v, l, nt, B->K, L, pb->Kt));
    if (B->C) {
      PetscCall(BodyTerms(v, l, nt, B->C, L, tmp));
      for (PetscInt e = 0; e < nt * l * l; e++) pb->Ct[e] = (PetscReal)tmp[e];
    }
    PetscCall(PetscFree(tmp));
    for (PetscInt kk = 0; kk < ng; kk++) {
      PetscCall(KFDenseGemm_Private('T', 'N', l, a, v, 1.0, L[kk], v, B->G, v, 0.0, pb->Gt + kk * l * a, PetscMax(l, 1)));
      PetscCall(KFDenseGemm_Private('N', 'N', t, l, v, 1.0, B->H, t, L[kk], v, 0.0, pb->Ht + kk * t * l, PetscMax(t, 1)));
    }
  }
  PetscCall(PetscFree3(L[0], L[1], L[2]));
  PetscFunctionReturn(0);
}

/* The joint whose child body b is (-1: none); PETSC_FALSE when the joints are not a forest (a body that is the child
   of two joints, or a loop) */
static PetscBool ParentJoints(KFReassembly r, PetscInt pj[])
{
  for (PetscInt b = 0; b < r->nb; b++) pj[b] = -1;
  for (PetscInt j = 0; j < r->nj; j++) {
    if (pj[r->joints[j].child] >= 0) return PETSC_FALSE;
    pj[r->joints[j].child] = j;
  }
  for (PetscInt b = 0; b < r->nb; b++) {
    PetscInt c = b, steps = 0;
    while (pj[c] >= 0 && steps <= r->nb) {
      c = r->joints[pj[c]].parent;
      steps++;
    }
    if (steps > r->nb) return PETSC_FALSE;
  }
  return PETSC_TRUE;
}

/* X (rows r0.. of an m x nc array, ld m) <- T^T X on r rows (rows) or X T on r columns (cols): one term's share */
static void CongruenceRows(PetscInt m, PetscInt nc, PetscInt r0, PetscInt r, const PetscReal T[], PetscReal X[], PetscReal w[])
{
  for (PetscInt c = 0; c < nc; c++) {
    for (PetscInt i = 0; i < r; i++) {
      PetscReal sum = 0;
      for (PetscInt k = 0; k < r; k++) sum += T[k + i * r] * X[r0 + k + c * m];
      w[i] = sum;
    }
    for (PetscInt i = 0; i < r; i++) X[r0 + i + c * m] = w[i];
  }
}

static void CongruenceCols(PetscInt m, PetscInt c0, PetscInt r, const PetscReal T[], PetscReal X[], PetscReal w[])
{
  for (PetscInt i = 0; i < m; i++) {
    for (PetscInt j = 0; j < r; j++) {
      PetscReal sum = 0;
      for (PetscInt k = 0; k < r; k++) sum += X[i + (c0 + k) * m] * T[k + j * r];
      w[j] = sum;
    }
    for (PetscInt j = 0; j < r; j++) X[i + (c0 + j) * m] = w[j];
  }
}

static void CongruenceL2(PetscInt l, PetscInt s0, PetscInt r, const PetscReal T[], long double X[], long double w[])
{
  for (PetscInt c = 0; c < l; c++) {
    for (PetscInt i = 0; i < r; i++) {
      long double sum = 0;
      for (PetscInt k = 0; k < r; k++) sum += (long double)T[k + i * r] * X[s0 + k + c * l];
      w[i] = sum;
    }
    for (PetscInt i = 0; i < r; i++) X[s0 + i + c * l] = w[i];
  }
  for (PetscInt i = 0; i < l; i++) {
    for (PetscInt j = 0; j < r; j++) {
      long double sum = 0;
      for (PetscInt k = 0; k < r; k++) sum += X[i + (s0 + k) * l] * (long double)T[k + j * r];
      w[j] = sum;
    }
    for (PetscInt j = 0; j < r; j++) X[i + (s0 + j) * l] = w[j];
  }
}

/* The body's terms on its local coordinates s0 .. s0 + r - 1 taken to new coordinates through T (r x r) */
static void TransformBody(KFPrimalBody *pb, PetscInt a, PetscInt t, PetscInt s0, PetscInt r, const PetscReal T[], PetscBool damped, PetscReal w[], long double wl[])
{
  const PetscInt l = pb->l, ll = l * l, ng = pb->nt > 1 ? 3 : 1;
  for (PetscInt k = 0; k < pb->nt; k++) {
    CongruenceRows(l, l, s0, r, T, pb->Mt + k * ll, w);
    CongruenceCols(l, s0, r, T, pb->Mt + k * ll, w);
    if (damped) {
      CongruenceRows(l, l, s0, r, T, pb->Ct + k * ll, w);
      CongruenceCols(l, s0, r, T, pb->Ct + k * ll, w);
    }
    CongruenceL2(l, s0, r, T, pb->Kt + k * ll, wl);
  }
  for (PetscInt k = 0; k < ng; k++) {
    CongruenceRows(l, a, s0, r, T, pb->Gt + k * l * a, w);
    CongruenceCols(t, s0, r, T, pb->Ht + k * t * l, w);
  }
}

/* The coordinates of the rows a body's children are tied to carry the children's mass (Galileo: the rotor's, 3e3 on
   the diagonal): each body's u block is taken to M-orthonormal coordinates at zero angles, T = Phi Lambda^-1/2 from
   that block of M, so that the closed form's M is as well conditioned as the SVD path's there. */
static PetscErrorCode BalanceCoordinates(KFReassembly r, const PetscInt pj[])
{
  KFPrimal pr = r->primal;

  PetscFunctionBegin;
  for (PetscInt p = 0; p < r->nb; p++) {
    KFPrimalBody  *pb = &pr->b[p];
    const PetscInt ru = pb->ru, own0 = pb->l - (r->bodies[p].v - pb->cw); /* p's u coordinates in its local ones */
    PetscReal     *B, *Id, *lam, *T, *Ti, *w;
    long double   *wl;

    if (!ru) continue;
    PetscCall(PetscCalloc6(ru * ru, &B, ru * ru, &Id, ru, &lam, ru * ru, &T, ru * ru, &Ti, PetscMax(pr->b[p].l, PetscMax(r->a, ru)) + ru, &w));
    PetscCall(PetscMalloc1(PetscMax(pr->b[p].l, ru) + 1, &wl));
    for (PetscInt b = 0; b < r->nb; b++) { /* the u block of M at zero angles: weights 1, 1, 0, 0, 0 */
      const KFPrimalBody *q  = &pr->b[b];
      PetscInt            s0 = -1;
      if (b == p) s0 = own0;
      else if (pj[b] >= 0 && r->joints[pj[b]].parent == p) s0 = 0;
      if (s0 < 0) continue;
      for (PetscInt j = 0; j < ru; j++)
        for (PetscInt i = 0; i < ru; i++) {
          const PetscInt e = s0 + i + (s0 + j) * q->l;
          B[i + j * ru] += q->Mt[e] + (q->nt > 1 ? q->Mt[e + q->l * q->l] : 0);
        }
    }
    for (PetscInt i = 0; i < ru; i++) Id[i + i * ru] = 1;
    PetscCall(KFDenseEig(ru, B, Id, lam, T)); /* B T = T diag(lam), T^T T = I */
    if (lam[0] > 1e-12 * lam[ru - 1]) {      /* a massless interface leaves the coordinates as they are */
      for (PetscInt j = 0; j < ru; j++)
        for (PetscInt i = 0; i < ru; i++) {
          Ti[i + j * ru] = T[i + j * ru] * PetscSqrtReal(lam[j]); /* (T^-1)^T = Phi Lambda^1/2, as CongruenceRows takes it */
          T[i + j * ru] /= PetscSqrtReal(lam[j]);
        }
      for (PetscInt b = 0; b < r->nb; b++) {
        if (b == p) TransformBody(&pr->b[b], r->a, r->t, own0, ru, T, r->bodies[b].C ? PETSC_TRUE : PETSC_FALSE, w, wl);
        else if (pj[b] >= 0 && r->joints[pj[b]].parent == p) TransformBody(&pr->b[b], r->a, r->t, 0, ru, T, r->bodies[b].C ? PETSC_TRUE : PETSC_FALSE, w, wl);
      }
      /* the coordinates from phi: u~' = T^-1 u~ */
      CongruenceRows(r->bodies[p].v - pb->cw, r->bodies[p].v, 0, ru, Ti, pb->Lq, w);
    }
    PetscCall(PetscFree6(B, Id, lam, T, Ti, w));
    PetscCall(PetscFree(wl));
  }
  PetscFunctionReturn(0);
}

PetscErrorCode KFPrimalCreate_Private(KFReassembly r)
{
  KFPrimal   pr;
  PetscInt  *pj, *qoff, lmax = 1;
  PetscReal **O;
  PetscBool  ok = PETSC_TRUE;

  PetscFunctionBegin;
  r->primal = NULL;
  PetscCall(PetscMalloc2(r->nb, &pj, r->nb + 1, &qoff));
  PetscCall(PetscCalloc1(r->nb, &O));
  PetscCall(PetscNew(&pr));
  PetscCall(PetscCalloc1(r->nb, &pr->b));
  pr->nb = r->nb;
  r->primal = pr;
  if (!ParentJoints(r, pj)) ok = PETSC_FALSE;
  qoff[0] = 0;
  for (PetscInt b = 0; ok && b < r->nb; b++) {
    PetscCall(SplitBody(r, b, pj[b], &pr->b[b], &O[b], &ok));
    qoff[b + 1] = qoff[b] + r->bodies[b].v - pr->b[b].cw;
  }
  if (ok) {
    pr->h      = qoff[r->nb];
    r->hprimal = pr->h;
    /* each joint's rows among its parent's u rows, in joint order */
    for (PetscInt b = 0; b < r->nb; b++) {
      PetscInt uoff = 0;
      for (PetscInt j = 0; j < r->nj; j++)
        if (r->joints[j].parent == b) {
          pr->b[r->joints[j].child].juoff = uoff;
          uoff += r->joints[j].type == KF_JOINT_REVOLUTE ? 5 : 6;
        }
    }
    for (PetscInt b = 0; b < r->nb; b++) {
      pr->b[b].irev = -1;
      if (pj[b] >= 0 && r->joints[pj[b]].type == KF_JOINT_REVOLUTE) {
        pr->b[b].irev = 0;
        for (PetscInt j = 0; j < pj[b]; j++) pr->b[b].irev += r->joints[j].type == KF_JOINT_REVOLUTE;
      }
      PetscCall(BodyBases(r, b, pj[b], qoff, O));
      lmax = PetscMax(lmax, pr->b[b].l);
    }
    PetscCall(PetscMalloc2(lmax * PetscMax(lmax, PetscMax(r->a, r->t)) + 1, &pr->work, lmax * lmax + 1, &pr->workl));
    PetscCall(BalanceCoordinates(r, pj));
  }
  for (PetscInt b = 0; b < r->nb; b++) {
    PetscCall(PetscFree(O[b]));
    if (pr->b[b].Pw) PetscCall(PetscFree2(pr->b[b].Rinv, pr->b[b].Pw));
  }
  PetscCall(PetscFree(O));
  PetscCall(PetscFree2(pj, qoff));
  if (!ok) PetscCall(KFPrimalDestroy_Private(&r->primal));
  PetscFunctionReturn(0);
}

PetscErrorCode KFPrimalDestroy_Private(KFPrimal *primal)
{
  KFPrimal pr = *primal;

  PetscFunctionBegin;
  if (!pr) PetscFunctionReturn(0);
  for (PetscInt b = 0; pr->b && b < pr->nb; b++) {
    PetscCall(PetscFree(pr->b[b].Lq));
    PetscCall(PetscFree(pr->b[b].idx));
    if (pr->b[b].Mt) PetscCall(PetscFree5(pr->b[b].Mt, pr->b[b].Kt, pr->b[b].Ct, pr->b[b].Gt, pr->b[b].Ht));
  }
  PetscCall(PetscFree(pr->b));
  if (pr->work) PetscCall(PetscFree2(pr->work, pr->workl));
  PetscCall(PetscFree(pr));
  *primal = NULL;
  PetscFunctionReturn(0);
}

/* out[idx_i + idx_j h] += sum_k w_k T_k (l x l), the terms of one body */
static inline void Scatter(PetscInt h, PetscInt l, const PetscInt idx[], PetscInt nt, const PetscReal w[], const PetscReal T[], PetscReal out[], PetscReal loc[])
{
  const PetscInt ll = l * l;
  for (PetscInt e = 0; e < ll; e++) loc[e] = T[e];
  for (PetscInt k = 1; k < nt; k++)
    for (PetscInt e = 0; e < ll; e++) loc[e] += w[k] * T[e + k * ll];
  for (PetscInt j = 0; j < l; j++)
    for (PetscInt i = 0; i < l; i++) out[idx[i] + idx[j] * h] += loc[i + j * l];
}

/* Mh, Kh, Ch (without Rayleigh), Gh, Hh at these angles: each body's terms weighted and added at its coordinates */
PetscErrorCode KFPrimalApply_Private(KFReassembly r, const PetscReal angles[], PetscReal Mh[], PetscReal Kh[], PetscReal Ch[], PetscReal Gh[], PetscReal Hh[])
{
  KFPrimal       pr = r->primal;
  const PetscInt h = pr->h, a = r->a, t = r->t;

  PetscFunctionBegin;
  PetscCall(PetscArrayzero(Mh, h * h));
  PetscCall(PetscArrayzero(Kh, h * h));
  PetscCall(PetscArrayzero(Gh, h * a));
  PetscCall(PetscArrayzero(Hh, t * h));
  if (Ch) PetscCall(PetscArrayzero(Ch, h * h));
  for (PetscInt b = 0; b < r->nb; b++) {
    const KFPrimalBody *pb = &pr->b[b];
    const PetscInt      l = pb->l, ll = l * l, *idx = pb->idx, nt = pb->nt;
    PetscReal           c = 1, s = 0, w[KF_NTERM];
    long double        *kl = pr->workl;

    if (!l) continue;
    if (pb->irev >= 0) {
      c = PetscCosReal(angles[pb->irev]);
      s = PetscSinReal(angles[pb->irev]);
    }
    w[0] = 1, w[1] = c, w[2] = s, w[3] = s * s, w[4] = c * s;
    Scatter(h, l, idx, nt, w, pb->Mt, Mh, pr->work);
    if (Ch && r->bodies[b].C) Scatter(h, l, idx, nt, w, pb->Ct, Ch, pr->work);
    /* K in long double, as the terms were made */
    for (PetscInt e = 0; e < ll; e++) kl[e] = pb->Kt[e];
    for (PetscInt k = 1; k < nt; k++)
      for (PetscInt e = 0; e < ll; e++) kl[e] += (long double)w[k] * pb->Kt[e + k * ll];
    for (PetscInt j = 0; j < l; j++)
      for (PetscInt i = 0; i < l; i++) Kh[idx[i] + idx[j] * h] += (PetscReal)kl[i + j * l];
    for (PetscInt k = 0; k < (nt > 1 ? 3 : 1); k++) {
      for (PetscInt j = 0; j < a; j++)
        for (PetscInt i = 0; i < l; i++) Gh[idx[i] + j * h] += w[k] * pb->Gt[i + j * l + k * l * a];
      for (PetscInt j = 0; j < l; j++)
        for (PetscInt i = 0; i < t; i++) Hh[i + idx[j] * t] += w[k] * pb->Ht[i + j * t + k * t * l];
    }
  }
  PetscCall(KFDenseSymmetrize_Private(h, Mh));
  PetscCall(KFDenseSymmetrize_Private(h, Kh));
  if (Ch) PetscCall(KFDenseSymmetrize_Private(h, Ch));
  PetscFunctionReturn(0);
}

/* Phir (h x q) = the coordinates of Y (n x q, stacked body coordinates of motions that satisfy the ties) */
PetscErrorCode KFPrimalToCoordinates_Private(KFReassembly r, PetscInt q, const PetscReal Y[], PetscReal Phir[])
{
  KFPrimal pr  = r->primal;
  PetscInt row = 0;

  PetscFunctionBegin;
  for (PetscInt b = 0; b < r->nb; b++) {
    const PetscInt v = r->bodies[b].v, hb = v - pr->b[b].cw;
    PetscCall(KFDenseGemm_Private('N', 'N', hb, q, v, 1.0, pr->b[b].Lq, PetscMax(hb, 1), Y + r->off[b], r->n, 0.0, Phir + row, pr->h));
    row += hb;
  }
  PetscFunctionReturn(0);
}
