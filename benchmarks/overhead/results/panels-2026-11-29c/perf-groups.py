import sys,re,collections
groups=[('Krylov append (both passes, M product, store)','KFMBasisAppend',None),
        ('  of it the basis subtractions (dgemm nn)','KFMBasisSubtract',None),
        ('  of it the coefficients (dgemm tn)','KFMBasisCoefficients',None),
        ('  of it the float correction (sgemm)','sgemm',None),
        ('solver glue outside MUMPS (KFFlexSolverApply)','KFFlexSolverApply','dmumps|KFMumpsMatSolve|mumps_'),
        ('  of it the residual K_S X (extended)','KFMatMultExtended',None),
        ('zero fills + page faults under kryflex stacks','memset|clear_page|exc_page_fault','dmumps|mumps_'),
        ('Krylov basis outside solves (KFKrylovBasisDamped_Private)','KFKrylovBasisDamped_Private','KFFlexSolverApply'),
        ('whole process','.',None)]
for f in sys.argv[1:]:
    c=collections.Counter(); st=[]
    def flush(s):
        if not s: return
        j=' '.join(s)
        for name,inc,exc in groups:
            if re.search(inc,j) and not (exc and re.search(exc,j)):
                if name.startswith('zero') and 'KF' not in j: continue
                c[name]+=1
    for line in open(f):
        if not line.strip(): flush(st); st=[]; continue
        if not line.startswith((' ','\t')): continue
        p=line.split(None,1)
        if len(p)>=2: st.append(p[1].strip())
    flush(st)
    print(f, ' | '.join('%s %.3f'%(n.strip(),c[n]/400) for n,_,_ in groups))
