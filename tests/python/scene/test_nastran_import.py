"""Nastran import (docs/guide/real-models.md): DMIG* punch + bulk GRIDs with CORD2R/C/S in CP and CD, massless rotations, an
SPOINT and PARAM,WTMASS, read by `kryflex convert` and from Python, checked against the same model built directly
in basic coordinates (nastran_model.py, NumPy, independent of the converter)."""
import os
import subprocess
import sys

import numpy as np
import pytest
import scipy.io

HERE = os.path.dirname(os.path.abspath(__file__))
SUPPORT = os.path.join(os.path.dirname(HERE), "support")   # the helpers (tests/python/support)
sys.path.insert(0, SUPPORT)
import run_env  # noqa: E402  (support/run_env.py: the repository's paths, the subprocesses' environment)
import nastran_model as nm  # noqa: E402

from kryflex.io import dmig  # noqa: E402
from kryflex.io.bodyfiles import ConversionError, ConversionWarning, dof_count, read_nodes  # noqa: E402
from kryflex.io.convert import convert, main  # noqa: E402

ENV = dict(run_env.BASE_ENV, PYTHONPATH=run_env.PACKAGE)
KRYFLEX = run_env.KRYFLEX
# DMIG* fields carry 11-12 significant digits (1.2345678901+05): entries within 5e-11 relative of the reference
ENTRY_RTOL = 1e-10


@pytest.fixture()
def model(tmp_path):
    ref = nm.write_model(str(tmp_path))
    ref["dir"] = tmp_path
    return ref


def body_dofs(nodes):
    """[(id, component)] of a written nodes list, in matrix order."""
    dofs = []
    for node in nodes:
        d = node[4]
        comps = {6: range(1, 7), 3: range(1, 4), "s": [0]}.get(d) or [int(c) for c in d[1:]]
        dofs += [(node[0], c) for c in comps]
    return dofs


def read_converted(out, name="frame"):
    K = scipy.io.mmread(str(out / f"{name}_K.mtx")).toarray()
    M = scipy.io.mmread(str(out / f"{name}_M.mtx")).toarray()
    nodes = read_nodes(out / f"{name}_nodes.txt")
    return K, M, nodes


def check_against_reference(K, M, nodes, ref, mass_scale=1.0):
    dofs = body_dofs(nodes)
    assert sorted(dofs) == sorted(ref["dofs"])
    assert {n[0]: n[4] for n in nodes} == {101: 6, 102: 6, 103: 6, 104: 6, 105: 6, 106: 6, 107: "c345", 108: 3,
                                           150: "s"}
    # the positions: basic coordinates from CP (rectangular, cylindrical in a RID chain, spherical)
    for node in nodes:
        if node[4] != "s":
            np.testing.assert_allclose(node[1:4], ref["basic"][node[0]], rtol=0, atol=1e-12)
    # the matrices, entry by entry in basic dofs (the CD transforms)
    p = [ref["dofs"].index(d) for d in dofs]
    Kr, Mr = ref["K"][np.ix_(p, p)], mass_scale * ref["M"][np.ix_(p, p)]
    assert np.abs(K - Kr).max() <= ENTRY_RTOL * np.abs(Kr).max()
    assert np.abs(M - Mr).max() <= ENTRY_RTOL * np.abs(Mr).max()
    # eigenvalues to 1e-8: 6 rigid-body modes, the elastic ones relative
    lam, lam_ref = nm.eigenvalues(K, M), nm.eigenvalues(Kr, Mr)
    assert lam.size == lam_ref.size == len(dofs) - 6          # rotations of 103 and 105 massless
    top = lam_ref.max()
    assert np.all(np.abs(lam_ref[:6]) < 1e-9 * top) and np.all(np.abs(lam[:6]) < 1e-8 * top)
    assert lam_ref[6] > 1e6 * np.abs(lam_ref[:6]).max()
    np.testing.assert_allclose(lam[6:], lam_ref[6:], rtol=1e-8, atol=0)
    # rigid-body modes from the written coordinates carry no strain energy: the transforms are right
    xyz = {n[0]: np.array(n[1:4]) for n in nodes}
    Phi = nm.rigid_modes(dofs, xyz)
    assert np.abs(K @ Phi).max() <= 1e-8 * np.abs(K).max() * np.abs(Phi).max()
    return dofs, lam


def test_convert_command_matches_the_basic_reference(model, capsys):
    d = model["dir"]
    out = d / "out"
    code = main([str(d / "model.pch"), "--grids", str(d / "model.bdf"), "--name", "frame", "--format", "mtx",
                 "--interface", "root=101", "--interface", "tip=106", "-o", str(out)])
    captured = capsys.readouterr()
    assert code == 0, captured.err
    assert f"PARAM,WTMASS={nm.WTMASS:g}" in captured.err      # reported, mass used as stored
    K, M, nodes = read_converted(out)
    dofs, lam = check_against_reference(K, M, nodes, model)
    assert "frame: %d dofs, 9 nodes" % len(dofs) in captured.out.replace("'", "")

    # the same model with the mass in weight units: --mass-scale wtmass multiplies M (and nothing else) by WTMASS
    code = main([str(d / "model.pch"), "--grids", str(d / "model.bdf"), "--name", "frame", "--format", "mtx",
                 "--mass-scale", "wtmass", "-o", str(d / "scaled")])
    assert code == 0
    K2, M2, nodes2 = read_converted(d / "scaled")
    np.testing.assert_array_equal(K2, K)
    np.testing.assert_allclose(M2, nm.WTMASS * M, rtol=1e-15)
    check_against_reference(K2, M2, nodes2, model, mass_scale=nm.WTMASS)


def test_a_raw_read_without_transforms_would_fail_the_rigid_mode_check(model):
    # the check above is sensitive: the matrices as stored (CD systems) with the basic coordinates are not rigid
    K_cd, dofs = dmig.read_dmig(model["dir"] / "model.pch")["KAAX"]
    Phi = nm.rigid_modes(dofs, model["basic"])
    K_cd = K_cd.toarray()
    assert np.abs(K_cd @ Phi).max() > 1e-3 * np.abs(K_cd).max() * np.abs(Phi).max()


def test_python_route_and_f06_echo_give_the_same_body(model):
    d = model["dir"]
    with pytest.warns(ConversionWarning, match="WTMASS"):
        M, K, nodes, notes = dmig.nastran_body(d / "model.pch", [d / "model.bdf"])
    with pytest.warns(ConversionWarning, match="WTMASS"):
        M6, K6, nodes6, _ = dmig.nastran_body(d / "model.pch", [d / "model.f06"])
    assert nodes6 == nodes
    assert (K6 != K).nnz == 0 and (M6 != M).nnz == 0
    assert notes["wtmass"] == nm.WTMASS and notes["rotated"]
    check_against_reference(K.toarray(), M.toarray(), nodes, model)
    # convert() from Python, from the .f06, PETSc binary output
    body = convert(str(d / "model.pch"), str(d / "py"), "frame", "petsc", {"root": 101}, grids=[str(d / "model.f06")],
                   mass_scale=1.0)
    assert body.size == sum(dof_count(n[4]) for n in nodes) == 43 and body.node_count == 9
    assert read_nodes(d / "py" / "frame_nodes.txt") == nodes
    assert dmig.read_grids(d / "model.f06") == dmig.read_grids(d / "model.bdf")


def edit(path, old, new):
    text = path.read_text()
    assert old in text
    path.write_text(text.replace(old, new, 1))


@pytest.mark.parametrize("case", ["missing grid", "unknown CP", "unknown CD", "unknown RID", "CORD1 grid", "non-symmetric",
                                  "open component set", "grid as scalar point", "no echo"])
def test_bad_models_give_clear_errors_and_no_output(model, case):
    d = model["dir"]
    pch, bdf, grids = d / "model.pch", d / "model.bdf", [d / "model.bdf"]
    if case == "missing grid":
        text = bdf.read_text().splitlines()
        k = next(i for i, line in enumerate(text) if line.startswith("GRID*") and line.split()[1] == "108")
        bdf.write_text("\n".join(text[:k] + text[k + 2:]) + "\n")
        expected = r"1 grid\(s\) used by the matrices have no GRID card .*\(108\)"
    elif case == "unknown CP":
        edit(bdf, "GRID*                104              10", "GRID*                104              11")
        expected = "GRID 104 gives CP=11, but no CORD card defines coordinate system 11"
    elif case == "unknown CD":
        text = bdf.read_text().splitlines()
        k = next(i for i, line in enumerate(text) if line.startswith("GRID*") and line.split()[1] == "106")
        text[k + 1] = text[k + 1][:24] + f"{77:>16}"
        bdf.write_text("\n".join(text) + "\n")
        expected = "GRID 106 gives CD=77, but no CORD card defines coordinate system 77"
    elif case == "unknown RID":
        edit(bdf, "CORD2C        20      10", "CORD2C        20      12")
        expected = "CORD2C 20 is defined in system RID=12, which no CORD card defines"
    elif case == "CORD1 grid":
        edit(bdf, "CORD1R        60     104     105     102", "CORD1R        60     104     105     999")
        expected = "CORD1R 60 is defined by GRID 999, which no file defines"
    elif case == "non-symmetric":
        # a square (IFO 1) stiffness whose (101-ux, 101-uy) and (101-uy, 101-ux) entries differ
        def column(cj, entries):
            lines = [f"{'DMIG*':<8}{'KAAX':<16}{'101':>16}{cj:>16}{'':>16}"]
            return lines + [f"{'*':<8}{'101':>16}{ci:>16}{nm.large(v):>16}{'':>16}" for ci, v in entries]
        lines = [f"{'DMIG*':<8}{'KAAX':<16}{'0':>16}{'1':>16}{'2':>16}", f"{'*':<8}{'0':>16}{'':>16}{'':>16}{'2':>16}"]
        lines += column(1, [(1, 2.0), (2, 1.0)]) + column(2, [(1, 1.5), (2, 2.0)])
        lines += nm.dmig_star("MAAX", np.eye(2), [(101, 1), (101, 2)])
        pch.write_text("\n".join(lines) + "\n")
        expected = r"stiffness matrix K of body 'frame' .* is not symmetric"
    elif case == "open component set":
        # grid 108 keeps only component 3 in its cylindrical CD: uz_cd is not a basic direction there
        K = np.array([[2.0, -1.0], [-1.0, 2.0]])
        pch.write_text("\n".join(nm.dmig_star("KAAX", K, [(101, 3), (108, 3)])
                                 + nm.dmig_star("MAAX", np.eye(2), [(101, 3), (108, 3)])) + "\n")
        expected = "GRID 108 .* has only components 3 in the matrices, in its displacement system CD=20"
    elif case == "grid as scalar point":
        edit(bdf, f"SPOINT  {nm.SPOINT:>8}", f"GRID    {nm.SPOINT:>8}        0.      0.      0.")
        expected = f"the matrices use point {nm.SPOINT} with component 0 .* defines GRID {nm.SPOINT}"
    else:
        (d / "empty.f06").write_text("1    no echo here\n")
        grids = [d / "empty.f06"]
        expected = "holds no bulk-data echo"
    out = d / "out"
    with pytest.raises(ConversionError, match=expected):
        convert(str(pch), str(out), "frame", "mtx", {}, grids=[str(g) for g in grids])
    assert not out.exists()
    code = subprocess.run([sys.executable, "-m", "kryflex", "convert", str(pch), "--name", "frame", "-o", str(out),
                           *sum((["--grids", str(g)] for g in grids), [])], env=ENV, capture_output=True, text=True,
                          timeout=120)
    assert code.returncode == 2, code.stderr
    assert "Traceback" not in code.stderr and "kryflex: error:" in code.stderr
    assert not out.exists()


def test_converted_model_reduces(model):
    """The converted body (6-dof, c345, 3 and s nodes; massless rotations) through `kryflex reduce`."""
    if not os.path.exists(KRYFLEX):
        pytest.skip("build/kryflex not built")
    d = model["dir"]
    assert main([str(d / "model.pch"), "--grids", str(d / "model.bdf"), "--name", "frame",
                 "--interface", "root=101", "-o", str(d)]) == 0
    (d / "scene.yaml").write_text(
        "name: nastran_frame\n"
        "bodies:\n"
        "  frame: {mass: frame_M.petsc, stiffness: frame_K.petsc, nodes: frame_nodes.txt, interfaces: {root: 101}}\n"
        "inputs:\n  force: {body: frame, node: 106, dof: uz}\n"
        "outputs:\n  tip: {body: frame, node: 108, dof: uz}\n"
        "band: [0.1, 100]\n")
    proc = subprocess.run([KRYFLEX, "reduce", str(d / "scene.yaml"), "-o", str(d / "red"), "-quiet"], env=ENV,
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    # the full-order frequencies the reduction verified against are the reference's (massless dofs condensed)
    import json
    with open(d / "red" / "summary.json") as f:
        summary = json.load(f)
    (label,) = summary["angle_labels"]
    full = np.array(summary["full"]["frequencies_hz"][label])
    lam = nm.eigenvalues(model["K"], model["M"])
    np.testing.assert_allclose(full, (np.sqrt(lam[6:]) / (2 * np.pi))[:len(full)], rtol=1e-8)
    # exact to rounding: the report flags a moment ratio beyond 1e-8 (measured 1.1e-9 on the elastic measure's model)
    assert summary["reduced"]["static_gain_error"][label] < 1e-8
    # the same body from Python, as arrays (nastran_body -> scene_from_dict), reduces to the same model
    import kryflex
    with pytest.warns(ConversionWarning, match="WTMASS"):
        M, K, nodes, _ = dmig.nastran_body(d / "model.pch", [d / "model.bdf"])
    spec = {"name": "nastran_frame", "band": [0.1, 100],
            "bodies": {"frame": {"mass": M, "stiffness": K, "nodes": nodes, "interfaces": {"root": 101}}},
            "inputs": {"force": [{"body": "frame", "node": 106, "dof": "uz"}]},
            "outputs": {"tip": [{"body": "frame", "node": 108, "dof": "uz"}]}}
    model_py = kryflex.reduce(kryflex.scene_from_dict(spec), quiet=True).model
    np.testing.assert_allclose(model_py.at([]).frequencies_hz, summary["reduced"]["frequencies_hz"][label],
                               rtol=1e-8)


def test_op4_with_a_nodes_file(model):
    """ASCII OUTPUT4 matrices (no dof labels) in basic dofs, their rows named by a nodes file with c/s dofs.
    (Binary OP4 goes through the same pyNastran reader; pyNastran 1.4.1 cannot write one to test with: its
    binary writer fails on a dense and refuses a sparse matrix.)"""
    from pyNastran.op2.result_objects.matrix import Matrix
    from pyNastran.op4.op4 import write_op4
    d = model["dir"]
    # rows in the reference's dof order, one nodes line per point, its components in the dofs field
    dofs = model["dofs"]
    groups = dmig.group_dofs(dofs)
    with open(d / "nodes.txt", "w") as f:
        for g, comps in groups:
            xyz = model["basic"].get(g, (0.0, 0.0, 0.0))
            f.write("%d %r %r %r %s\n" % (g, *map(float, xyz), dmig.node_dofs(comps)))
    write_op4(str(d / "model.op4"), {"KAA": Matrix("KAA", 6, model["K"]), "MAA": Matrix("MAA", 6, model["M"])},
              precision="double", is_binary=False)
    out = d / "op4"
    assert main([str(d / "model.op4"), "--nodes", str(d / "nodes.txt"), "--stiffness-name", "KAA",
                 "--mass-name", "maa", "--name", "frame", "--format", "mtx", "-o", str(out)]) == 0
    K, M, nodes = read_converted(out)
    np.testing.assert_allclose(K, model["K"], rtol=0, atol=1e-15 * np.abs(model["K"]).max())
    np.testing.assert_allclose(M, model["M"], rtol=0, atol=1e-15 * np.abs(model["M"]).max())
    check_against_reference(K, M, nodes, model)
    with pytest.raises(ConversionError, match=r"holds no matrix KAAX \(matrices: KAA, MAA\)"):
        convert(str(d / "model.op4"), str(d / "x"), "frame", "mtx", {}, nodes=str(d / "nodes.txt"))
    with pytest.raises(ConversionError, match="an OP4 matrix has no dof labels; give the nodes"):
        convert(str(d / "model.op4"), str(d / "x"), "frame", "mtx", {}, stiffness_name="KAA", mass_name="MAA")
    assert not (d / "x").exists()


def test_grdset_cd_and_command_line_checks(model, capsys):
    d = model["dir"]
    # GRDSET CD=60 stands for grid 106's CD once its field is blank: the same body, and a warning says so
    text = d.joinpath("model.bdf").read_text().splitlines()
    k = next(i for i, line in enumerate(text) if line.startswith("GRID*") and line.split()[1] == "106")
    text[k + 1] = text[k + 1][:24]
    text.insert(text.index("BEGIN BULK") + 1, "GRDSET                                          60")
    # grid 101 has CD 0: with a GRDSET it would take CD 60 too; make it a basic-aligned CORD2R (the warning's fix)
    text.insert(text.index("BEGIN BULK") + 1, "CORD2R        50       0      0.      0.      0.      0.      0.      1.+C50")
    text.insert(text.index("BEGIN BULK") + 2, "+C50          1.      0.      0.")
    j = next(i for i, line in enumerate(text) if line.startswith("GRID*") and line.split()[1] == "101")
    text[j + 1] = text[j + 1][:24] + f"{50:>16}"
    d.joinpath("grdset.bdf").write_text("\n".join(text) + "\n")
    with pytest.warns(ConversionWarning, match=r"GRDSET .* sets CP=0 CD=60: 1 GRID\(s\) .* \(e.g. 106\)"):
        M, K, nodes, _ = dmig.nastran_body(d / "model.pch", [d / "grdset.bdf"], mass_scale=1.0)
    check_against_reference(K.toarray(), M.toarray(), nodes, model)
    # usage errors of the new option
    for argv in (["--mass-scale", "-1"], ["--mass-scale", "heavy"]):
        assert main([str(d / "model.pch"), "--grids", str(d / "model.bdf"), "--name", "f", "-o", str(d / "n"),
                     *argv]) == 2
        assert "--mass-scale" in capsys.readouterr().err
    assert not (d / "n").exists()


def test_include_files_are_followed(model):
    """A deck whose GRIDs sit in an INCLUDE file (relative to the deck) gives the same body."""
    d = model["dir"]
    lines = d.joinpath("model.bdf").read_text().splitlines()
    grids = [k for k, line in enumerate(lines) if line.startswith("GRID*")]
    included = [lines[k + i] for k in grids for i in (0, 1)]
    (d / "inc").mkdir()
    (d / "inc" / "grids.bdf").write_text("\n".join(included) + "\n")
    rest = [line for k, line in enumerate(lines) if k not in set(grids) | {k + 1 for k in grids}]
    rest.insert(rest.index("ENDDATA"), "INCLUDE 'inc/grids.bdf'")
    (d / "deck.bdf").write_text("\n".join(rest) + "\n")
    with pytest.warns(ConversionWarning):
        M, K, nodes, _ = dmig.nastran_body(d / "model.pch", [d / "deck.bdf"])
    check_against_reference(K.toarray(), M.toarray(), nodes, model)


def test_params_across_files(model):
    """Only WTMASS matters: two files giving it differently is an error; other PARAMs may differ."""
    d = model["dir"]
    with open(d / "model.pch", "a") as f:
        f.write("PARAM,POST,-1\n")
    with open(d / "model.bdf", "r+") as f:
        text = f.read().replace("ENDDATA", "PARAM,POST,-2\nENDDATA")
        f.seek(0)
        f.write(text)
    with pytest.warns(ConversionWarning, match="WTMASS"):
        dmig.nastran_body(d / "model.pch", [d / "model.bdf"])
    with open(d / "model.pch", "a") as f:
        f.write("PARAM,WTMASS,0.5\n")
    with pytest.raises(ConversionError, match="PARAM WTMASS is defined in .*model.pch and again, differently, in "
                                              ".*model.bdf"):
        dmig.nastran_body(d / "model.pch", [d / "model.bdf"])
