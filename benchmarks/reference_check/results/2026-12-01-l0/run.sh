#!/bin/bash
# before (merge3 at 33fbd16, built in /tmp/l0ref/base, with this tree's static_moment.py and reference.py copied in)
# and after (this tree): Galileo and the solid, 1 and 2 ranks
cd /work/wt/l0ref
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1 OPENBLAS_NUM_THREADS=1 MPLBACKEND=Agg
R=benchmarks/reference_check/results/2026-12-01-l0
for which in before after; do
  if [ $which = before ]; then T=/tmp/l0ref/base; else T=$PWD; fi
  for s in galileo solid; do
    if [ $s = galileo ]; then SC="--scene meshes/galileo/galileo.yaml --beta 0.00719"; else SC="--scene /tmp/l0ref/solid/spacecraft.yaml --beta 0.000133"; fi
    for n in 1 2; do
      f=$R/${which}_${s}_${n}rank.txt
      (date -u; cat /proc/loadavg; PYTHONPATH=$T/python nice .venv/bin/python $T/benchmarks/reference_check/static_moment.py $SC $([ $n = 2 ] && echo --ranks 2) 2>&1 | grep -v "loaded "; date -u; cat /proc/loadavg) > $f 2>&1
    done
  done
done
