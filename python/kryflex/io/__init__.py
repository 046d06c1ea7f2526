"""What goes into a reduction: scenes (YAML files or in-memory matrices), body files (PETSc binary, Matrix Market),
Nastran DMIG punch files and the converters between them, and the atomic writing of result files."""
