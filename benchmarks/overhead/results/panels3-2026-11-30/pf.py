import collections,sys
HZ=float(sys.argv[2]); c=collections.Counter(); st=[]; tot=[0,0]
def flush(st):
    if not st: return
    tot[0]+=1
    if not any('page_fault' in s for s in st): return
    tot[1]+=1
    kf=[f for f in st if f.startswith(('KF','BV','Mat','dmumps','mumps','PetscMalloc','PetscCalloc','Vec'))]
    c[' < '.join(kf[:3]) if kf else '(none) '+' < '.join(st[-6:-3])]+=1
for line in open(sys.argv[1]):
    if not line.strip(): flush(st); st=[]; continue
    p=line.split(None,1)
    if len(p)>=2: st.append(p[1].strip().split('+')[0])
flush(st)
print('all %.3fs, page faults %.3fs'%(tot[0]/HZ,tot[1]/HZ))
for k,v in c.most_common(40): print('%6.3fs %s'%(v/HZ,k))
