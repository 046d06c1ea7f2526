/* Private data of the reduced model (src/model, src/io): not part of the public API. */
#ifndef KRYFLEX_MODELIMPL_H
#define KRYFLEX_MODELIMPL_H

#include <kryflex_impl.h>

/* HDF5 file format written by KFReducedModelSave and accepted by KFReducedModelLoad */
#define KF_MODEL_FORMAT  "kryflex-reduced-model"
#define KF_MODEL_VERSION 2

/* One reduced body; arrays column-major, replicated, owned by the model. */
typedef struct {
  char       name[KF_MAX_NAME];
  PetscInt   full_dofs;
  PetscInt   v, ninterfaces;
  char     (*iface_names)[KF_MAX_NAME];
  PetscReal *M, *K, *G, *H; /* v x v, v x v, v x a, t x v */
  PetscReal *iface;         /* (6 ninterfaces) x v */
  PetscReal *rigid;         /* v x 6 */
  PetscReal *map;           /* full_dofs x v, or NULL when not kept */
  PetscReal *C;             /* v x v reduced viscous damping Psi^T C_b Psi, or NULL */
} KFModelBody;

struct _KFReducedModelOps {
  PetscErrorCode (*view)(KFReducedModel, PetscViewer);
};

struct _p_KFReducedModel {
  PETSCHEADER(struct _KFReducedModelOps);
  char          scene_name[PETSC_MAX_PATH_LEN];
  char          fingerprint[17];
  PetscInt      nb, nj, nrevolute, ninputs, noutputs;
  PetscInt      nrigid;      /* rigid-body and mechanism modes of the scene (-1: unknown; setting rigid_modes) */
  KFModelBody  *bodies;
  char        (*joint_names)[KF_MAX_NAME];
  KFJointDef   *joints;      /* revolute joints in revolute order, as KFReassemble consumes the angles */
  char        (*input_names)[KF_MAX_NAME], (*output_names)[KF_MAX_NAME];
  PetscInt      nangles;     /* reduction configurations */
  PetscReal    *angles;      /* nangles x nrevolute, row by row, radians */
  PetscInt      nsettings, nsettings_alloc;
  char        **keys, **values;
  KFDamping     damping;     /* modal, Rayleigh, structural (src/model/damping.c) */
  PetscInt     *quantity;    /* per output a KFQuantity */
  PetscInt      nties;       /* coordinate ties between the bodies (shared directions), 0: none */
  PetscReal    *ties;        /* nties x (sum of the bodies' v), column-major, or NULL */
};

/* A reassembled model at one configuration (plain data). */
struct _n_KFReducedSystem {
  PetscInt   n, a, t;
  PetscInt   nrigid;         /* from Phir, or 6 + revolute joints when the bodies' rigid motions are unknown */
  PetscInt   nrigid_expected; /* 6 + revolute joints */
  PetscBool  phir_known;
  PetscInt   rank;
  PetscReal  sratio;
  PetscReal *M, *K, *G, *H;  /* n x n, n x n, n x a, t x n */
  PetscReal *lambda, *Phi;   /* n, n x n */
  PetscReal *Phir;           /* n x nrigid, or NULL */
  PetscInt   nf;
  PetscReal *freq;           /* nf flexible frequencies, Hz */
  PetscReal *HPhi, *PhiG;    /* t x n, n x a: made by the first frequency response */
  KFDamping  damping;        /* the model's */
  PetscInt  *quantity;       /* t, the model's output quantities */
  PetscReal *C;              /* n x n viscous damping (bodies' C_b reassembled + alpha M + beta K), or NULL */
  PetscReal *Cm;             /* Phi^T C Phi, made by the first damped response */
  PetscInt   ntrimmed;       /* flexible modes taken out above fmax_trim (src/model/trim.c), 0: none */
  PetscReal  fmax_trim;      /* the trimming limit (Hz), 0: off */
  PetscReal  ftop_untrimmed; /* the highest flexible frequency before trimming (Hz) */
  PetscReal *D;              /* t x a quasi-static feedthrough of the trimmed modes, or NULL */
};

/* src/model/trim.c: the feedthrough's share of a frequency response */
PETSC_INTERN PetscErrorCode KFReducedSystemAddFeedthrough_Private(KFReducedSystem, const PetscInt quantity[], PetscInt nw, const PetscReal w[], PetscReal Tre[], PetscReal Tim[]);

/* an empty model on comm, with counts set and arrays allocated for nb bodies, nj joints, a inputs, t outputs */
PETSC_INTERN PetscErrorCode KFReducedModelCreateEmpty_Private(MPI_Comm, PetscInt nb, PetscInt nj, PetscInt a, PetscInt t, KFReducedModel *);

#endif
