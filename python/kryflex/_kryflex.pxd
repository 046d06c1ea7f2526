# The C API of src/include/kryflex.h, for the binding (_core.pyx). PETSc's handle types come from petsc4py and
# SLEPc's from slepc4py; the scalar typedefs are extern, as petsc4py declares them, so that the C compiler uses
# the sizes PETSc was built with (64-bit PetscInt included): Cython never assumes them.

from petsc4py.PETSc cimport MPI_Comm, PetscMat, PetscObject, PetscVec, PetscViewer
from slepc4py.SLEPc cimport SlepcBV

cdef extern from "petscsys.h" nogil:
    ctypedef long PetscInt
    ctypedef double PetscReal
    ctypedef int PetscErrorCode
    ctypedef enum PetscBool:
        PETSC_FALSE
        PETSC_TRUE
    PetscErrorCode PetscObjectReference(PetscObject)
    PetscErrorCode PetscObjectDereference(PetscObject)
    PetscErrorCode PetscObjectDestroy(PetscObject*)
    PetscErrorCode PetscObjectGetComm(PetscObject, MPI_Comm*)
    PetscErrorCode PetscOptionsLeftGet(void*, PetscInt*, char***, char***)
    PetscErrorCode PetscOptionsLeftRestore(void*, PetscInt*, char***, char***)
    PetscBool PetscInitializeCalled
    PetscBool PetscFinalizeCalled

cdef extern from "mpi.h" nogil:
    int MPI_Comm_size(MPI_Comm, int*)

cdef extern from "petsc/private/garbagecollector.h" nogil:
    # what petsc4py's objects are released through: destroyed later, together, by PetscGarbageCleanup
    PetscErrorCode PetscObjectDelayedDestroy(PetscObject*)

cdef extern from "slepcbv.h" nogil:
    PetscErrorCode BVGetActiveColumns(SlepcBV, PetscInt*, PetscInt*)

cdef extern from "kryflex.h" nogil:
    # ------------------------------------------------------------ scene
    ctypedef struct _n_KFScene
    ctypedef _n_KFScene* KFScene
    ctypedef enum KFJointType:
        KF_JOINT_REVOLUTE
        KF_JOINT_FIXED

    PetscErrorCode KFInitialize()
    PetscErrorCode KFSceneCreate(MPI_Comm, KFScene*)
    PetscErrorCode KFSceneDestroy(KFScene*)
    PetscErrorCode KFSceneAddBody(KFScene, const char*, PetscMat, PetscMat, PetscInt, const PetscInt*, const PetscReal*, const PetscInt*, PetscInt*)
    PetscErrorCode KFSceneAddInterface(KFScene, PetscInt, const char*, PetscInt)
    PetscErrorCode KFSceneAddJoint(KFScene, const char*, KFJointType, PetscInt, const char*, PetscInt, const char*, const PetscReal*, const PetscReal*)
    PetscErrorCode KFSceneAddConstraint(KFScene, PetscInt, PetscInt, const char*)
    PetscErrorCode KFSceneAddBodyComponents(KFScene, const char*, PetscMat, PetscMat, PetscInt, const PetscInt*, const PetscReal*, const PetscInt*, PetscInt*)
    PetscErrorCode KFSceneAddSpring(KFScene, PetscInt, PetscInt, PetscInt, PetscReal)
    PetscErrorCode KFSceneGetRigidCount(KFScene, PetscInt*)
    PetscErrorCode KFSceneSetNumIO(KFScene, PetscInt, PetscInt)
    PetscErrorCode KFSceneAddInputLoad(KFScene, PetscInt, PetscInt, PetscInt, PetscInt, PetscReal)
    PetscErrorCode KFSceneAddInputVector(KFScene, PetscInt, PetscInt, PetscVec)
    PetscErrorCode KFSceneAddOutputReading(KFScene, PetscInt, PetscInt, PetscInt, PetscInt, PetscReal)
    PetscErrorCode KFSceneAddOutputVector(KFScene, PetscInt, PetscInt, PetscVec)
    PetscErrorCode KFSceneSetUp(KFScene)
    PetscErrorCode KFSceneGetInfo(KFScene, PetscInt*, PetscInt*, PetscInt*, PetscInt*, PetscInt*, PetscInt*)
    PetscErrorCode KFSceneGetBodyInfo(KFScene, PetscInt, const char**, PetscInt*, PetscInt*)
    PetscErrorCode KFSceneGetBodyMatrices(KFScene, PetscInt, PetscMat*, PetscMat*, PetscMat*, PetscMat*)
    PetscErrorCode KFSceneGetBodySymmetric(KFScene, PetscInt, PetscBool*, PetscBool*)
    PetscErrorCode KFSceneView(KFScene, PetscViewer)
    PetscErrorCode KFMatLoadFile(MPI_Comm, const char*, PetscMat*)

    # ------------------------------------------------------------ full-order system, K+, Krylov basis, projection
    ctypedef struct _n_KFSystem
    ctypedef _n_KFSystem* KFSystem
    ctypedef struct _p_KFFlexSolver
    ctypedef _p_KFFlexSolver* KFFlexSolver
    ctypedef struct _n_KFBodyBasis
    ctypedef _n_KFBodyBasis* KFBodyBasis

    PetscErrorCode KFSystemCreate(KFScene, KFSystem*)
    PetscErrorCode KFSystemDestroy(KFSystem*)
    PetscErrorCode KFSystemSetAngles(KFSystem, const PetscReal*)
    PetscErrorCode KFSystemGetMatrices(KFSystem, PetscMat*, PetscMat*, PetscMat*, PetscMat*)
    PetscErrorCode KFSystemGetBodyMap(KFSystem, PetscInt, PetscMat*)
    PetscErrorCode KFSystemComputeRigidModes(KFSystem)
    PetscErrorCode KFSystemSetRigidModes(KFSystem, PetscMat)
    PetscErrorCode KFSystemGetRigidModes(KFSystem, PetscMat*, PetscReal*)
    PetscErrorCode KFSystemGetRigidProducts(KFSystem, PetscMat*, PetscMat*)
    PetscErrorCode KFSystemRigidIO(KFSystem, PetscInt*, PetscReal*, PetscReal*)
    PetscErrorCode KFSystemEigen(KFSystem, PetscInt, PetscInt*, PetscReal*, PetscReal*, PetscReal*)
    PetscErrorCode KFSystemEigenModes(KFSystem, PetscInt, PetscInt*, PetscReal*, PetscMat*)
    PetscErrorCode KFSystemCountModesBelow(KFSystem, PetscReal, PetscInt*)
    PetscErrorCode KFSystemProject(KFSystem, SlepcBV, PetscReal*, PetscReal*, PetscReal*, PetscReal*)
    PetscErrorCode KFBVCombine(SlepcBV, PetscInt, const PetscReal*, PetscMat*)
    PetscErrorCode KFMatCombine(PetscMat, PetscInt, const PetscReal*, PetscMat*)
    PetscErrorCode KFMatInner(PetscMat, PetscMat, PetscReal*)
    PetscErrorCode KFFlexSolverCreate(KFSystem, KFFlexSolver*)
    PetscErrorCode KFFlexSolverSetShift(KFFlexSolver, PetscReal)
    PetscErrorCode KFFlexSolverSetUp(KFFlexSolver)
    PetscErrorCode KFFlexSolverApply(KFFlexSolver, PetscMat, PetscMat)
    PetscErrorCode KFFlexSolverDestroy(KFFlexSolver*)
    PetscErrorCode KFFlexSolverGetStats(KFFlexSolver, PetscInt*, PetscInt*, PetscInt*)
    ctypedef const char* KFFlexSolverType
    PetscErrorCode KFFlexSolverSetType(KFFlexSolver, const char*)
    PetscErrorCode KFFlexSolverGetType(KFFlexSolver, KFFlexSolverType*)
    PetscErrorCode KFSystemGetFactorCount(KFSystem, PetscInt*)
    PetscErrorCode KFFlexSolverMoments(KFFlexSolver, PetscInt, PetscReal*)
    PetscErrorCode KFKrylovBasis(KFFlexSolver, PetscInt, PetscInt, PetscReal, SlepcBV*, PetscInt*)
    PetscErrorCode KFKrylovRawBasis(KFFlexSolver, PetscInt, PetscInt, PetscMat*, PetscReal*)
    PetscErrorCode KFBodyBasisCreate(KFScene, KFBodyBasis*)
    PetscErrorCode KFBodyBasisAdd(KFBodyBasis, KFSystem, PetscMat)
    PetscErrorCode KFBodyBasisFinish(KFBodyBasis, PetscReal)
    PetscErrorCode KFBodyBasisDestroy(KFBodyBasis*)
    PetscErrorCode KFBodyBasisGetReduced(KFBodyBasis, PetscInt, PetscInt*, const PetscReal**, const PetscReal**, const PetscReal**, const PetscReal**, PetscInt*, const PetscReal**, const PetscReal**, PetscInt*)
    PetscErrorCode KFBodyBasisGetMap(KFBodyBasis, PetscInt, PetscMat*)

    # ------------------------------------------------------------ small dense algebra
    ctypedef enum KFImportance:
        KF_IMPORTANCE_H2
        KF_IMPORTANCE_HINF
        KF_IMPORTANCE_STATIC
        KF_IMPORTANCE_BAND
    ctypedef struct KFReducedBody:
        PetscInt v
        const PetscReal *M
        const PetscReal *K
        const PetscReal *G
        const PetscReal *H
        PetscInt ninterfaces
        const PetscReal *iface
        const PetscReal *rigid
    ctypedef struct KFJointDef:
        KFJointType type
        PetscInt parent, parent_interface, child, child_interface
        PetscReal axis[3]
        PetscReal R0[9]

    PetscErrorCode KFDenseEig(PetscInt, const PetscReal*, const PetscReal*, PetscReal*, PetscReal*)
    PetscErrorCode KFDenseModeImportance(PetscInt, const PetscReal*, const PetscReal*, PetscInt, const PetscReal*, PetscInt, const PetscReal*, PetscReal, KFImportance, PetscReal, PetscReal*)
    PetscErrorCode KFDenseModeImportanceBand(PetscInt, const PetscReal*, const PetscReal*, PetscInt, const PetscReal*, PetscInt, const PetscReal*, PetscReal, const PetscReal*, PetscReal, PetscReal, PetscReal*, PetscInt*)
    PetscErrorCode KFModalHankelSingularValues(PetscInt, const PetscReal*, PetscInt, const PetscReal*, PetscInt, const PetscReal*, PetscReal, PetscReal*)
    PetscErrorCode KFDenseStaticCorrection(PetscInt, PetscInt, const PetscReal*, const PetscReal*, PetscInt, const PetscReal*, PetscReal*)
    PetscErrorCode KFDenseNullSpace(PetscInt, PetscInt, const PetscReal*, PetscReal, PetscInt*, PetscReal*, PetscInt*, PetscReal*)
    PetscErrorCode KFDenseMoments(PetscInt, const PetscReal*, const PetscReal*, PetscInt, const PetscReal*, PetscInt, const PetscReal*, PetscReal, PetscInt, PetscReal*)
    PetscErrorCode KFDenseMomentsRigid(PetscInt, const PetscReal*, const PetscReal*, PetscInt, const PetscReal*, PetscInt, const PetscReal*, PetscInt, const PetscReal*, PetscInt, PetscReal*)
    PetscErrorCode KFModalFRF(PetscInt, const PetscReal*, PetscInt, const PetscReal*, PetscInt, const PetscReal*, PetscReal, PetscReal, PetscInt, const PetscReal*, PetscReal*, PetscReal*)
    PetscErrorCode KFReassemble(PetscInt, const KFReducedBody*, PetscInt, const KFJointDef*, const PetscReal*, PetscInt, PetscInt, PetscReal, PetscInt*, PetscReal*, PetscReal*, PetscReal*, PetscReal*, PetscInt*, PetscReal*, PetscInt*, PetscReal*)
    PetscErrorCode KFJointRotation(const PetscReal*, const PetscReal*, PetscReal, PetscReal*)

    # ------------------------------------------------------------ progress and errors
    PetscErrorCode KFProgress(MPI_Comm, const char*, ...)
    PetscErrorCode KFPushErrorRecorder()
    const char *KFLastError()
    void KFClearError()
    enum: KF_ERR_INTERRUPTED
    PetscErrorCode KFInterruptCatch()
    PetscErrorCode KFInterruptCheck(MPI_Comm)
    int KFInterruptSignal()

    # ------------------------------------------------------------ reduced model and reduced system
    ctypedef struct _n_KFReducedSystem
    ctypedef _n_KFReducedSystem* KFReducedSystem
    ctypedef struct _p_KFReducedModel
    ctypedef _p_KFReducedModel* KFReducedModel

    PetscErrorCode KFReducedSystemGetMatrices(KFReducedSystem, PetscInt*, PetscInt*, PetscInt*, const PetscReal**, const PetscReal**, const PetscReal**, const PetscReal**)
    PetscErrorCode KFReducedSystemGetModes(KFReducedSystem, const PetscReal**, const PetscReal**, PetscInt*, const PetscReal**)
    PetscErrorCode KFReducedSystemGetReassemblyInfo(KFReducedSystem, PetscInt*, PetscReal*)
    PetscErrorCode KFReducedSystemGetFrequencies(KFReducedSystem, PetscInt*, const PetscReal**)
    PetscErrorCode KFReducedSystemMoments(KFReducedSystem, PetscInt, PetscReal*)
    PetscErrorCode KFReducedSystemGetTrim(KFReducedSystem, PetscInt*, PetscReal*, PetscReal*, const PetscReal**)
    PetscErrorCode KFReducedSystemTrim(KFReducedSystem, PetscReal)
    PetscErrorCode KFParseMaxFrequency(MPI_Comm, const char*, PetscReal*, PetscBool*)
    PetscErrorCode KFReducedSystemFRF(KFReducedSystem, PetscReal, PetscInt, const PetscReal*, PetscReal*, PetscReal*)
    PetscErrorCode KFReducedSystemView(KFReducedSystem, PetscViewer)
    PetscErrorCode KFReducedSystemDestroy(KFReducedSystem*)

    PetscErrorCode KFReducedModelCreateFromBodyBasis(KFScene, KFBodyBasis, PetscInt, const PetscReal*, PetscBool, KFReducedModel*)
    PetscErrorCode KFReducedModelDestroy(KFReducedModel*)
    PetscErrorCode KFReducedModelView(KFReducedModel, PetscViewer)
    PetscErrorCode KFReducedModelGetInfo(KFReducedModel, PetscInt*, PetscInt*, PetscInt*, PetscInt*, PetscInt*, PetscInt*)
    PetscErrorCode KFReducedModelGetSceneName(KFReducedModel, const char**, const char**)
    PetscErrorCode KFReducedModelGetReductionAngles(KFReducedModel, PetscInt*, const PetscReal**)
    PetscErrorCode KFReducedModelGetBody(KFReducedModel, PetscInt, const char**, PetscInt*, KFReducedBody*, const PetscReal**)
    PetscErrorCode KFReducedModelGetInterfaceName(KFReducedModel, PetscInt, PetscInt, const char**)
    PetscErrorCode KFReducedModelGetJoint(KFReducedModel, PetscInt, const char**, KFJointDef*)
    PetscErrorCode KFReducedModelGetIOName(KFReducedModel, PetscBool, PetscInt, const char**)
    PetscErrorCode KFReducedModelSetSetting(KFReducedModel, const char*, const char*)
    PetscErrorCode KFReducedModelGetSettings(KFReducedModel, PetscInt*, const char * const **, const char * const **)
    PetscErrorCode KFReducedModelReassemble(KFReducedModel, const PetscReal*, KFReducedSystem*)
    ctypedef struct _n_KFReassembly
    ctypedef _n_KFReassembly* KFReassembly
    PetscErrorCode KFReducedModelCreateReassembly(KFReducedModel, KFReassembly*)
    PetscErrorCode KFReassemblyGetSizes(KFReassembly, PetscInt*, PetscInt*, PetscInt*, PetscBool*, PetscBool*)
    PetscErrorCode KFReassemblyApply(KFReassembly, const PetscReal*, PetscInt*, PetscReal*, PetscReal*, PetscReal*, PetscReal*, PetscReal*, PetscInt*, PetscReal*, PetscInt*, PetscReal*)
    PetscErrorCode KFReassemblyEig(KFReassembly, PetscInt, const PetscReal*, const PetscReal*, PetscInt, const PetscReal*, PetscReal*, PetscReal*)
    PetscErrorCode KFReassemblyDestroy(KFReassembly*)
    PetscErrorCode KFReassemblySetUseSVD(KFReassembly, PetscBool)
    PetscErrorCode KFReassemblyGetUseSVD(KFReassembly, PetscBool*)
    PetscErrorCode KFSceneGetFingerprint(KFScene, char*)
    PetscErrorCode KFSceneSetName(KFScene, const char*)
    PetscErrorCode KFSceneGetName(KFScene, const char**)
    PetscErrorCode KFSceneSetIOName(KFScene, PetscBool, PetscInt, const char*)
    PetscErrorCode KFSceneGetIOName(KFScene, PetscBool, PetscInt, const char**)
    PetscErrorCode KFReducedModelSave(KFReducedModel, const char*)
    PetscErrorCode KFReducedModelLoad(MPI_Comm, const char*, KFReducedModel*)

    # ------------------------------------------------------------ error measures (src/measure)
    PetscErrorCode KFFRFErrors(PetscInt, PetscInt, PetscInt, const PetscReal*, const PetscReal*, const PetscReal*, const PetscReal*, PetscReal, PetscReal*, PetscReal*)
    PetscErrorCode KFFRFElasticErrors(PetscInt, PetscInt, PetscInt, const PetscReal*, const PetscReal*, const PetscReal*, const PetscReal*, const PetscReal*, const PetscReal*, PetscReal, PetscReal*, PetscReal*)
    PetscErrorCode KFFRFPairFloors(PetscInt, PetscInt, PetscInt, const PetscReal*, const PetscReal*, const PetscReal*, const PetscReal*, PetscInt*)
    PetscErrorCode KFMomentErrors(PetscInt, PetscInt, PetscInt, PetscInt, const PetscReal*, PetscInt, const PetscReal*, PetscReal, PetscReal*, PetscReal*)
    PetscErrorCode KFRigidTolerance(PetscInt, const PetscReal*, PetscInt, PetscReal*)
    PetscErrorCode KFFrequencyGrid(PetscReal, PetscReal, PetscInt, PetscInt, const PetscReal*, PetscReal, PetscInt*, PetscReal*)

    # ------------------------------------------------------------ the reducer (KFReducer)
    ctypedef struct _p_KFReducer
    ctypedef _p_KFReducer* KFReducer
    ctypedef const char* KFReducerType
    ctypedef enum KFReducerMethod:
        KF_METHOD_SINGLE_ANGLE
        KF_METHOD_MULTI_ANGLE
        KF_METHOD_AUTO

    PetscErrorCode KFReducerCreate(MPI_Comm, KFReducer*)
    PetscErrorCode KFReducerDestroy(KFReducer*)
    PetscErrorCode KFReducerSetType(KFReducer, KFReducerType)
    PetscErrorCode KFReducerGetType(KFReducer, KFReducerType*)
    PetscErrorCode KFReducerSetOptionsPrefix(KFReducer, const char*)
    PetscErrorCode KFReducerSetScene(KFReducer, KFScene)
    PetscErrorCode KFReducerGetScene(KFReducer, KFScene*)
    PetscErrorCode KFReducerSetSystem(KFReducer, KFSystem)
    PetscErrorCode KFReducerSetAngles(KFReducer, PetscInt, const PetscReal*)
    PetscErrorCode KFReducerGetAngles(KFReducer, PetscInt*, const PetscReal**)
    PetscErrorCode KFReducerSetReductionAngle(KFReducer, const PetscReal*)
    PetscErrorCode KFReducerSetMultiAngles(KFReducer, PetscInt, const PetscReal*)
    PetscErrorCode KFReducerSetMethod(KFReducer, KFReducerMethod)
    PetscErrorCode KFReducerSetBand(KFReducer, PetscReal, PetscReal)
    PetscErrorCode KFReducerSetDamping(KFReducer, PetscReal)
    PetscErrorCode KFReducerSetAccuracy(KFReducer, PetscReal)
    ctypedef enum KFAccuracyMeasure:
        KF_ACCURACY_ELASTIC
        KF_ACCURACY_TOTAL
    PetscErrorCode KFReducerSetAccuracyMeasure(KFReducer, KFAccuracyMeasure)
    PetscErrorCode KFReducerGetAccuracyMeasure(KFReducer, KFAccuracyMeasure*)
    PetscErrorCode KFReducerSetMoments(KFReducer, PetscInt, PetscInt)
    PetscErrorCode KFReducerSetSearch(KFReducer, PetscBool, PetscInt)
    PetscErrorCode KFReducerSetClusterTolerance(KFReducer, PetscReal)
    PetscErrorCode KFReducerSetCompress(KFReducer, PetscBool)
    PetscErrorCode KFReducerSetStaticExact(KFReducer, PetscBool)
    PetscErrorCode KFReducerSetImportance(KFReducer, KFImportance, PetscReal)
    PetscErrorCode KFReducerSetStaticCorrection(KFReducer, PetscBool)
    PetscErrorCode KFReducerSetTolerances(KFReducer, PetscReal, PetscReal, PetscReal)
    PetscErrorCode KFReducerSetMaxFrequency(KFReducer, PetscReal, PetscBool)
    PetscErrorCode KFReducerGetMaxFrequency(KFReducer, PetscReal*)
    PetscErrorCode KFReducerSetShift(KFReducer, PetscReal)
    PetscErrorCode KFReducerSetSaveMaps(KFReducer, PetscInt)
    PetscErrorCode KFReducerEigenSetCover(KFReducer, PetscReal)
    PetscErrorCode KFReducerSetVerification(KFReducer, PetscBool, PetscInt, PetscInt, PetscReal)
    PetscErrorCode KFReducerSetVerificationAuto(KFReducer, PetscInt)
    PetscErrorCode KFReducerGetVerificationPlan(KFReducer, PetscBool*, PetscBool*)
    PetscErrorCode KFReducerSetCountSource(KFReducer, int)
    PetscErrorCode KFReducerCertifyCountWrite(KFReducer, int)
    PetscErrorCode KFReducerSetFromOptions(KFReducer)
    PetscErrorCode KFReducerSetUp(KFReducer)
    PetscErrorCode KFReducerSolve(KFReducer)
    PetscErrorCode KFReducerView(KFReducer, PetscViewer)
    PetscErrorCode KFReducerGetReducedModel(KFReducer, KFReducedModel*)
    PetscErrorCode KFReducerGetReducedModels(KFReducer, KFReducedModel*, KFReducedModel*)
    PetscErrorCode KFReducerGetResultNames(KFReducer, PetscInt, PetscInt*, const char * const **)
    PetscErrorCode KFReducerGetResult(KFReducer, PetscInt, const char*, PetscInt*, const PetscInt**, const PetscReal**)
    PetscErrorCode KFReducerGetNotes(KFReducer, PetscInt*, const char * const **)
    PetscErrorCode KFReducerGetReductionRule(KFReducer, const char**)

cdef extern from "kryflex.h" nogil:
    # ------------------------------------------------------------ damping and output quantities
    enum: KF_MAX_DAMPING_BANDS
    ctypedef struct KFDamping:
        PetscInt nbands
        PetscReal fmax_hz[16]
        PetscReal zeta[16]
        PetscReal alpha
        PetscReal beta
        PetscReal g
    ctypedef enum KFQuantity:
        KF_QUANTITY_DISPLACEMENT
        KF_QUANTITY_VELOCITY
        KF_QUANTITY_ACCELERATION
    PetscErrorCode KFDampingSetUniform(KFDamping*, PetscReal)
    PetscReal KFDampingModalRatio(const KFDamping*, PetscReal)
    PetscErrorCode KFSceneSetBodyDamping(KFScene, PetscInt, PetscMat)
    PetscErrorCode KFSceneSetOutputQuantity(KFScene, PetscInt, KFQuantity)
    PetscErrorCode KFSceneGetOutputQuantity(KFScene, PetscInt, KFQuantity*)
    PetscErrorCode KFReducedModelSetDamping(KFReducedModel, const KFDamping*)
    PetscErrorCode KFReducedModelGetDamping(KFReducedModel, KFDamping*)
    PetscErrorCode KFReducedModelGetOutputQuantities(KFReducedModel, const PetscInt**)
    PetscErrorCode KFReducedModelGetBodyDamping(KFReducedModel, PetscInt, const PetscReal**)
    PetscErrorCode KFReducedModelGetTies(KFReducedModel, PetscInt*, PetscInt*, const PetscReal**)
    PetscErrorCode KFReducedSystemGetDamping(KFReducedSystem, const PetscReal**, KFDamping*)
    PetscErrorCode KFReducedSystemResponse(KFReducedSystem, PetscInt, const PetscReal*, PetscReal*, PetscReal*)
    PetscErrorCode KFReducedSystemRigidResponse(KFReducedSystem, PetscInt, const PetscReal*, PetscReal*, PetscReal*)
    PetscErrorCode KFReducerSetDampingModel(KFReducer, const KFDamping*)
    PetscErrorCode KFReducerGetDampingModel(KFReducer, KFDamping*)
    ctypedef enum KFSettingType:
        KF_SETTING_BOOL
        KF_SETTING_INT
        KF_SETTING_REAL
        KF_SETTING_ENUM
        KF_SETTING_STRING
        KF_SETTING_LIST
    const char *const KFSettingTypes[]
    ctypedef struct KFSettingInfo:
        const char *name
        KFSettingType type
        const char *default "def"
        const char *range
        const char *choices
        const char *help
        const char *scene
        const char *object
        const char *setter
    PetscErrorCode KFSettingsTableGet(const KFSettingInfo**, PetscInt*)
