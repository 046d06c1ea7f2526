"""The kryflex command (reduce, reassemble, info, convert): python -m kryflex, or build/kryflex under mpirun."""
