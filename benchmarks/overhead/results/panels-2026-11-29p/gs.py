import collections,sys
HZ=400.0
def scan(fn):
    c=collections.Counter(); st=[]
    def flush(st):
        if not st: return
        if 'KFKrylovBasisDamped_Private' in st and 'KFFlexSolverApply' not in st and 'KFKrylovHealth' not in st:
            c['gs_total']+=1
            for name in ('KFMBasisLaggedSweeps','KFMBasisLagChunk','KFMBasisProjectOut','KFMBasisPasses','KFMBasisKeep','KFMProduct','KFMNorms','KFMBasisFinishLag','KFChainNext','KFChainCombine'):
                if name in st: c[name]+=1
        if 'KFFlexSolverApply' in st and not any(s.startswith(('dmumps','mumps')) for s in st): c['solver_glue']+=1
        if 'KFReducerSolve' in st: c['whole']+=1
        if 'KFReducerSolve' in st and any(s.startswith(('dmumps','mumps','_SCOTCH','SCOTCH')) for s in st): c['whole_mumps']+=1
    for line in open(fn):
        if not line.strip(): flush(st); st=[]; continue
        p=line.split(None,1)
        if len(p)>=2: st.append(p[1].strip().split('+')[0])
    flush(st)
    return c
for fn in sys.argv[1:]:
    c=scan(fn); print(fn, ' '.join('%s %.3f'%(k,v/HZ) for k,v in sorted(c.items())))
    print('   CPU ratio whole/mumps %.3f'%(c['whole']/c['whole_mumps']))
