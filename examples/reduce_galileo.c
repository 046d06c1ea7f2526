/*
  reduce_galileo: the reduction of the Galileo-like two-body model (meshes/galileo) with the C library alone.

  Builds the scene of meshes/galileo/galileo.yaml by API calls: the stator and the rotor (M and K from Matrix Market
  files, nodes from the text files), the spin bearing (a revolute joint about z from the stator's interface 'bearing',
  node 1, to the rotor's, node 101), the bearing torque pair as input and the rotation about y at point A (stator
  node 2) as output. Reduces it for the clock angles 0, 15, 30, 45, 60, 72 deg over 0.01-10 Hz with 0.25 % modal
  damping, a 5 % accuracy target and 10 moments (one output block), as the scene file says; every -kf_ option
  overrides these (KFReducerSetFromOptions; -help lists them). Prints the rule that chose alpha_G and the
  frequency-response error at each angle, saves the model, loads it back and reassembles it at a new angle.

    mpiexec -n 2 build/examples/reduce_galileo [-mesh_dir meshes/galileo] [-o galileo-reduced.h5] [-angle 37.5]
                                               [-kf_moments 12] [-kf_reducer_view] [-kf_quiet] ...
*/
#include <kryflex.h>

static const char help[] = "Reduces the Galileo-like model of meshes/galileo and reassembles it at a new angle.\n";

#define MAX_NODES 64

/* "id x y z ndof" lines; '#' starts a comment */
static PetscErrorCode ReadNodes(const char path[], PetscInt *nnodes, PetscInt ids[], PetscReal xyz[], PetscInt ndof[])
{
  FILE    *fp;
  char     line[512];
  PetscInt n = 0;

  PetscFunctionBegin;
  PetscCall(PetscFOpen(PETSC_COMM_SELF, path, "r", &fp));
  while (fgets(line, sizeof(line), fp)) {
    long long id, d;
    double    x, y, z;
    char     *hash = strchr(line, '#');
    if (hash) *hash = 0;
    if (sscanf(line, "%lld %lf %lf %lf %lld", &id, &x, &y, &z, &d) != 5) continue;
    PetscCheck(n < MAX_NODES, PETSC_COMM_SELF, PETSC_ERR_SUP, "%s: more than %d nodes", path, MAX_NODES);
    ids[n]         = (PetscInt)id;
    ndof[n]        = (PetscInt)d;
    xyz[3 * n + 0] = x;
    xyz[3 * n + 1] = y;
    xyz[3 * n + 2] = z;
    n++;
  }
  PetscCall(PetscFClose(PETSC_COMM_SELF, fp));
  PetscCheck(n > 0, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "%s: no node lines (id x y z ndof)", path);
  *nnodes = n;
  PetscFunctionReturn(0);
}

/* <dir>/<name>_M.mtx, <name>_K.mtx, <name>_nodes.txt */
static PetscErrorCode AddBody(KFScene scene, const char dir[], const char name[], PetscInt *body)
{
  char      path[PETSC_MAX_PATH_LEN];
  Mat       M, K;
  PetscInt  nnodes = 0, ids[MAX_NODES], ndof[MAX_NODES];
  PetscReal xyz[3 * MAX_NODES];

  PetscFunctionBegin;
  PetscCall(PetscSNPrintf(path, sizeof(path), "%s/%s_M.mtx", dir, name));
  PetscCall(KFMatLoadFile(PETSC_COMM_WORLD, path, &M));
  PetscCall(PetscSNPrintf(path, sizeof(path), "%s/%s_K.mtx", dir, name));
  PetscCall(KFMatLoadFile(PETSC_COMM_WORLD, path, &K));
  PetscCall(PetscSNPrintf(path, sizeof(path), "%s/%s_nodes.txt", dir, name));
  PetscCall(ReadNodes(path, &nnodes, ids, xyz, ndof));
  PetscCall(KFSceneAddBody(scene, name, M, K, nnodes, ids, xyz, ndof, body));
  PetscCall(MatDestroy(&M)); /* the scene holds its own references */
  PetscCall(MatDestroy(&K));
  PetscFunctionReturn(0);
}

/* the scene of meshes/galileo/galileo.yaml */
static PetscErrorCode GalileoScene(const char dir[], KFScene *scene)
{
  const PetscReal z[3] = {0, 0, 1};
  PetscInt        stator, rotor;

  PetscFunctionBegin;
  PetscCall(KFSceneCreate(PETSC_COMM_WORLD, scene));
  PetscCall(KFSceneSetName(*scene, "galileo"));
  PetscCall(AddBody(*scene, dir, "stator", &stator));
  PetscCall(AddBody(*scene, dir, "rotor", &rotor));
  PetscCall(KFSceneAddInterface(*scene, stator, "bearing", 1));
  PetscCall(KFSceneAddInterface(*scene, rotor, "bearing", 101));
  PetscCall(KFSceneAddJoint(*scene, "spin_bearing", KF_JOINT_REVOLUTE, stator, "bearing", rotor, "bearing", z, NULL));
  PetscCall(KFSceneSetNumIO(*scene, 1, 1));
  /* spin bearing actuator: +torque about z on the stator, -torque on the rotor (component 5: rz) */
  PetscCall(KFSceneAddInputLoad(*scene, 0, stator, 1, 5, 1.0));
  PetscCall(KFSceneAddInputLoad(*scene, 0, rotor, 101, 5, -1.0));
  PetscCall(KFSceneSetIOName(*scene, PETSC_TRUE, 0, "bearing_torque"));
  /* rotation about y at point A on the stator (component 4: ry) */
  PetscCall(KFSceneAddOutputReading(*scene, 0, stator, 2, 4, 1.0));
  PetscCall(KFSceneSetIOName(*scene, PETSC_FALSE, 0, "pointA_ry"));
  PetscCall(KFSceneSetUp(*scene));
  PetscFunctionReturn(0);
}

static PetscBool HasResult(KFReducer r, PetscInt config, const char name[])
{
  PetscInt           n;
  const char *const *names;

  if (KFReducerGetResultNames(r, config, &n, &names)) return PETSC_FALSE;
  for (PetscInt i = 0; i < n; i++)
    if (!strcmp(names[i], name)) return PETSC_TRUE;
  return PETSC_FALSE;
}

int main(int argc, char **argv)
{
  const PetscReal    deg[6] = {0, 15, 30, 45, 60, 72};
  char               dir[PETSC_MAX_PATH_LEN] = "meshes/galileo", out[PETSC_MAX_PATH_LEN] = "galileo-reduced.h5";
  PetscReal          angles[6], angle_deg = 37.5, angle, accuracy = 0.05;
  PetscInt           nconfig = 6, nrev, nang, nnotes, nf, n, nrigid;
  KFScene            scene;
  KFReducer          reducer;
  KFReducedModel     model, loaded;
  KFReducedSystem    sys;
  const char        *rule;
  const char *const *notes;
  const PetscReal   *alpha, *freq;
  PetscMPIInt        size;

  PetscCall(SlepcInitialize(&argc, &argv, NULL, help));
  PetscCallMPI(MPI_Comm_size(PETSC_COMM_WORLD, &size));
  PetscOptionsBegin(PETSC_COMM_WORLD, NULL, "reduce_galileo example", NULL);
  PetscCall(PetscOptionsString("-mesh_dir", "Folder of the Galileo-like model's files (default meshes/galileo)", NULL, dir, dir, sizeof(dir), NULL));
  PetscCall(PetscOptionsString("-o", "Reduced-model file to write (default galileo-reduced.h5)", NULL, out, out, sizeof(out), NULL));
  PetscCall(PetscOptionsReal("-angle", "Clock angle in degrees to reassemble the saved model at (default 37.5)", NULL, angle_deg, &angle_deg, NULL));
  PetscOptionsEnd();

  PetscCall(GalileoScene(dir, &scene));
  PetscCall(KFSceneGetInfo(scene, NULL, NULL, &nrev, &n, NULL, NULL));
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "Galileo-like model from %s: %" PetscInt_FMT " system dofs, %" PetscInt_FMT " revolute joint, on %d rank(s)\n", dir, n, nrev, size));

  /* what the reduction must serve: the scene file's values, then the command line */
  for (PetscInt c = 0; c < nconfig; c++) angles[c] = deg[c] * PETSC_PI / 180;
  PetscCall(KFReducerCreate(PETSC_COMM_WORLD, &reducer));
  PetscCall(KFReducerSetScene(reducer, scene));
  PetscCall(KFReducerSetAngles(reducer, nconfig, angles));
  PetscCall(KFReducerSetBand(reducer, 0.01, 10.0));
  PetscCall(KFReducerSetDamping(reducer, 0.0025));
  PetscCall(KFReducerSetAccuracy(reducer, accuracy));
  PetscCall(KFReducerSetMoments(reducer, 10, 1));
  PetscCall(KFReducerSetImportance(reducer, KF_IMPORTANCE_H2, 0.1)); /* the scene's: the paper's threshold (Tables 2-3) */
  PetscCall(KFReducerSetReductionAngle(reducer, NULL)); /* auto: the paper's rule */
  PetscCall(KFReducerSetFromOptions(reducer));
  PetscCall(KFReducerSetUp(reducer));
  PetscCall(KFReducerSolve(reducer));
  PetscCall(KFReducerViewFromOptions(reducer, NULL, "-kf_reducer_view"));

  /* what the solve did */
  PetscCall(KFReducerGetReductionRule(reducer, &rule));
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "\nreduction rule: %s\n", rule));
  PetscCall(KFReducerGetReducedModel(reducer, &model));
  PetscCall(KFReducedModelGetReductionAngles(model, &nang, &alpha));
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "model built at"));
  for (PetscInt i = 0; i < nang; i++)
    for (PetscInt j = 0; j < nrev; j++) PetscCall(PetscPrintf(PETSC_COMM_WORLD, "%s%g", j ? "/" : (i ? ", " : " "), (double)(alpha[i * nrev + j] * 180 / PETSC_PI)));
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, " deg\n"));
  if (HasResult(reducer, -1, "kept_modes")) {
    const PetscInt  *shape;
    const PetscReal *kept;
    PetscInt         ndim, nk = 1;
    PetscCall(KFReducerGetResult(reducer, -1, "kept_modes", &ndim, &shape, &kept));
    for (PetscInt d = 0; d < ndim; d++) nk *= shape[d];
    PetscCall(PetscPrintf(PETSC_COMM_WORLD, "kept Krylov modes (%" PetscInt_FMT "):", nk));
    for (PetscInt i = 0; i < nk; i++) PetscCall(PetscPrintf(PETSC_COMM_WORLD, " %d", (int)kept[i]));
    PetscCall(PetscPrintf(PETSC_COMM_WORLD, "\n"));
  }
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "\n  angle (deg)   reduced dofs   FRF error (max relative, band)\n"));
  for (PetscInt c = 0; c < nconfig; c++) {
    const PetscReal *err, *dofs;
    PetscCall(KFReducerGetResult(reducer, c, "reduced_dofs", NULL, NULL, &dofs));
    if (HasResult(reducer, c, "frf_error")) {
      PetscCall(KFReducerGetResult(reducer, c, "frf_error", NULL, NULL, &err));
      PetscCall(PetscPrintf(PETSC_COMM_WORLD, "  %10g   %12d   %.3e  %s\n", (double)deg[c], (int)dofs[0], (double)err[0], err[0] <= accuracy ? "" : "(above the target)"));
    } else PetscCall(PetscPrintf(PETSC_COMM_WORLD, "  %10g   %12d   not verified (-kf_verify false)\n", (double)deg[c], (int)dofs[0]));
  }
  PetscCall(KFReducerGetNotes(reducer, &nnotes, &notes));
  for (PetscInt i = 0; i < nnotes; i++) PetscCall(PetscPrintf(PETSC_COMM_WORLD, "note: %s\n", notes[i]));

  /* the model file holds everything reassembly needs: load it back and reassemble at a new angle */
  PetscCall(KFReducedModelSave(model, out));
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "\nreduced model written to %s\n", out));
  PetscCall(KFReducerDestroy(&reducer)); /* the model goes with it; the file remains */
  PetscCall(KFSceneDestroy(&scene));
  PetscCall(KFReducedModelLoad(PETSC_COMM_WORLD, out, &loaded));
  angle = angle_deg * PETSC_PI / 180;
  PetscCall(KFReducedModelReassemble(loaded, &angle, &sys));
  PetscCall(KFReducedSystemGetMatrices(sys, &n, NULL, NULL, NULL, NULL, NULL, NULL));
  PetscCall(KFReducedSystemGetModes(sys, NULL, NULL, &nrigid, NULL));
  PetscCall(KFReducedSystemGetFrequencies(sys, &nf, &freq));
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "reassembled from the file at %g deg: %" PetscInt_FMT " dofs, %" PetscInt_FMT " rigid-body and mechanism modes, flexible frequencies (Hz):\n ", (double)angle_deg, n, nrigid));
  for (PetscInt i = 0; i < nf; i++) PetscCall(PetscPrintf(PETSC_COMM_WORLD, " %.5g", (double)freq[i]));
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "\n"));
  PetscCall(KFReducedSystemDestroy(&sys));
  PetscCall(KFReducedModelDestroy(&loaded));
  PetscCall(SlepcFinalize());
  return 0;
}
