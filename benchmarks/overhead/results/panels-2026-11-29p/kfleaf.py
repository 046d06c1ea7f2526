import collections,sys
HZ=float(sys.argv[2]); depth=int(sys.argv[3]) if len(sys.argv)>3 else 2
c=collections.Counter(); st=[]
def flush(st):
    if not st: return
    kf=[f for f in st if f.startswith('KF')]
    if not kf: c['(none) '+st[0][:40]]+=1; return
    key=' < '.join(kf[:depth])
    if any(s.startswith(('dmumps','mumps','_SCOTCH','SCOTCH')) for s in st): key='MUMPS@'+kf[0]
    c[key]+=1
for line in open(sys.argv[1]):
    if not line.strip(): flush(st); st=[]; continue
    p=line.split(None,1)
    if len(p)>=2: st.append(p[1].strip().split('+')[0])
flush(st)
for k,v in c.most_common(60): print('%6.3fs %s'%(v/HZ,k))
