/*
  Body-wise compression of a reduced model by what its assembled response needs. A body basis holds every
  direction its system vectors restrict to, whatever share of the response each carries; here each body's reduced
  coordinates are ordered by that share:
    - snapshots: the body's part q_b = N_b y(w) of the reassembled model's elastic response y(w) to every input (N: the
      null space of the ties), at the given frequencies and configurations, under the model's damping;
    - kept exactly: the body's 6 rigid motions and (static_exact) its part of the static elastic response y(0) at every
      configuration, so that the static moment L^0 there is reproduced (a Galerkin projection whose space holds the
      static solution returns it). Without static_exact y(0) is one more snapshot, ordered and truncated like the
      others: L^0 is then approximated, and a body needs no direction for each of its static columns;
    - ordered: the rest of the snapshots, M_b-orthogonal to the kept columns, by the eigenvectors of their M_b-weighted
      Gram matrix (the left singular vectors of the snapshots, leading first). Each input's snapshots may be weighted
      (the caller's inw): the accuracy is relative per input/output pair, so an input whose response is small counts
      as much as one whose response is large only when its snapshots are scaled up to match.
  KFReducedModelCompress then makes the model whose body b keeps its kept columns and its first counts[b] directions:
  a Galerkin projection of each reduced body (M, K, C, G, H, interface rows, rigid motions and map). All dense and
  replicated: every rank computes the same numbers.
*/
#include <kryflex/modelimpl.h>
#include <petscblaslapack.h>
#include "../dense/dense_impl.h"

/* C (m x n) = A^T B, A m' x m and B m' x n column-major (small: plain loops) */
static void KFAtB(PetscInt mp, PetscInt m, PetscInt n, const PetscReal A[], PetscInt lda, const PetscReal B[], PetscInt ldb, PetscReal C[])
{
  for (PetscInt j = 0; j < n; j++)
    for (PetscInt i = 0; i < m; i++) {
      PetscReal d = 0;
      for (PetscInt k = 0; k < mp; k++) d += A[k + i * lda] * B[k + j * ldb];
      C[i + j * m] = d;
    }
}

/* C (m x n) = A B, A m x k, B k x n */
static void KFAB(PetscInt m, PetscInt k, PetscInt n, const PetscReal A[], PetscInt lda, const PetscReal B[], PetscInt ldb, PetscReal C[], PetscInt ldc)
{
  for (PetscInt j = 0; j < n; j++)
    for (PetscInt i = 0; i < m; i++) {
      PetscReal d = 0;
      for (PetscInt l = 0; l < k; l++) d += A[i + l * lda] * B[l + j * ldb];
      C[i + j * ldc] = d;
    }
}

/* Gq (v x v) += s2 (re re^T + im im^T) of one snapshot column (re, im: v entries; im NULL: real) */
static void KFGramAdd(PetscInt v, PetscReal s2, const PetscReal re[], const PetscReal im[], PetscReal Gq[])
{
  for (PetscInt c = 0; c < v; c++)
    for (PetscInt r = 0; r < v; r++) Gq[r + c * v] += s2 * (re[r] * re[c] + (im ? im[r] * im[c] : 0));
}

/* one configuration's snapshots: each group's share of the static response (appended to S[g], v_g x a columns at
   column nS; also added to the Gram as a snapshot when !static_exact) and the Gram matrix of its dynamic response,
   input j weighted by inw[j] (NULL: 1), added to Gq[g] (v_g x v_g), in reduced body coordinates. The groups: each
   body (stacked false) or all bodies' stacked coordinates as one (stacked true: the Gram's cross-body terms too).
   *ok false (nothing added): the reassembly here finds fewer rigid and mechanism modes than the scene has, so the
   static response, a solve on the flexible subspace, cannot be formed */
static PetscErrorCode KFCompressSnapshots(KFReducedModel m, const PetscReal angles[], PetscInt nw, const PetscReal w[], const PetscReal inw[], PetscBool static_exact, PetscBool stacked, PetscInt nS, PetscReal *S[], PetscReal *Gq[], PetscBool *ok)
{
  const PetscInt a = m->ninputs;
  PetscInt       n = 0, h, rank, nrigid, *off, ng, goff[2];
  const PetscInt *go;
  KFReducedBody *bodies;
  PetscReal     *Mh, *Kh, *Gh, *N, *Phir, *lambda, *Phi, *PG, *NP, *Hid, sratio, rtol = 1e-9;

  PetscFunctionBegin;
  PetscCall(PetscMalloc2(m->nb, &bodies, m->nb + 1, &off));
  off[0] = 0;
  for (PetscInt b = 0; b < m->nb; b++) {
    PetscCall(KFReducedModelGetBody(m, b, NULL, NULL, &bodies[b], NULL));
    off[b + 1] = off[b] + bodies[b].v;
  }
  n       = off[m->nb];
  ng      = stacked ? 1 : m->nb;
  goff[0] = 0;
  goff[1] = n;
  go      = stacked ? goff : off;
  /* outputs H = I: the reassembled outputs are N itself (n x h) */
  PetscCall(PetscCalloc1(n * n, &Hid));
  for (PetscInt b = 0; b < m->nb; b++) {
    for (PetscInt i = 0; i < bodies[b].v; i++) Hid[(off[b] + i) + (off[b] + i) * n] = 1;
    bodies[b].H = Hid + off[b] * n; /* n x v_b, leading dimension n */
    bodies[b].C = NULL;
  }
  for (PetscInt k = 0; k < m->nsettings; k++) {
    PetscBool same;
    PetscCall(PetscStrcmp(m->keys[k], "reassembly_rtol", &same));
    if (same) rtol = (PetscReal)atof(m->values[k]);
  }
  PetscCall(PetscMalloc5(n * n, &Mh, n * n, &Kh, n * a, &Gh, n * n, &N, n * n, &Phir));
  /* a tied model's coordinate ties too: N spans what its stacked coordinates may take */
  PetscCall(KFReassembleTied(m->nb, bodies, m->nj, m->joints, m->nties, m->ties, angles, a, n, rtol, &h, Mh, Kh, NULL, Gh, N, &rank, &sratio, &nrigid, Phir));
  PetscCheck(nrigid >= 0, PetscObjectComm((PetscObject)m), PETSC_ERR_ARG_WRONG, "compression needs the bodies' rigid motions: the model has none recorded");
  *ok = (PetscBool)(m->nrigid < 0 || nrigid >= m->nrigid);
  if (!*ok) {
    PetscCall(PetscInfo(m, "compression snapshots: %" PetscInt_FMT " rigid and mechanism modes of the bodies' rigid motions under the ties, the scene has %" PetscInt_FMT "\n", nrigid, m->nrigid));
    PetscCall(PetscFree5(Mh, Kh, Gh, N, Phir));
    PetscCall(PetscFree(Hid));
    PetscCall(PetscFree2(bodies, off));
    PetscFunctionReturn(0);
  }
  PetscCall(PetscMalloc4(h, &lambda, h * h, &Phi, h * a, &PG, n * h, &NP));
  PetscCall(KFDenseEigRigid(h, Kh, Mh, nrigid, Phir, lambda, Phi));
  {
    const PetscInt nf = h - nrigid;
    PetscReal     *Pf = Phi + nrigid * h, *y, *yi, *glk, *dwk;

    KFAtB(h, nf, a, Pf, h, Gh, h, PG);      /* Phi_f^T G (nf x a) */
    KFAB(n, h, nf, N, n, Pf, h, NP, n);     /* N Phi_f (n x nf) */
    PetscCall(PetscMalloc2(n * a, &y, n * a, &yi));
    /* static: N K^+ G on the flexible subspace, by solves that keep the digits an eigendecomposition of a stiff model
       loses (KFDenseMomentsRigid with the outputs N) */
    PetscCall(KFDenseMomentsRigid(h, Kh, Mh, a, Gh, n, N, nrigid, Phir, 1, y));
    for (PetscInt g = 0; g < ng; g++) {
      const PetscInt v = go[g + 1] - go[g];

      for (PetscInt j = 0; j < a; j++) {
        PetscCall(PetscArraycpy(&S[g][(nS + j) * v], &y[go[g] + j * n], v));
        if (!static_exact) KFGramAdd(v, inw ? inw[j] * inw[j] : 1, &y[go[g] + j * n], NULL, Gq[g]);
      }
    }
    PetscCall(PetscMalloc2(nf + 1, &glk, nf + 1, &dwk));
    for (PetscInt k = 0; k < nf; k++) { /* the parts of each mode's damping that do not depend on w, made once */
      const PetscReal lk = lambda[nrigid + k], sk = PetscSqrtReal(PetscMax(lk, 0)), zk = KFDampingModalRatio(&m->damping, sk / (2 * PETSC_PI));

      glk[k] = lk * m->damping.g;
      dwk[k] = 2 * zk * sk + m->damping.alpha + m->damping.beta * lk;
    }
    for (PetscInt f = 0; f < nw; f++) {
      PetscCall(PetscArrayzero(y, n * a));
      PetscCall(PetscArrayzero(yi, n * a));
      for (PetscInt k = 0; k < nf; k++) { /* 1 / (lambda (1 + i g) - w^2 + i w (2 zeta_k sqrt(lambda) + alpha + beta lambda)) */
        const PetscReal lk = lambda[nrigid + k];
        const PetscReal re = lk - w[f] * w[f], im = glk[k] + w[f] * dwk[k], den = re * re + im * im;
        for (PetscInt j = 0; j < a; j++) {
          const PetscReal c = PG[k + j * nf], cr = c * re / den, ci = -c * im / den;
          for (PetscInt i = 0; i < n; i++) {
            y[i + j * n] += NP[i + k * n] * cr;
            yi[i + j * n] += NP[i + k * n] * ci;
          }
        }
      }
      for (PetscInt g = 0; g < ng; g++) { /* Gq_g += Re q Re q^T + Im q Im q^T */
        const PetscInt v = go[g + 1] - go[g];
        for (PetscInt j = 0; j < a; j++) KFGramAdd(v, inw ? inw[j] * inw[j] : 1, &y[go[g] + j * n], &yi[go[g] + j * n], Gq[g]);
      }
    }
    PetscCall(PetscFree2(glk, dwk));
    PetscCall(PetscFree2(y, yi));
  }
  PetscCall(PetscFree4(lambda, Phi, PG, NP));
  PetscCall(PetscFree5(Mh, Kh, Gh, N, Phir));
  PetscCall(PetscFree(Hid));
  PetscCall(PetscFree2(bodies, off));
  PetscFunctionReturn(0);
}

/* the directions of coordinates of mass M (v x v, named name) from their nr rigid motions R (v x nr), static columns S
   (v x ns) and snapshot Gram Gq (v x v): W (v x (nkeep + ndir)) M-orthonormal, the kept columns first, then the
   others leading first, with their weights. One body (nr 6) or all bodies stacked (M, R block diagonal) */
static PetscErrorCode KFCompressBody(const char name[], PetscInt v, const PetscReal Mb[], PetscInt nr, const PetscReal R[], PetscInt ns, const PetscReal S[], PetscReal Gq[], KFBodyDirections *d)
{
  PetscBLASInt   bv, info, lwork;
  PetscReal     *L, *X, *Gz, *T, *ev, *work;
  PetscInt       nk;

  PetscFunctionBegin;
  d->v = v;
  if (!v) { /* a body reduced to nothing keeps nothing */
    PetscCall(PetscMalloc2(1, &d->W, 1, &d->weight));
    PetscFunctionReturn(0);
  }
  PetscCall(PetscBLASIntCast(v, &bv));
  lwork = PetscMax(3 * bv, 1) * 4;
  PetscCall(PetscMalloc6(v * v, &L, v * (nr + ns + v), &X, v * v, &Gz, v * v, &T, v, &ev, lwork, &work));
  /* M_b = L L^T; coordinates z = L^T q make the M_b inner product Euclidean */
  for (PetscInt i = 0; i < v * v; i++) L[i] = 0.5 * (Mb[i] + Mb[(i % v) * v + i / v]);
  PetscCallBLAS("LAPACKpotrf", LAPACKpotrf_("L", &bv, L, &bv, &info));
  PetscCheck(!info, PETSC_COMM_SELF, PETSC_ERR_LIB, "body '%s': its reduced mass matrix is not positive definite (potrf %d): compression needs a mass on every reduced coordinate; set -kf_compress false", name, (int)info);
  for (PetscInt j = 0; j < v; j++)
    for (PetscInt i = 0; i < j; i++) L[i + j * v] = 0;
  /* kept: L^T [rigid, S] */
  KFAtB(v, v, nr, L, v, R, v, X);
  KFAtB(v, v, ns, L, v, S, v, X + nr * v);
  PetscCall(KFDenseOrthonormalizeSmall_Private(v, nr + ns, X, NULL, 1e-8, &nk));
  /* the snapshots' Gram in z: L^T Gq L, then with the kept span projected out: P Gz P, P = I - X X^T */
  KFAtB(v, v, v, L, v, Gq, v, T);
  KFAB(v, v, v, T, v, L, v, Gz, v);
  for (PetscInt i = 0; i < v * v; i++) T[i] = (i % v == i / v) ? 1 : 0;
  for (PetscInt j = 0; j < v; j++)
    for (PetscInt i = 0; i < v; i++)
      for (PetscInt q = 0; q < nk; q++) T[i + j * v] -= X[i + q * v] * X[j + q * v];
  KFAB(v, v, v, T, v, Gz, v, Gq, v);
  KFAB(v, v, v, Gq, v, T, v, Gz, v);
  for (PetscInt j = 0; j < v; j++)
    for (PetscInt i = 0; i < j; i++) Gz[i + j * v] = Gz[j + i * v] = 0.5 * (Gz[i + j * v] + Gz[j + i * v]);
  PetscCallBLAS("LAPACKsyev", LAPACKsyev_("V", "L", &bv, Gz, &bv, ev, work, &lwork, &info));
  PetscCheck(!info, PETSC_COMM_SELF, PETSC_ERR_LIB, "body '%s': the eigensolve of its response snapshots failed (syev %d)", name, (int)info);
  /* directions, leading first, after the kept ones; what the kept span already holds drops out. Each with its largest
     entry positive: an eigenvector's sign is arbitrary, and 1 and 2 ranks must make the same model */
  for (PetscInt q = 0; q < v; q++) {
    PetscReal *x = X + (nk + q) * v, big = 0;

    PetscCall(PetscArraycpy(x, Gz + (v - 1 - q) * v, v));
    for (PetscInt i = 0; i < v; i++)
      if (PetscAbsReal(x[i]) > PetscAbsReal(big) * (1 + 1e-8)) big = x[i];
    if (big < 0)
      for (PetscInt i = 0; i < v; i++) x[i] = -x[i];
  }
  {
    PetscInt nall;
    PetscReal top = ev[v - 1] > 0 ? ev[v - 1] : 0;
    PetscInt  nd  = 0;

    for (PetscInt q = 0; q < v; q++) nd += ev[v - 1 - q] > 1e-20 * top && top > 0;
    PetscCall(KFDenseOrthonormalizeSmall_Private(v, nk + nd, X, NULL, 1e-6, &nall));
    d->nkeep = nk;
    d->ndir  = nall - nk;
    PetscCall(PetscMalloc2(v * nall + 1, &d->W, d->ndir + 1, &d->weight));
    for (PetscInt q = 0; q < d->ndir; q++) d->weight[q] = PetscSqrtReal(PetscMax(ev[v - 1 - q], 0));
  }
  /* W = L^-T X */
  PetscCall(PetscArraycpy(d->W, X, v * (d->nkeep + d->ndir)));
  {
    PetscBLASInt nc;
    PetscCall(PetscBLASIntCast(d->nkeep + d->ndir, &nc));
    if (nc) PetscCallBLAS("LAPACKtrtrs", LAPACKtrtrs_("L", "T", "N", &bv, &nc, L, &bv, d->W, &bv, &info));
  }
  d->v = v;
  PetscCall(PetscFree6(L, X, Gz, T, ev, work));
  PetscFunctionReturn(0);
}

/*
  KFBodyCompressDirections - every body's directions ordered by its share of the model's elastic response at nconf
  configurations (angles: nconf x nrevolute, row by row, radians), configuration k at the nw[k] frequencies w[k]
  (rad/s), its input j's snapshots weighted by inw[k][j] (inw NULL: all 1), under the model's damping (modal, Rayleigh
  and structural; the bodies' viscous matrices left out). static_exact: each body's share of the static response is
  kept exactly (L^0 reproduced at the configurations); false: it is one more snapshot. dirs: nb of them, freed with
  KFBodyDirectionsDestroy.
*/
PetscErrorCode KFBodyCompressDirections(KFReducedModel m, PetscInt nconf, const PetscReal angles[], const PetscInt nw[], const PetscReal *const w[], const PetscReal *const inw[], PetscBool static_exact, KFBodyDirections **dirs)
{
  const PetscInt nrev1 = PetscMax(m->nrevolute, 1), a = m->ninputs;
  PetscReal    **S, **Gq;

  PetscFunctionBegin;
  PetscValidHeaderSpecific(m, KF_REDUCEDMODEL_CLASSID, 1);
  PetscCheck(nconf >= 1, PetscObjectComm((PetscObject)m), PETSC_ERR_ARG_OUTOFRANGE, "compression needs at least one configuration");
  PetscCheck(!m->nties, PetscObjectComm((PetscObject)m), PETSC_ERR_SUP, "the model's bodies are tied by %" PetscInt_FMT " coordinate ties (shared directions), and compression truncates each body on its own: reduce with -kf_shared_directions false to compress", m->nties);
  PetscCall(PetscCalloc1(m->nb, dirs));
  PetscCall(PetscMalloc2(m->nb, &S, m->nb, &Gq));
  for (PetscInt b = 0; b < m->nb; b++) {
    const PetscInt v = m->bodies[b].v;
    PetscCheck(m->bodies[b].rigid, PetscObjectComm((PetscObject)m), PETSC_ERR_ARG_WRONG, "body '%s' has no rigid motions recorded: compression keeps them exactly", m->bodies[b].name);
    PetscCall(PetscCalloc1(v * a * nconf + 1, &S[b]));
    PetscCall(PetscCalloc1(v * v + 1, &Gq[b]));
  }
  for (PetscInt k = 0; k < nconf; k++) {
    PetscBool ok;

    PetscCall(KFCompressSnapshots(m, m->nrevolute ? &angles[k * nrev1] : NULL, nw[k], w[k], inw ? inw[k] : NULL, static_exact, PETSC_FALSE, k * a, S, Gq, &ok));
    PetscCheck(ok, PetscObjectComm((PetscObject)m), PETSC_ERR_ARG_WRONG, "compression: the model reassembled at configuration %" PetscInt_FMT " has fewer rigid and mechanism modes than the scene's %" PetscInt_FMT ": its static response cannot be formed; set -kf_compress false", k, m->nrigid);
  }
  for (PetscInt b = 0; b < m->nb; b++) {
    const KFModelBody *B = &m->bodies[b];

    PetscCall(KFCompressBody(B->name, B->v, B->M, 6, B->rigid, static_exact ? a * nconf : 0, S[b], Gq[b], &(*dirs)[b]));
    PetscCall(PetscFree(S[b]));
    PetscCall(PetscFree(Gq[b]));
  }
  PetscCall(PetscFree2(S, Gq));
  PetscFunctionReturn(0);
}

PetscErrorCode KFBodyDirectionsDestroy(PetscInt nb, KFBodyDirections **dirs)
{
  PetscFunctionBegin;
  if (!*dirs) PetscFunctionReturn(0);
  for (PetscInt b = 0; b < nb; b++) PetscCall(PetscFree2((*dirs)[b].W, (*dirs)[b].weight));
  PetscCall(PetscFree(*dirs));
  PetscFunctionReturn(0);
}

/* W^T A W (k x k) of A (v x v), W v x k, symmetric, accumulated in long double: a reduced body keeps its stiff
   modes, and the static moment the compression promises to keep is read through K */
static PetscErrorCode KFCongruence(PetscInt v, PetscInt k, const PetscReal A[], const PetscReal W[], PetscReal **out)
{
  long double *X, *T;

  PetscFunctionBegin;
  PetscCall(PetscMalloc2(v * k + 1, &X, k * k + 1, &T));
  PetscCall(PetscMalloc1(k * k + 1, out));
  KFDenseCongruenceL_Private(v, k, A, W, v, W, v, X, T);
  for (PetscInt j = 0; j < k; j++)
    for (PetscInt i = 0; i <= j; i++) (*out)[i + j * k] = (*out)[j + i * k] = (PetscReal)(0.5L * (T[i + j * k] + T[j + i * k]));
  PetscCall(PetscFree2(X, T));
  PetscFunctionReturn(0);
}

/* body R of the compressed model: body B projected on W (v x k, M_b-orthonormal, holding B's rigid motions); its map
   to the full dofs only when with_map (the product with the map is most of the projection's work) */
static PetscErrorCode KFProjectBody(const KFModelBody *B, PetscInt a, PetscInt t, PetscInt k, const PetscReal W[], PetscBool with_map, KFModelBody *R)
{
  const PetscInt v = B->v, ni = B->ninterfaces;
  PetscReal     *MR;

  PetscFunctionBegin;
  *R   = *B;
  R->v = k;
  PetscCall(PetscMalloc1(ni, &R->iface_names));
  PetscCall(PetscArraycpy(R->iface_names, B->iface_names, ni));
  PetscCall(KFCongruence(v, k, B->M, W, &R->M));
  PetscCall(KFCongruence(v, k, B->K, W, &R->K));
  R->C = NULL;
  if (B->C) PetscCall(KFCongruence(v, k, B->C, W, &R->C));
  /* one allocation each (the model frees them one by one), NULL when empty, as the model's own constructor */
  PetscCall(PetscMalloc1(k * a, &R->G));
  PetscCall(PetscMalloc1(t * k, &R->H));
  PetscCall(PetscMalloc1(6 * ni * k, &R->iface));
  PetscCall(PetscMalloc1(6 * k, &R->rigid));
  KFAtB(v, k, a, W, v, B->G, v, R->G);
  KFAB(t, v, k, B->H, t, W, v, R->H, t);
  KFAB(6 * ni, v, k, B->iface, 6 * ni, W, v, R->iface, 6 * ni);
  /* rigid motions in the new coordinates: W^T M_b rigid (exact: they lie in span W, which is M_b-orthonormal) */
  PetscCall(PetscMalloc1(v * 6, &MR));
  KFAB(v, v, 6, B->M, v, B->rigid, v, MR, v);
  KFAtB(v, k, 6, W, v, MR, v, R->rigid);
  PetscCall(PetscFree(MR));
  R->map = NULL;
  if (B->map && with_map) {
    PetscCall(PetscMalloc1(B->full_dofs * k, &R->map));
    KFAB(B->full_dofs, v, k, B->map, B->full_dofs, W, v, R->map, B->full_dofs);
  }
  PetscFunctionReturn(0);
}

/*
  KFReducedModelCompress - the model whose body b keeps the kept columns of dirs[b] and its first counts[b] directions
  (counts NULL: all of them): each reduced body projected on them; names, joints, damping, settings and reduction
  angles as m's. The new model lives on m's communicator. with_map: the bodies' maps to the full dofs too (where m
  has them); a candidate that is only reassembled and measured needs none.
*/
PetscErrorCode KFReducedModelCompress(KFReducedModel m, const KFBodyDirections dirs[], const PetscInt counts[], PetscBool with_map, KFReducedModel *out)
{
  KFReducedModel c;
  const PetscInt nb = m->nb, nj = m->nj, a = m->ninputs, t = m->noutputs;

  PetscFunctionBegin;
  PetscValidHeaderSpecific(m, KF_REDUCEDMODEL_CLASSID, 1);
  PetscCall(KFReducedModelCreateEmpty_Private(PetscObjectComm((PetscObject)m), nb, nj, a, t, &c));
  PetscCall(PetscStrncpy(c->scene_name, m->scene_name, sizeof(c->scene_name)));
  PetscCall(PetscStrncpy(c->fingerprint, m->fingerprint, sizeof(c->fingerprint)));
  PetscCall(PetscObjectSetName((PetscObject)c, ((PetscObject)m)->name));
  c->nrevolute = m->nrevolute;
  c->nrigid    = m->nrigid;
  PetscCall(PetscArraycpy(c->joint_names, m->joint_names, nj));
  PetscCall(PetscArraycpy(c->joints, m->joints, nj));
  PetscCall(PetscArraycpy(c->input_names, m->input_names, a));
  PetscCall(PetscArraycpy(c->output_names, m->output_names, t));
  PetscCall(PetscArraycpy(c->quantity, m->quantity, t));
  c->damping = m->damping;
  c->nangles = m->nangles;
  PetscCall(PetscMalloc1(m->nangles * m->nrevolute + 1, &c->angles));
  PetscCall(PetscArraycpy(c->angles, m->angles, m->nangles * m->nrevolute));
  for (PetscInt k = 0; k < m->nsettings; k++) PetscCall(KFReducedModelSetSetting(c, m->keys[k], m->values[k]));
  for (PetscInt b = 0; b < nb; b++) {
    const KFBodyDirections *d = &dirs[b];
    const PetscInt          k = d->nkeep + (counts ? PetscMin(PetscMax(counts[b], 0), d->ndir) : d->ndir);

    PetscCheck(d->v == m->bodies[b].v, PetscObjectComm((PetscObject)m), PETSC_ERR_ARG_INCOMP, "body '%s': directions of %" PetscInt_FMT " coordinates for a body of %" PetscInt_FMT ": make them from this model", m->bodies[b].name, d->v, m->bodies[b].v);
    PetscCall(KFProjectBody(&m->bodies[b], a, t, k, d->W, with_map, &c->bodies[b]));
  }
  *out = c;
  PetscFunctionReturn(0);
}

/*
  KFTiedCompressDirections - the directions of the model's stacked body coordinates q = (q_1, ..., q_nb) ordered by
  the whole elastic response at nconf configurations (the arguments as KFBodyCompressDirections'): one set d (v the
  sum of the bodies' v_b), M-orthonormal in blockdiag(M_b), keeping every body's rigid motions (free in a tied
  model, they absorb the joints' interface motions) and (static_exact) the static responses exactly, the rest ordered
  by one SVD of all configurations' snapshots. Each direction has a part in every body: a model made of the leading
  ones ties its bodies (KFReducedModelCompressTied). The model may be tied already (its response lies in its ties'
  span) or split. Freed with KFBodyDirectionsDestroy(1, d). *d NULL: the model reassembled at some configuration has
  fewer rigid and mechanism modes than the scene (its ties cut one; its static response cannot be formed).
*/
PetscErrorCode KFTiedCompressDirections(KFReducedModel m, PetscInt nconf, const PetscReal angles[], const PetscInt nw[], const PetscReal *const w[], const PetscReal *const inw[], PetscBool static_exact, KFBodyDirections **d)
{
  const PetscInt nrev1 = PetscMax(m->nrevolute, 1), a = m->ninputs, nb = m->nb;
  PetscInt       n = 0, o = 0;
  PetscReal     *S, *Gq, *Mblk, *Rblk;

  PetscFunctionBegin;
  PetscValidHeaderSpecific(m, KF_REDUCEDMODEL_CLASSID, 1);
  PetscCheck(nconf >= 1, PetscObjectComm((PetscObject)m), PETSC_ERR_ARG_OUTOFRANGE, "compression needs at least one configuration");
  for (PetscInt b = 0; b < nb; b++) {
    PetscCheck(m->bodies[b].rigid, PetscObjectComm((PetscObject)m), PETSC_ERR_ARG_WRONG, "body '%s' has no rigid motions recorded: compression keeps them exactly", m->bodies[b].name);
    n += m->bodies[b].v;
  }
  PetscCall(PetscCalloc1(1, d));
  PetscCall(PetscCalloc4(n * a * nconf + 1, &S, n * n + 1, &Gq, n * n + 1, &Mblk, n * 6 * nb + 1, &Rblk));
  for (PetscInt b = 0; b < nb; b++) { /* blockdiag(M_b), blockdiag(rigid_b) */
    const PetscInt v = m->bodies[b].v;

    for (PetscInt j = 0; j < v; j++)
      for (PetscInt i = 0; i < v; i++) Mblk[(o + i) + (o + j) * n] = m->bodies[b].M[i + j * v];
    for (PetscInt j = 0; j < 6; j++)
      for (PetscInt i = 0; i < v; i++) Rblk[(o + i) + (6 * b + j) * n] = m->bodies[b].rigid[i + j * v];
    o += v;
  }
  for (PetscInt k = 0; k < nconf; k++) {
    PetscBool ok;

    PetscCall(KFCompressSnapshots(m, m->nrevolute ? &angles[k * nrev1] : NULL, nw[k], w[k], inw ? inw[k] : NULL, static_exact, PETSC_TRUE, k * a, &S, &Gq, &ok));
    if (!ok) { /* no directions: the caller keeps the model */
      PetscCall(PetscFree4(S, Gq, Mblk, Rblk));
      PetscCall(PetscFree(*d));
      PetscFunctionReturn(0);
    }
  }
  PetscCall(KFCompressBody("(all bodies, stacked)", n, Mblk, 6 * nb, Rblk, static_exact ? a * nconf : 0, S, Gq, *d));
  PetscCall(PetscFree4(S, Gq, Mblk, Rblk));
  PetscFunctionReturn(0);
}

/*
  KFReducedModelCompressTied - the model tied to the kept columns of the stacked directions d (KFTiedCompressDirections)
  and its first count directions: each body projected on the span of its rigid motions and its parts of those columns
  (nothing of the model's response is lost by it), and *C[b] (v'_b x *k, allocated here, freed by the caller with
  PetscFree each and the array) the columns' coordinates in the new bodies, from which the caller makes the ties
  (KFCandidateTies_Private). with_map as KFReducedModelCompress's.
*/
PetscErrorCode KFReducedModelCompressTied(KFReducedModel m, const KFBodyDirections *d, PetscInt count, PetscBool with_map, KFReducedModel *out, PetscInt *k, PetscReal ***C)
{
  const PetscInt    nb = m->nb;
  KFBodyDirections *db;
  PetscReal        *Z, *MC;
  PetscInt          o = 0;

  PetscFunctionBegin;
  PetscValidHeaderSpecific(m, KF_REDUCEDMODEL_CLASSID, 1);
  *k = d->nkeep + PetscMin(PetscMax(count, 0), d->ndir);
  PetscCall(PetscCalloc1(nb, &db));
  PetscCall(PetscMalloc1(nb, C));
  for (PetscInt b = 0; b < nb; b++) { /* body b's span: its rigid motions and its rows of the columns, kept exactly */
    const KFModelBody *B = &m->bodies[b];
    const PetscInt     v = B->v;
    PetscReal         *Cb;

    PetscCall(PetscCalloc3(v * *k + 1, &Cb, v * v + 1, &Z, v * *k + 1, &MC));
    for (PetscInt j = 0; j < *k; j++) PetscCall(PetscArraycpy(&Cb[j * v], &d->W[o + j * d->v], v));
    PetscCall(KFCompressBody(B->name, v, B->M, 6, B->rigid, *k, Cb, Z, &db[b]));
    /* the columns in the new coordinates: W_b^T M_b C_b (W_b M_b-orthonormal and spanning C_b) */
    PetscCall(PetscMalloc1(db[b].nkeep * *k + 1, &(*C)[b]));
    KFAB(v, v, *k, B->M, v, Cb, v, MC, v);
    KFAtB(v, db[b].nkeep, *k, db[b].W, v, MC, v, (*C)[b]);
    PetscCall(PetscFree3(Cb, Z, MC));
    o += v;
  }
  PetscCall(KFReducedModelCompress(m, db, NULL, with_map, out));
  PetscCall(KFBodyDirectionsDestroy(nb, &db));
  PetscFunctionReturn(0);
}
