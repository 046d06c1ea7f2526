import collections,sys
HZ=float(sys.argv[2]); targets=sys.argv[3].split(',')
c=collections.Counter(); st=[]
def flush(st):
    if not st: return
    mumps=any(s.startswith(('dmumps','mumps','_SCOTCH','SCOTCH')) for s in st)
    for t in targets:
        if t in st:
            i=st.index(t)
            child=st[i-1] if i>0 else '(self)'
            c[(t,('MUMPS:' if mumps else '')+child)]+=1
            return
    c[('none','')]+=1
for line in open(sys.argv[1]):
    if not line.strip(): flush(st); st=[]; continue
    p=line.split(None,1)
    if len(p)>=2: st.append(p[1].strip().split('+')[0])
flush(st)
for k,v in sorted(c.items(),key=lambda x:-x[1])[:50]: print('%6.3fs %s'%(v/HZ,' | '.join(k)))
