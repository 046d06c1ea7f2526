import collections,sys
c=collections.Counter(); st=[]; n=[0]
def flush(st):
    if not st: return
    n[0]+=1
    kf=[f for f in st if f.startswith(('KF','BV','dmumps','mumps','PetscMalloc','PetscCalloc','PetscRealloc','Vec','Mat','Py','_Py'))]
    c[' < '.join(kf[:int(sys.argv[2])]) if kf else '(none) '+' < '.join(st[:4])]+=1
for line in open(sys.argv[1]):
    if not line.strip(): flush(st); st=[]; continue
    p=line.split(None,1)
    if len(p)>=2: st.append(p[1].strip().split('+')[0])
flush(st)
print('samples %d = faults %d'%(n[0],n[0]*8))
for k,v in c.most_common(45): print('%7d faults %5.1f%% %s'%(v*8,100.*v/n[0],k))
