"""The reduction does no wasted work, and what it skips does not change the model.

- Iterative refinement is decided by the residual of each block's first solve (-kf_refine_rtol): the model and the
  moments agree with the always-refined run (-kf_refine_rtol 0) to far below any accuracy target, and the residual
  reported is the one the library measured. A block stops refining when a step no longer halves its residual, and
  blocks left above the threshold are counted and named in a warning line.
- Without verification the full-order moments are not solved for: the accuracy search takes them from its richest
  candidate. They agree with the dense NumPy moments of tests/python/support/reference.py, the model is the same as with
  -kf_full_moments, and fewer columns go through the factor.
- The memory estimate after MUMPS' analysis stops the run before the factorization (faked with -kf_memory_limit_mb
  1e-4: Galileo's factors take a few kB): exit code 3, one message, on 1 and 2 ranks, no hang.
- The factorization options (-kf_ordering, -kf_blr) give the same model.

No timed test: speed is measured by benchmarks/scaling/bench-scaling.
"""
import json
import os
import re
import subprocess
import sys

import numpy as np
import pytest

import kryflex

HERE = os.path.dirname(os.path.abspath(__file__))
SUPPORT = os.path.join(os.path.dirname(HERE), "support")   # the helpers (tests/python/support)
sys.path.insert(0, SUPPORT)
import run_env  # noqa: E402  (support/run_env.py: the repository's paths, the subprocesses' environment)
ROOT = run_env.ROOT
GALILEO = os.path.join(ROOT, "meshes", "galileo", "galileo.yaml")
KRYFLEX = run_env.KRYFLEX
ENV = dict(run_env.ENV, MPLBACKEND="Agg")
EXIT_NUMERIC = 3
import reference as ref  # noqa: E402
from solid_runs import reduce_solid, solid_scene  # noqa: E402

SAME_MODEL_RTOL = 1e-5      # Galileo refitted to the paper: unrefined first solves leave residuals 1.1e-7 (the stick model
                            # ~1e-9), and the refined and unrefined models' FRFs differ by up to 1.1e-6 of the peak; the
                            # models must agree far below the targets (1e-3)
MOMENT_RTOL = 1e-6          # the richest candidate's moments against the dense reference (normwise per k)
MOMENTS_CHECKED = 4         # the lowest moments: the higher ones of a stiff model carry rounding ~cond^k


def scalar(reducer, name, config=-1):
    return float(np.ravel(reducer.result(config, name))[0])


def reduce(**opts):
    scene = kryflex.load_scene(GALILEO)
    reducer = kryflex.Reducer(scene, quiet=True, **opts)
    return scene, reducer, reducer.reduce()


def frf(scene, reducer, model, c):
    """The reduced model's FRF at angle of interest c, on the reducer's frequency grid there."""
    freqs = np.ravel(reducer.result(c, "frf_frequencies_hz"))
    return model.at(scene.configurations[c]).frf(freqs, scene.damping)


@pytest.fixture(scope="module")
def runs():
    """Galileo without verification: the default, full-order moments forced, and refinement always on."""
    return {"default": reduce(verify=False),
            "full": reduce(verify=False, full_moments=True),
            "loose_refine": reduce(verify=False, full_moments=True, refine_rtol=1e-6),
            "always_refine": reduce(verify=False, full_moments=True, refine_rtol=0.0)}


def test_refinement_decided_by_residual_keeps_the_model(runs):
    scene, r_def, red_def = runs["loose_refine"]
    _, r_all, red_all = runs["always_refine"]
    # the always-refined run refines every block; with a tolerance above Galileo's first-solve residuals (1.1e-7 on
    # the model refitted to the paper, ~1e-9 on the stick model) none of the Krylov blocks is refined; the residual of
    # each block's first solve is what decides. The full-order moments (one block per moment and angle), the moment
    # checks' reference, are refined by one step in both (KFFlexSolverApplyRefined)
    nfull = r_def.moments(0, "full_moments").shape[0]
    assert scalar(r_all, "refinement_solves") == scalar(r_all, "solve_blocks") > 0
    assert scalar(r_def, "solve_residual_first_max") <= 1e-6
    assert scalar(r_def, "refinement_solves") == len(scene.configurations) * nfull
    assert scalar(r_def, "solve_calls") < scalar(r_all, "solve_calls")
    # the residuals are measured, and refinement never makes the final one worse than the first
    for r in (r_def, r_all):
        first, final = scalar(r, "solve_residual_first_max"), scalar(r, "solve_residual_final_max")
        assert 0 < first < 1e-6 and 0 < final <= first * (1 + 1e-12)
    # the same model: sizes, and FRFs equal to far below the accuracy target
    assert red_def.model.sizes == red_all.model.sizes
    for c in range(len(scene.configurations)):
        a, b = frf(scene, r_def, red_def.model, c), frf(scene, r_all, red_all.model, c)
        assert np.max(np.abs(a - b)) <= SAME_MODEL_RTOL * np.max(np.abs(b))
        La, Lb = r_def.moments(c, "full_moments"), r_all.moments(c, "full_moments")
        for k in range(MOMENTS_CHECKED):
            assert np.linalg.norm(La[k] - Lb[k]) <= SAME_MODEL_RTOL * np.linalg.norm(Lb[k])


def test_refinement_stops_when_it_stalls_and_says_what_stayed_above(runs):
    """A threshold no solve can meet (1e-30): every block is refined, each stops after the step that no longer halves
    its residual (the factor's floor), is then escalated (more steps while each gains 10 %), and every block is counted
    as left above the threshold (the reducer's warning; summary.json's performance.blocks_unconverged)."""
    scene, r0, red0 = runs["default"]
    _, r, red = reduce(verify=False, refine=3, refine_rtol=1e-30)
    blocks = scalar(r, "solve_blocks")
    assert blocks > 0 and scalar(r, "solve_blocks_unconverged") == blocks
    # each block refined until it stalls, then escalated (more steps while each gains 10 %: at most 4 x 3 + 10)
    assert scalar(r, "solve_blocks_escalated") == blocks
    assert 2 * blocks <= scalar(r, "refinement_solves") <= (3 + 4 * 3 + 10) * blocks
    assert scalar(r, "solve_residual_final_max") <= scalar(r, "solve_residual_first_max")
    assert scalar(r0, "solve_blocks_unconverged") == 0      # the default threshold is met without refinement
    assert red.model.sizes == red0.model.sizes


@pytest.mark.mpi
@pytest.mark.parametrize("ranks", [1, 2])
def test_unconverged_refinement_is_a_warning_and_in_the_summary(tmp_path, ranks):
    """The same count on 1 and 2 ranks (the residuals are global), the warning printed once."""
    out = tmp_path / "out"
    p = subprocess.run((["mpiexec", "-n", str(ranks)] if ranks > 1 else []) + [
        KRYFLEX, "reduce", GALILEO, "-o", str(out), "-kf_verify", "false", "-kf_refine", "2", "-kf_refine_rtol",
        "1e-30"], capture_output=True, text=True, env=ENV, timeout=300)
    assert p.returncode == 0, p.stderr[-2000:]   # the accuracy target is the FRF error's, which the run measures
    perf = json.load(open(out / "summary.json"))["performance"]
    assert perf["blocks_unconverged"] > 0
    found = re.search(r"warning: (\d+) of (\d+) block solves stayed above -kf_refine_rtol after refinement "
                      r"\(largest final residual (\S+)\)", p.stdout)
    assert found, p.stdout[-3000:]
    assert p.stdout.count("block solves stayed above -kf_refine_rtol") == 1
    assert int(found.group(1)) == perf["blocks_unconverged"] == int(found.group(2))
    assert float(found.group(3)) == pytest.approx(perf["residual_final_max"], rel=0.06)  # printed with 2 digits


def test_moments_without_verification_are_not_solved_for(runs):
    scene, r_def, red_def = runs["default"]
    _, r_full, red_full = runs["full"]
    # no full-order moment solves: the moments stage is the richest candidate's (dense, small), fewer columns solved
    assert scalar(r_def, "solve_columns") < scalar(r_full, "solve_columns")
    assert "full_moments_estimated" in r_def.result_names(0) and "full_moments_estimated" not in r_full.result_names(0)
    # the model is unchanged
    assert red_def.model.sizes == red_full.model.sizes
    assert scalar(r_def, "error_max") == pytest.approx(scalar(r_full, "error_max"), rel=1e-6)
    # and the moments it reports are the full order's: against the dense reference (NumPy, from the files)
    rscene = ref.load_scene(GALILEO)
    for c, angles in enumerate(scene.configurations):
        Ms, Ks, Gs, Hs = ref.assemble(rscene, angles)
        Lref = ref.moments(Ms, Ks, Gs, Hs, MOMENTS_CHECKED)
        Lest, Lsol = r_def.moments(c, "full_moments"), r_full.moments(c, "full_moments")
        for k in range(MOMENTS_CHECKED):
            scale = np.linalg.norm(Lref[k])
            assert np.linalg.norm(Lest[k] - Lref[k]) <= MOMENT_RTOL * scale, (c, k)
            assert np.linalg.norm(Lsol[k] - Lref[k]) <= MOMENT_RTOL * scale, (c, k)


def test_timing_table_is_recorded(runs):
    _, r, _ = runs["default"]
    t = np.ravel(r.result(-1, "timings"))
    assert t.size == 10
    factor, solves, whole, ratio = t[1], t[2], t[8], t[9]
    assert factor > 0 and solves > 0 and whole >= factor + solves
    assert ratio == pytest.approx((whole - t[7]) / (factor + solves), rel=1e-12)
    assert scalar(r, "time_ratio") == pytest.approx(ratio, rel=1e-12)
    # every second of whole is in a stage or in "other"; the factorization stage holds its set-up outside MUMPS
    stages = ["time_assembly", "time_factorization", "time_basis", "time_modes", "time_moments", "time_projection",
              "time_verification"]
    assert sum(scalar(r, k) for k in stages) + scalar(r, "time_other") == pytest.approx(whole, rel=1e-9)
    assert 0 <= scalar(r, "time_factor_setup") <= scalar(r, "time_factorization")


@pytest.mark.parametrize("opts", [{"ordering": "amd"}, {"blr": 1e-10}, {"spd": True}])
def test_factorization_options_keep_the_model(runs, opts):
    scene, r0, red0 = runs["full"]
    _, r1, red1 = reduce(verify=False, full_moments=True, **opts)
    assert red1.model.sizes == red0.model.sizes
    for c in range(len(scene.configurations)):
        a, b = frf(scene, r1, red1.model, c), frf(scene, r0, red0.model, c)
        assert np.max(np.abs(a - b)) <= 1e-5 * np.max(np.abs(b)), opts


def test_bad_factorization_option_is_named():
    with pytest.raises(kryflex.Error, match=r"-kf_blr 2 is outside \[0, 1\); give a value in \[0, 1\)"):
        reduce(verify=False, blr=2.0)


@pytest.mark.mpi
@pytest.mark.skipif(not os.path.exists(KRYFLEX), reason="build/kryflex not built (scripts/setup)")
@pytest.mark.parametrize("ranks", [1, 2])
def test_memory_estimate_stops_before_the_factorization(tmp_path, ranks):
    out = tmp_path / "out"
    cmd = (["mpiexec", "-n", str(ranks)] if ranks > 1 else []) + [
        KRYFLEX, "reduce", GALILEO, "-o", str(out), "-kf_verify", "false", "-kf_memory_limit_mb", "1e-4",
        "-kf_error_agreement_timeout", "2"]
    p = subprocess.run(cmd, env=ENV, capture_output=True, text=True, timeout=120)
    assert p.returncode == EXIT_NUMERIC, p.stderr
    errors = [line for line in p.stderr.splitlines() if line.startswith("kryflex: error")]
    assert len(errors) == 1, p.stderr           # one message, from rank 0
    assert "not enough memory to factor the stiffness matrix" in errors[0]
    assert "-kf_memory_limit_mb" in errors[0] and "-kf_ooc" in errors[0]
    assert not (out / "summary.json").exists()  # no half-written output


def test_modal_baseline_shares_the_factorization():
    """The eigenvector baseline's sparse eigensolve (forced with -kf_verify_dense_max_dofs 0) runs on the flexible
    solver's factor: one factorization in the whole run, and the modes are the dense reference's."""
    scene = kryflex.load_scene(GALILEO)
    angles = scene.configurations[0]
    from petsc4py import PETSc
    PETSc.Log.begin()
    event = PETSc.Log.Event("MatCholFctrNum")
    before = event.getPerfInfo()["count"]
    reducer = kryflex.Reducer(scene, quiet=True, reducer_type="eigen", search=False, verify=False,
                              verify_dense_max_dofs=0, check_null_pivots=False)
    reducer.reduce()
    # one numeric factorization per configuration: SLEPc's shift-and-invert made none of its own
    assert event.getPerfInfo()["count"] - before == len(reducer.configurations)
    freqs = np.ravel(reducer.result(0, "krylov_frequencies_hz"))
    rscene = ref.load_scene(GALILEO)
    Ms, Ks, _, _ = ref.assemble(rscene, angles)
    lam = np.sort(ref.eigenvalues(Ms, Ks))
    nrig = ref.rigid_count(Ms, Ks)
    fref = np.sqrt(lam[nrig:nrig + freqs.size]) / (2 * np.pi)
    assert freqs.size >= 1
    assert np.allclose(freqs, fref, rtol=1e-8)
    assert scalar(reducer, "solve_calls") > freqs.size   # the eigensolve's steps went through the flexible solver


@pytest.mark.skipif(not os.path.exists(KRYFLEX), reason="build/kryflex not built (scripts/setup)")
@pytest.mark.parametrize("ordering", ["amd", "pord"])
def test_ordering_is_the_one_applied(tmp_path, ordering):
    """-kf_ordering reaches MUMPS' analysis: the progress line reports the ordering MUMPS applied (INFOG(7))."""
    p = subprocess.run([KRYFLEX, "reduce", GALILEO, "-o", str(tmp_path / "o"), "-kf_verify", "false",
                        "-kf_ordering", ordering], env=ENV, capture_output=True, text=True, timeout=120)
    assert p.returncode == 0, p.stderr
    assert ("MUMPS analysis: %s ordering" % ordering) in p.stdout


@pytest.fixture(scope="module")
def solid14k(tmp_path_factory):
    """The 13,513-dof solid pair: large enough that MUMPS' in-core and out-of-core estimates differ (31 / 13 MB)."""
    return solid_scene(tmp_path_factory, "solid14k", 1, ENV)


def _reduce_solid(scene, out, ranks, *options):
    return reduce_solid(scene, out, ranks, *options, env=ENV)


@pytest.mark.mpi
@pytest.mark.skipif(not os.path.exists(KRYFLEX), reason="build/kryflex not built (scripts/setup)")
@pytest.mark.parametrize("ranks", [1, 2])
def test_out_of_core_when_only_that_fits(solid14k, tmp_path, ranks):
    """-kf_ooc auto (the default): a limit between MUMPS' out-of-core and in-core estimates (read off the refusal at a
    tiny limit) factors out of core and says so, with the in-core run's model; -kf_ooc false refuses at that limit."""
    import re
    import json
    p = _reduce_solid(solid14k, tmp_path / "refused", ranks, "-kf_memory_limit_mb", "1e-3")
    assert p.returncode == EXIT_NUMERIC, p.stderr
    m = re.search(r"estimates ([0-9.e+]+) MB in core and ([0-9.e+]+) MB out of core", p.stderr)
    assert m, p.stderr
    incore, ooc = float(m.group(1)), float(m.group(2))
    assert ooc < incore
    between = str((incore * ooc) ** 0.5)
    p = _reduce_solid(solid14k, tmp_path / "ooc", ranks, "-kf_memory_limit_mb", between)
    assert p.returncode == 0, p.stderr
    assert "the factors go out of core" in p.stdout + p.stderr
    p = _reduce_solid(solid14k, tmp_path / "incore", ranks)
    assert p.returncode == 0, p.stderr
    assert "the factors go out of core" not in p.stdout + p.stderr
    a = json.load(open(tmp_path / "ooc" / "summary.json"))
    b = json.load(open(tmp_path / "incore" / "summary.json"))
    assert a["reduced"]["dofs_per_body"] == b["reduced"]["dofs_per_body"]
    fa, fb = (np.array(x["reduced"]["frequencies_hz"]["30"]) for x in (a, b))
    assert np.allclose(fa, fb, rtol=1e-9, atol=0)   # the same model to rounding (out of core orders sums differently)
    assert abs(a["error_max"] - b["error_max"]) <= 1e-6 * b["error_max"]
    p = _reduce_solid(solid14k, tmp_path / "forced", ranks, "-kf_memory_limit_mb", between, "-kf_ooc", "false")
    assert p.returncode == EXIT_NUMERIC, p.stderr
    assert not (tmp_path / "forced" / "summary.json").exists()
