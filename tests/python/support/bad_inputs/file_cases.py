"""Bad body files (Matrix Market, PETSc binary, nodes, load vectors, a folder given as a file), and good variants that
must be accepted (capitalised banner words, CRLF, a subnormal value, comments and blank lines, PETSc binary).

A refusal is exit 2 naming the scene entry or the file (and the line or entry where it helps) and the fix
(re-export the matrix, ...); kryflex.load_scene raises kryflex.SceneError with the same content. An indefinite
stiffness behind a positive diagonal is found only by the factorization: `kryflex reduce` exits with 3.
"""
from . import edits as e
from .harness import EXIT_INPUT, EXIT_NUMERIC, EXIT_OK, FIX, Case

REDUCE = ("reduce", "{scene}", "-o", "{out}", "-quiet")
REEXPORT = FIX           # any imperative: re-export the matrix, write it as real, fix the path, ...


def F(name, prepare, mentions, fix=REEXPORT, argv=("info", "{scene}"), **kw):
    return Case("file", name, prepare, argv=argv, code=kw.pop("code", EXIT_INPUT), mentions=tuple(mentions), fix=fix,
                api=kw.pop("api", "scene"), **kw)


def R(name, prepare, mentions, fix=REEXPORT, out="absent", **kw):
    return F(name, prepare, mentions, fix, argv=REDUCE, out=out, **kw)


def GOOD(name, prepare, argv=("info", "{scene}")):
    """A variant the readers must accept: exit 0, no error line."""
    return Case("file", name, prepare, argv=argv, code=EXIT_OK, kind="accept", api="scene")


K_ROTOR = ["bodies.rotor.stiffness", "rotor_K.mtx"]
M_ROTOR = ["bodies.rotor.mass", "rotor_M.mtx"]   # a sparse (diagonal) matrix: Galileo's K files hold every entry
K_STATOR = ["bodies.stator.stiffness", "stator_K.mtx"]

CASES = [
    # ------------------------------------------------------------------ Matrix Market
    R("missing_matrix", e.remove("rotor_K.mtx"), K_ROTOR, fix=r"not found.*fix the path"),           # existing
    F("mtx_empty", e.write("rotor_K.mtx", ""), K_ROTOR + ["re:empty"]),
    F("mtx_bad_banner", e.mtx_banner("rotor_K.mtx", "%%MatrixMarkt matrix coordinate real symmetric"),
      K_ROTOR + ["re:banner|header|MatrixMarket"]),
    F("mtx_no_banner", e.mtx_edit("rotor_K.mtx", lambda h, s, en: ([], s, en)), K_ROTOR + ["re:banner|header"]),
    F("mtx_pattern_field", e.mtx_banner("stator_M.mtx", "%%MatrixMarket matrix coordinate pattern symmetric"),
      ["bodies.stator.mass", "stator_M.mtx", "pattern"]),
    F("mtx_complex_field", e.mtx_banner("stator_M.mtx", "%%MatrixMarket matrix coordinate complex symmetric"),
      ["bodies.stator.mass", "stator_M.mtx", "complex"]),
    F("mtx_integer_field_hermitian", e.mtx_banner("stator_M.mtx", "%%MatrixMarket matrix coordinate real hermitian"),
      ["stator_M.mtx", "hermitian"]),
    F("mass_size_mismatch", e.text("mass: stator_M.mtx", "mass: rotor_M.mtx"), ["stator", "21 x 21", "12 x 12"],
      fix=r"same size"),                                                                               # existing
    F("nodes_mismatch", e.text("106 0 0 -1.1000000000000001 3", "106 0 0 -1.1000000000000001 6", "rotor_nodes.txt"),
      ["rotor", "24", "21"], fix=r"must match"),                                                       # existing
    F("mtx_not_square", e.mtx_size_line("rotor_K.mtx", "21 20 109"), K_ROTOR + ["21", "20"]),
    F("mtx_extra_entries", e.mtx_append_entries("rotor_M.mtx", ["21 1 1.0", "21 2 1.0"], bump_count=False),
      M_ROTOR + ["re:more than the 21 entries", "line 25"]),
    R("truncated_mtx", e.cut_mtx("rotor_K.mtx", inside_line=False), K_ROTOR, fix=r"truncated.*re-export"),  # existing
    F("truncated_mtx_inside_line", e.cut_mtx("rotor_K.mtx", inside_line=True), K_ROTOR,
      fix=r"(truncated|corrupt).*re-export"),                                                         # existing
    F("mtx_nan_entry", e.mtx_entry("rotor_K.mtx", 3, "4 1 nan"), K_ROTOR + ["re:nan"]),
    F("mtx_inf_entry", e.mtx_entry("rotor_K.mtx", 3, "4 1 inf"), K_ROTOR + ["re:inf"]),
    F("mtx_row_out_of_range", e.mtx_entry("rotor_K.mtx", 3, "22 1 1.5"), K_ROTOR + ["22"]),
    F("mtx_index_zero", e.mtx_entry("rotor_K.mtx", 3, "0 1 1.5"), K_ROTOR + ["re:\\b0\\b"]),
    F("mtx_value_not_a_number", e.mtx_entry("rotor_K.mtx", 3, "4 1 abc"), K_ROTOR + ["abc"]),
    F("mtx_garbage", e.write("rotor_K.mtx", bytes(range(256)) * 8), K_ROTOR),
    F("nonsymmetric_stiffness", e.nonsymmetric_general, ["stator", "stiffness"],
      fix=r"not symmetric.*check the export"),                                                        # existing
    F("mtx_symmetric_both_triangles", e.both_triangles_symmetric, K_STATOR + ["re:triangle|above|upper|both"]),
    F("negative_diagonal", e.negative_diagonal, ["rotor", "stiffness"],
      fix=r"(indefinite|negative).*check the export"),                                               # existing
    F("mtx_is_a_folder", e.make_folder("rotor_K.mtx"), K_ROTOR + ["re:folder|directory"], fix=FIX),
    R("indefinite_behind_positive_diagonal", e.negative_eigenvalue, ["re:indefinite|negative pivot"], fix=FIX,
      code=EXIT_NUMERIC, api=None),
    # ------------------------------------------------------------------ PETSc binary
    R("truncated_petsc", e.petsc_edit(e.petsc_truncated), ["bodies.rotor.stiffness", "rotor_K.petsc"],
      fix=r"(corrupt|truncated).*re-export"),                                                         # existing
    F("petsc_column_out_of_range", e.petsc_edit(e.petsc_first_column(-1)), ["rotor_K.petsc"],
      fix=r"(corrupt|re-export)"),                                                                    # existing
    F("petsc_column_too_large", e.petsc_edit(e.petsc_first_column(21)), ["rotor_K.petsc", "21"]),
    F("petsc_not_a_matrix", e.petsc_edit(e.petsc_classid), ["rotor_K.petsc"]),
    F("petsc_nonzero_count", e.petsc_edit(e.petsc_nnz), ["rotor_K.petsc"]),
    F("petsc_nan_value", e.petsc_edit(e.petsc_nan_value), ["rotor_K.petsc", "re:nan"]),
    # ------------------------------------------------------------------ nodes files
    F("nodes_missing", e.remove("rotor_nodes.txt"), ["bodies.rotor.nodes", "rotor_nodes.txt"], fix=FIX),
    F("nodes_four_columns", e.text("105 0 0 2.8999999999999999 3", "105 0 0 2.8999999999999999", "rotor_nodes.txt"),
      ["rotor_nodes.txt", "re:line 8\\b"], fix=FIX),
    F("nodes_not_numbers", e.text("105 0 0 2.8999999999999999 3", "105 0 zero 2.8999999999999999 3", "rotor_nodes.txt"),
      ["rotor_nodes.txt", "zero"], fix=FIX),
    F("nodes_duplicate_ids", e.text("105 0 0 2.8999999999999999 3", "104 0 0 2.8999999999999999 3", "rotor_nodes.txt"),
      ["rotor_nodes.txt", "104", "re:duplicate|twice|more than once"], fix=FIX),
    F("nodes_bad_ndof", e.text("105 0 0 2.8999999999999999 3", "105 0 0 2.8999999999999999 4", "rotor_nodes.txt"),
      ["rotor_nodes.txt", "re:\\b4\\b"], fix=FIX),
    F("nodes_id_2pow31", e.text("105 0 0 2.8999999999999999 3", "2147483648 0 0 2.8999999999999999 3",
                                "rotor_nodes.txt"), ["rotor_nodes.txt", "2147483648"], fix=FIX),
    F("nodes_nan_coordinate", e.text("105 0 0 2.8999999999999999 3", "105 0 nan 2.8999999999999999 3",
                                     "rotor_nodes.txt"), ["rotor_nodes.txt", "re:nan"], fix=FIX),
    F("nodes_empty", e.write("rotor_nodes.txt", "# nothing here\n"), ["rotor_nodes.txt", "re:no nodes|empty"], fix=FIX),
    F("nodes_is_a_folder", e.make_folder("rotor_nodes.txt"), ["rotor_nodes.txt", "re:folder|directory"], fix=FIX),
    # ------------------------------------------------------------------ load vectors
    F("vector_wrong_length", e.use_load_vector(values=[0.0] * 20), ["load.txt", "20", "21"], fix=FIX),
    F("vector_nan", e.use_load_vector(values=[float("nan")] + [0.0] * 20), ["load.txt", "re:nan"], fix=FIX),
    F("vector_missing", e.all_of(e.use_load_vector(), e.remove("load.txt")), ["load.txt", "re:not found"], fix=FIX),
    F("vector_not_numbers", e.all_of(e.use_load_vector(), e.text("-1.0", "minus one", "load.txt")),
      ["load.txt", "minus one"], fix=FIX),
    # ------------------------------------------------------------------ good variants: accepted
    GOOD("good_mtx_coordinate_capitalised",
         e.mtx_banner("rotor_K.mtx", "%%MatrixMarket MATRIX Coordinate Real Symmetric")),
    GOOD("good_mtx_crlf", e.all_of(e.crlf("rotor_K.mtx"), e.crlf("rotor_M.mtx"))),
    GOOD("good_mtx_subnormal_value", e.mtx_append_entries("rotor_M.mtx", ["12 9 1e-310"], bump_count=True)),
    GOOD("good_mtx_comments_blank_lines", e.comments_and_blank_lines("rotor_K.mtx")),
    GOOD("good_nodes_crlf_comments", e.all_of(e.crlf("rotor_nodes.txt"),
                                              e.text("# id x y z ndof", "# id x y z ndof\n\n   # indented comment",
                                                     "rotor_nodes.txt"))),
    GOOD("good_petsc_binary", e.petsc_edit(lambda data: data)),
    GOOD("good_load_vector", e.use_load_vector()),
    GOOD("good_reduce_crlf_scene", e.crlf("galileo.yaml"),
         argv=("reduce", "{scene}", "-o", "{out}", "-quiet", "-scene.angles", "0", "-kf_verify", "0")),
]
