/* The fingerprint of a scene: what a reduced model must agree with to stand for the scene. */
#include <kryflex_impl.h>

/* 64-bit FNV-1a: tiny, deterministic on every platform and rank; this is an identity check, not security */
#define KF_FNV_OFFSET 0xcbf29ce484222325ULL
#define KF_FNV_PRIME  0x100000001b3ULL

static void FNVText(unsigned long long *h, const char text[])
{
  for (const unsigned char *c = (const unsigned char *)text; *c; c++) {
    *h ^= *c;
    *h *= KF_FNV_PRIME;
  }
}

/* one field of the canonical text: its characters and a newline (names cannot hide a field boundary unless they
   contain newlines, which scene names never do) */
static void FNVField(unsigned long long *h, const char text[])
{
  FNVText(h, text);
  FNVText(h, "\n");
}

static PetscErrorCode FNVInt(unsigned long long *h, PetscInt i)
{
  char buf[32];

  PetscFunctionBegin;
  PetscCall(PetscSNPrintf(buf, sizeof(buf), "%" PetscInt_FMT, i));
  FNVField(h, buf);
  PetscFunctionReturn(0);
}

/* an axis component rounded to 12 decimals, like the Python face did; -0 and 0 are the same axis */
static PetscErrorCode FNVAxis(unsigned long long *h, PetscReal x)
{
  char buf[64];

  PetscFunctionBegin;
  PetscCall(PetscSNPrintf(buf, sizeof(buf), "%.12f", (double)x));
  if (buf[0] == '-') {
    PetscBool zero = PETSC_TRUE;
    for (const char *c = buf + 1; *c; c++)
      if (*c != '0' && *c != '.') zero = PETSC_FALSE;
    if (zero) PetscCall(PetscSNPrintf(buf, sizeof(buf), "%.12f", 0.0));
  }
  FNVField(h, buf);
  PetscFunctionReturn(0);
}

/*
  KFSceneGetFingerprint - 16 hex digits identifying a scene's structure: the FNV-1a hash of the canonical text

    kryflex-scene-1
    bodies <nb>      then per body: name, dofs, number of interfaces, interface names (and, for a body with
                     clamped dofs, "clamped", their count and their body dof indices)
    joints <nj>      then per joint: name, revolute|fixed, parent name, child name, parent interface name,
                     child interface name, axis x y z (%.12f; a fixed joint's axis is ignored and written 0 0 1)
    inputs <a>       then the input names
    outputs <t>      then the output names

  one field per line. Matrices, node coordinates and loads do not enter: a model must be reduced again when they
  change, but the fingerprint only guards against using a model with a scene of a different shape.
*/
PetscErrorCode KFSceneGetFingerprint(KFScene s, char fp[17])
{
  unsigned long long h = KF_FNV_OFFSET;

  PetscFunctionBegin;
  PetscValidHeaderSpecific(s, KF_SCENE_CLASSID, 1);
  FNVField(&h, "kryflex-scene-1");
  FNVField(&h, "bodies");
  PetscCall(FNVInt(&h, s->nb));
  for (PetscInt b = 0; b < s->nb; b++) {
    KFBodyData *B = &s->bodies[b];
    FNVField(&h, B->name);
    PetscCall(FNVInt(&h, B->n));
    PetscCall(FNVInt(&h, B->ninterfaces));
    for (PetscInt i = 0; i < B->ninterfaces; i++) FNVField(&h, B->iface[i].name);
    /* boundary conditions change the reduced bodies (clamped dofs read zero): a body with any enters them (sorted
       at set-up); a body without keeps the fingerprint it always had */
    if (B->nclamp) {
      FNVField(&h, "clamped");
      PetscCall(FNVInt(&h, B->nclamp));
      for (PetscInt k = 0; k < B->nclamp; k++) PetscCall(FNVInt(&h, B->clamp[k]));
    }
  }
  FNVField(&h, "joints");
  PetscCall(FNVInt(&h, s->nj));
  for (PetscInt j = 0; j < s->nj; j++) {
    KFJointData *J = &s->joints[j];
    FNVField(&h, J->name);
    FNVField(&h, J->type == KF_JOINT_REVOLUTE ? "revolute" : "fixed");
    FNVField(&h, s->bodies[J->parent].name);
    FNVField(&h, s->bodies[J->child].name);
    FNVField(&h, s->bodies[J->parent].iface[J->parent_iface].name);
    FNVField(&h, s->bodies[J->child].iface[J->child_iface].name);
    for (int c = 0; c < 3; c++) PetscCall(FNVAxis(&h, J->axis[c]));
  }
  for (int pass = 0; pass < 2; pass++) {
    PetscInt n = pass ? s->noutputs : s->ninputs;
    FNVField(&h, pass ? "outputs" : "inputs");
    PetscCall(FNVInt(&h, n));
    for (PetscInt i = 0; i < n; i++) FNVField(&h, pass ? s->output_names[i] : s->input_names[i]);
  }
  PetscCall(PetscSNPrintf(fp, 17, "%016llx", h));
  PetscFunctionReturn(0);
}
