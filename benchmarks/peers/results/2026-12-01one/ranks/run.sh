#!/bin/bash
# kryflex reduce on 1 and 2 ranks, the default and -kf_static_exact false, on the bench's one-angle scenes
cd /work/wt/peers57
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1 OPENBLAS_NUM_THREADS=1 MPLBACKEND=Agg
D=/tmp/peers57/ranks
for s in galileo solid; do for t in 0.01 0.001 0.0001; do
  for v in default nse; do
    opt=""; [ $v = nse ] && opt="-kf_static_exact false"
    nice build/kryflex reduce $D/${s}_$t.yaml -o $D/out/${s}_${t}_${v}_1 -quiet $opt; echo "$s $t $v 1 rank: exit $?"
    nice mpiexec -n 2 build/kryflex reduce $D/${s}_$t.yaml -o $D/out/${s}_${t}_${v}_2 -quiet $opt; echo "$s $t $v 2 ranks: exit $?"
  done
done; done
