#!/bin/bash
# The moment solves' cost at 57k: the 57,031-dof solid at 0 deg, target 1e-3, default verification, 1 rank, before
# (merge3 at 33fbd16 built in /tmp/l0ref/base) and after (this tree), one after the other
# OPTS: further options (cost57k_full_moments.txt: OPTS="-kf_full_moments true", the moments solved)
cd /work/wt/l0ref
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OPENBLAS_NUM_THREADS=1
for which in before after; do
  if [ $which = before ]; then T=/tmp/l0ref/base; else T=$PWD; fi
  echo "== $which"; date -u; cat /proc/loadavg
  /usr/bin/time -f "CPU user %U s, system %S s, wall %e s, max RSS %M kB" nice $T/build/kryflex reduce \
    /tmp/peers57/l057k/solid57k_0.001.yaml -o /tmp/l0ref/57k_$which -quiet $OPTS 2>&1 | grep -v "loaded "
  .venv/bin/python -c "
import json, sys
d = json.load(open('/tmp/l0ref/57k_$which/summary.json'))
p = d['performance']
print('static_moment_error', d['chosen']['static_moment_error'], 'frf_error', d['chosen'].get('frf_error'))
print({k: v for k, v in p.items() if any(w in k for w in ('solve', 'moment', 'refine', 'whole', 'verif', 'factor', 'block'))})"
  date -u; cat /proc/loadavg
done
