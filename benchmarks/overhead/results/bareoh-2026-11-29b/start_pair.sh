#!/bin/sh
# The process's start and end alone, two trees alternating: `kryflex --help` imports the command's modules, starts
# MPI, PETSc and SLEPc (init runs before the help is printed), then finalizes them and exits.
#   sh benchmarks/overhead/results/bareoh-2026-11-29b/start_pair.sh OTHER_TREE THIS_TREE ROUNDS
other=$1; this=$2; n=${3:-8}
echo "start and end, $(date -u '+%Y-%m-%d %H:%M') UTC, load $(cut -d' ' -f1-3 /proc/loadavg)"
i=0
while [ $i -lt $n ]; do
  for t in "$other" "$this"; do
    /usr/bin/time -f "$t: wall %e user %U sys %S" "$t/build/kryflex" --help > /dev/null
  done
  i=$((i + 1))
done 2>&1 | awk '{print} /wall/ {w[$1]+=$3; c[$1]+=$5+$7; k[$1]++} END {for (t in w) printf "%s mean of %d: wall %.3f, cpu %.3f\n", t, k[t], w[t]/k[t], c[t]/k[t]}'
echo "load $(cut -d' ' -f1-3 /proc/loadavg)"
