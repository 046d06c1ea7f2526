import collections,sys,re
HZ=float(sys.argv[2])
B=[('gs-health','KFKrylovHealth'),('gs-chain','KFChainNext|KFChainComplement'),('gs-passes','KFMBasisPasses|KFMBasisProjectOut'),('gs-append-rest','KFMBasisAppend'),
   ('residual','KFFlexSolverResidual|KFMatMultExtended'),('solve','dmumps_sol|KFMumpsMatSolve|dmumps_solve|KFFlexSolverSolve'),('analysis','dmumps_ana|SCOTCH|KFMumpsAnalyse|mumps_ana'),('factor','dmumps_fac|KFMumpsFactor'),
   ('project','KFProject|KFSystemProject'),('bodybasis','KFBodyBasis|KFReducerMakeModel'),('rigid','KFSystemComputeRigid|KFSystemGetRigid'),('assemble','KFSystemSetAngles|KFSystemSum'),('load','KFMatLoad|KFCheckPetscBinary|MatLoad|KFScene'),
   ('krylov-other','KFKrylovBasis'),('reducer-other','KFReducer'),('mumps-other','dmumps|mumps'),('python','Py|_start')]
c=collections.Counter();tot=0;stack=[]
def flush(st):
    global tot
    if not st:return
    tot+=1
    j=' '.join(st)
    for name,pat in B:
        if re.search(pat,j): c[name]+=1;return
    c['other:'+st[0][:30]]+=1
for line in open(sys.argv[1]):
    if not line.strip(): flush(stack);stack=[];continue
    if not line.startswith((' ','\t')):continue
    p=line.split(None,1)
    if len(p)>=2: stack.append(p[1].strip())
flush(stack)
print('total %.2fs'%(tot/HZ))
for k,v in c.most_common(30): print('%7.2fs %s'%(v/HZ,k))
