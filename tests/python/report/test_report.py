"""Tests of the verification report writer (python/kryflex/report/).

The summary is computed here from a 4-dof spring-mass chain whose coupling spring and second output depend on
a "joint angle": real frequencies, Krylov modes, moments, a Krylov reduced model built at one angle, FRFs.
The report is then parsed back and compared with these independently computed numbers.
"""

import json
import math
import os
import pathlib
import re
import subprocess
import sys

import numpy as np
import pytest

from kryflex import report
from kryflex.report import plots
from kryflex.results import SUMMARY_VERSION

ROOT = pathlib.Path(__file__).resolve().parents[3]

ANGLES = [0.0, 30.0, 60.0]
LABELS = ["0", "30", "60"]
LABEL_G = "30"
C = 3                 # Krylov vectors (moments matched at alpha_G)
ZETA = 0.02
KEEP = 0.05
MASSES = np.array([1.0, 2.0, 1.5, 1.0])


# =============================================================================================== the analytic system

def stiffness(alpha_deg):
    k_ground, k12, k34 = 400.0, 300.0, 250.0
    k23 = 150.0 * (1.0 + 0.8 * math.sin(math.radians(alpha_deg)) ** 2)
    springs = [(None, 0, k_ground), (0, 1, k12), (1, 2, k23), (2, 3, k34)]
    K = np.zeros((4, 4))
    for i, j, k in springs:
        K[j, j] += k
        if i is not None:
            K[i, i] += k
            K[i, j] -= k
            K[j, i] -= k
    return K


def input_matrix():
    return np.array([[0.0], [0.0], [0.0], [1.0]])        # force on mass 4


def output_matrix(alpha_deg):
    """x1 and a reading that vanishes at alpha = 0 (so its moments are negligible there, like the paper's 0 deg)."""
    return np.array([[1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 0.0, math.sin(math.radians(alpha_deg))]])


def m_orthonormal(vectors, M):
    basis = []
    for v in vectors.T:
        for _ in range(2):
            for b in basis:
                v = v - b * (b @ M @ v)
        basis.append(v / math.sqrt(v @ M @ v))
    return np.array(basis).T


def krylov_basis(K, M, G, count):
    raw = [np.linalg.solve(K, G[:, 0])]
    for _ in range(count - 1):
        raw.append(np.linalg.solve(K, M @ raw[-1]))
    raw = np.array(raw).T
    gram = raw.T @ M @ raw
    return m_orthonormal(raw, M), float(np.linalg.cond(gram))


def modes(K, M):
    """Mass-normalized modes (columns) and frequencies in Hz, by a Cholesky-reduced symmetric eigenproblem."""
    L = np.linalg.cholesky(M)
    Li = np.linalg.inv(L)
    w2, y = np.linalg.eigh(Li @ K @ Li.T)
    return np.sqrt(np.maximum(w2, 0.0)) / (2 * math.pi), Li.T @ y


def moments(K, M, G, H, count):
    out, x = [], np.linalg.solve(K, G)
    for _ in range(count):
        out.append(H @ x)
        x = np.linalg.solve(K, M @ x)
    return out


def frf(freq_hz, f_modes, phi, G, H):
    w = 2 * math.pi * np.asarray(freq_hz)
    wn = 2 * math.pi * f_modes
    hp, pg = H @ phi, phi.T @ G
    denom = wn[None, :] ** 2 - w[:, None] ** 2 + 2j * ZETA * wn[None, :] * w[:, None]
    return np.einsum("om,fm,ma->foa", hp, 1.0 / denom, pg)


def contributions(f_modes, phi, G, H):
    wn = 2 * math.pi * f_modes
    return np.linalg.norm(H @ phi, axis=0) * np.linalg.norm(phi.T @ G, axis=1) / wn ** 2


def reduced_body_frequencies(V, M, Kb, dofs):
    Q, _ = np.linalg.qr(V[dofs, :])
    Mb = M[np.ix_(dofs, dofs)]
    w2 = np.linalg.eigvals(np.linalg.solve(Q.T @ Mb @ Q, Q.T @ Kb @ Q)).real
    return sorted(np.sqrt(np.maximum(w2, 0.0)) / (2 * math.pi))


def hinf_error(T_full, T_red):
    """The contract's measure, written out: max over pairs of max_w |Tf - Tr| / max_w |Tf| (a pair whose peak is
    below 1e-4 of the largest pair's peak measured against 1e-4 x that peak)."""
    peak = np.abs(T_full).max(axis=0)
    peak = np.maximum(peak, 1e-4 * peak.max())
    return float((np.abs(T_full - T_red).max(axis=0) / peak).max())


def pointwise_error(T_full, T_red, floor_db=-60.0):
    """The information measure: per pair max_w |Tf - Tr| / max(|Tf(w)|, 10^(floor/20) max_w |Tf|)."""
    ref = np.maximum(np.abs(T_full), 10 ** (floor_db / 20) * np.abs(T_full).max(axis=0))
    with np.errstate(invalid="ignore"):
        ratio = np.where(ref > 0, np.abs(T_full - T_red) / np.where(ref > 0, ref, 1.0), 0.0)
    return float(ratio.max())


def hankel_singular_values(f_modes, phi, G, H):
    """Of the damped modal system (states (q, qdot) per mode), by two dense Lyapunov solves (SciPy)."""
    import scipy.linalg as sl
    wn = 2 * math.pi * f_modes
    n = wn.size
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-np.diag(wn ** 2), -np.diag(2 * ZETA * wn)]])
    B = np.vstack([np.zeros((n, G.shape[1])), phi.T @ G])
    Cm = np.hstack([H @ phi, np.zeros((H.shape[0], n))])
    P = sl.solve_continuous_lyapunov(A, -B @ B.T)
    Q = sl.solve_continuous_lyapunov(A.T, -Cm.T @ Cm)
    return np.sort(np.sqrt(np.abs(np.linalg.eigvals(P @ Q))))[::-1]


def ratio_matrix(full, red):
    scale = max(abs(full).max(), 1e-300)
    return [[None if abs(f) <= 1e-12 * scale else float(f / r) for f, r in zip(fr, rr)] for fr, rr in zip(full, red)]


def build_summary():
    M = np.diag(MASSES)
    G = input_matrix()
    K_all = {l: stiffness(a) for l, a in zip(LABELS, ANGLES)}
    H_all = {l: output_matrix(a) for l, a in zip(LABELS, ANGLES)}
    V_g, _ = krylov_basis(K_all[LABEL_G], M, G, C)
    V_multi = m_orthonormal(np.hstack([krylov_basis(K_all[l], M, G, C)[0] for l in LABELS]), M)[:, :4]
    f_all = {}
    for l in LABELS:
        f_all[l] = modes(K_all[l], M)
    # Up to below the 4th mode, which the 3-vector reduced model cannot represent.
    band = [0.5 * min(f[0][0] for f in f_all.values()), 0.9 * min(f[0][3] for f in f_all.values())]
    freq = np.logspace(math.log10(band[0]), math.log10(band[1]), 150)
    s = {"kryflex_version": "test", "scene": "chain4", "scene_file": "chain4.yaml",
         "inputs": ["force4"], "outputs": ["x1", "x4_rot"], "joints": ["hinge"],
         "angles_deg": [[a] for a in ANGLES], "angle_labels": LABELS, "band_hz": band, "damping": ZETA,
         "settings": {"moments": C, "output_blocks": 1, "importance": "h2", "keep_threshold": KEEP,
                      "deflation_tol": 1e-10, "reduction_angles_deg": [[30.0]], "method": "single-angle"},
         "full": {"dofs_per_body": {"A": 2, "B": 2}, "system_dofs": 4, "rigid_modes": 0,
                  "body_frequencies_hz": {}, "frequencies_hz": {}, "moments": {}},
         "krylov": {}, "reduction_label": LABEL_G, "reduction_rule": "most important Krylov modes (test)",
         "reduced": {"dofs_per_body": {"A": 2, "B": 2}, "body_frequencies_hz": {}, "system_dofs": {},
                     "frequencies_hz": {}, "moments": {}, "moment_ratios": {}, "static_gain_error": {},
                     "reassembly_rank": {}, "reassembly_sigma_ratio": {}, "reassembly_seconds": 0.01},
         "frf": {}, "dominant_modes": {}, "dominant_freq_error": {},
         "multi_angle": {"system_dofs": {}, "dofs_per_body": {"A": 2, "B": 2}, "moment_ratios": {},
                         "frf_max_rel_error": {}},
         "timings_s": {"assemble": 0.5, "krylov": 0.25}, "notes": ["synthetic test summary"]}
    # Body A: masses 1-2 with the ground and 1-2 springs; body B: masses 3-4 with the 3-4 spring (free-free).
    body_K = {"A": np.array([[700.0, -300.0], [-300.0, 300.0]]), "B": np.array([[250.0, -250.0], [-250.0, 250.0]])}
    for dofs, body in (([0, 1], "A"), ([2, 3], "B")):
        fb, _ = modes(body_K[body], M[np.ix_(dofs, dofs)])
        s["full"]["body_frequencies_hz"][body] = fb.tolist()
        s["reduced"]["body_frequencies_hz"][body] = [
            float(x) for x in reduced_body_frequencies(V_g, M, body_K[body], dofs)]
    accuracy_errors, pointwise = {}, {}
    s["hankel"] = {}
    for l in LABELS:
        K, H = K_all[l], H_all[l]
        f_full, phi = f_all[l]
        s["full"]["frequencies_hz"][l] = f_full.tolist()
        full_moments = moments(K, M, G, H, C)
        s["full"]["moments"][l] = [m.tolist() for m in full_moments]
        Vk, cond = krylov_basis(K, M, G, C)
        f_k, psi = modes(Vk.T @ K @ Vk, np.eye(C))
        imp = contributions(f_k, Vk @ psi, G, H)
        imp = imp / imp.max()
        s["krylov"][l] = {"frequency_hz": f_k.tolist(), "importance": imp.tolist(),
                          "kept": [bool(v >= KEEP) for v in imp], "deflations": 0, "gram_condition_raw": cond}
        Kr, Mr, Gr, Hr = V_g.T @ K @ V_g, V_g.T @ M @ V_g, V_g.T @ G, H @ V_g
        f_red, phi_r = modes(Kr, Mr)
        s["reduced"]["frequencies_hz"][l] = f_red.tolist()
        s["reduced"]["system_dofs"][l] = C
        red_moments = moments(Kr, Mr, Gr, Hr, C)
        s["reduced"]["moments"][l] = [m.tolist() for m in red_moments]
        s["reduced"]["moment_ratios"][l] = [ratio_matrix(f, r) for f, r in zip(full_moments, red_moments)]
        s["reduced"]["static_gain_error"][l] = float(np.linalg.norm(full_moments[0] - red_moments[0])
                                                     / np.linalg.norm(full_moments[0]))
        s["reduced"]["reassembly_rank"][l] = C
        s["reduced"]["reassembly_sigma_ratio"][l] = 1e-15
        H_full, H_red = frf(freq, f_full, phi, G, H), frf(freq, f_red, V_g @ phi_r, G, H)
        accuracy_errors[l] = hinf_error(H_full, H_red)
        pointwise[l] = pointwise_error(H_full, H_red)
        s["frf"][l] = {"freq_hz": freq.tolist(), "full_re": H_full.real.tolist(), "full_im": H_full.imag.tolist(),
                       "reduced_re": H_red.real.tolist(), "reduced_im": H_red.imag.tolist(),
                       "frf_error": accuracy_errors[l], "frf_pointwise_error": pointwise[l],
                       "max_rel_error": accuracy_errors[l]}
        hsv = hankel_singular_values(f_full, phi, G, H)
        s["hankel"][l] = {"order": hankel_order(hsv), "singular_values": hsv.tolist()}
        contrib = contributions(f_full, phi, G, H)
        dominant = [int(i) for i in np.flatnonzero(contrib >= 0.1 * contrib.max())]
        s["dominant_modes"][l] = dominant
        s["dominant_freq_error"][l] = [float(abs(f_red[np.argmin(abs(f_red - f_full[i]))] - f_full[i]) / f_full[i])
                                       for i in dominant]
        Km, Mm, Gm, Hm = V_multi.T @ K @ V_multi, V_multi.T @ M @ V_multi, V_multi.T @ G, H @ V_multi
        s["multi_angle"]["system_dofs"][l] = 4
        s["multi_angle"]["moment_ratios"][l] = [ratio_matrix(f, r) for f, r in
                                                zip(full_moments, moments(Km, Mm, Gm, Hm, C))]
        s["multi_angle"]["frf_max_rel_error"][l] = 0.0
    kept_g = [m + 1 for m, k in enumerate(s["krylov"][LABEL_G]["kept"]) if k]
    s["kept_modes"] = kept_g
    s["static_correction_modes"] = C - len(kept_g)
    # A target strictly between the best and the worst configuration: at least one PASS and one MISS.
    errors = sorted(accuracy_errors.values())
    s["accuracy"] = math.sqrt(errors[0] * errors[-1])
    for l in LABELS:
        # the bound's scale: a model within e x each pair's peak has a 2-norm error below sqrt(t a) e max|T_full|
        full = np.array(s["frf"][l]["full_re"]) + 1j * np.array(s["frf"][l]["full_im"])
        scale = math.sqrt(2 * 1) * np.abs(full).max()
        hsv = np.array(s["hankel"][l]["singular_values"])
        s["hankel"][l].update(order=hankel_order(hsv, s["accuracy"] * scale), scale=scale, chosen_states=2 * C,
                              bound_at_chosen=float(hsv[2 * C] / scale))
    # the single-angle model at the midpoints between the angles of interest
    s["midpoints"] = []
    for a0, a1 in zip(ANGLES[:-1], ANGLES[1:]):
        mid = 0.5 * (a0 + a1)
        K, H = stiffness(mid), output_matrix(mid)
        f_full, phi = modes(K, M)
        f_red, phi_r = modes(V_g.T @ K @ V_g, V_g.T @ M @ V_g)
        e = hinf_error(frf(freq, f_full, phi, G, H), frf(freq, f_red, V_g @ phi_r, G, H))
        s["midpoints"].append({"angles_deg": [mid], "label": f"{mid:g}", "frf_error": e})
    # the search: single-angle models of c = 1 .. C moments at alpha_G, their worst error over the angles
    s["search"] = []
    for c in range(1, C + 1):
        Vc, _ = krylov_basis(K_all[LABEL_G], M, G, c)
        worst = 0.0
        for l in LABELS:
            f_red, phi_r = modes(Vc.T @ K_all[l] @ Vc, Vc.T @ M @ Vc)
            worst = max(worst, hinf_error(frf(freq, *f_all[l], G, H_all[l]), frf(freq, f_red, Vc @ phi_r, G, H_all[l])))
        s["search"].append({"family": "single-angle", "moments": c, "kept_clusters": None, "expansion_angles": 1,
                            "reduced_dofs": c, "max_system_dofs": c, "error": worst})
    s["search_chosen"] = C - 1
    all_errors = list(accuracy_errors.values()) + [m["frf_error"] for m in s["midpoints"]]
    worst = max(range(len(all_errors)), key=lambda k: all_errors[k])
    places = [(l, "angle") for l in LABELS] + [(m["label"], "midpoint") for m in s["midpoints"]]
    s.update({"chosen_method": "single-angle", "moments_matched": C, "multi_moments_matched": C,
              "target_met": bool(max(all_errors) <= s["accuracy"]), "error_max": max(all_errors),
              "error_estimated": False, "frf_floor_db": -60.0,
              "error_definition": "relative H-infinity error per input/output pair (test)",
              "chosen": {"method": "single-angle", "moments": C, "dofs_per_body": {"A": 2, "B": 2}, "dofs": 4,
                         "system_dofs": {l: C for l in LABELS}, "expansion_angles_deg": [[30.0]],
                         "kept_modes": kept_g, "kept_clusters": None,
                         "frf_error": dict(accuracy_errors), "frf_pointwise_error": dict(pointwise),
                         "worst_error": all_errors[worst], "worst_where": places[worst][0],
                         "worst_kind": places[worst][1]}})
    return s


def hankel_order(hsv, limit=None):
    """The fewest states r with sigma_(r+1) <= limit (None before the target is known)."""
    if limit is None:
        return None
    return next(r for r in range(len(hsv) + 1) if r == len(hsv) or hsv[r] <= limit)


# =============================================================================================== helpers

def table_after(markdown, caption_start):
    """Cells of the Markdown table that follows the line starting with caption_start (header row first)."""
    lines = markdown.splitlines()
    start = next(n for n, line in enumerate(lines) if line.startswith(caption_start))
    rows, n = [], start + 1
    while not lines[n].startswith("|"):
        n += 1
    while n < len(lines) and lines[n].startswith("|"):
        rows.append([cell.strip() for cell in lines[n].strip("|").split("|")])
        n += 1
    return [rows[0]] + rows[2:]          # drop the alignment rule


def number(cell):
    return float(cell.replace("−", "-").rstrip("*†‡ ").replace(" %", ""))


@pytest.fixture(scope="module")
def summary():
    return build_summary()


@pytest.fixture(scope="module")
def written(summary, tmp_path_factory):
    out = tmp_path_factory.mktemp("report")
    paths = report.write_report(summary, str(out))
    return out, paths, (out / "report.md").read_text(encoding="utf-8")


# =============================================================================================== tests

def test_every_file_is_written_and_valid(summary, written):
    out, paths, _ = written
    names = {pathlib.Path(p).name for p in paths}
    expected = {"summary.json", "report.md", "bode_overview.png", "moment_ratios.png", "frf_error.png"}
    expected |= {f"importance_{l}deg.png" for l in LABELS}
    expected |= {f"bode_{l}deg.png" for l in LABELS}      # every input/output pair of a configuration in one figure
    assert names == expected
    assert all(pathlib.Path(p).parent == out for p in paths)
    for name in names:
        if name.endswith(".png"):
            assert (out / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n", name
    # every key and value as given, at the current summary version (the synthetic summary has none: version 1)
    assert json.loads((out / "summary.json").read_text()) == dict(summary, summary_version=SUMMARY_VERSION)
    assert not list(out.glob(".*.tmp"))


def test_pair_plots_add_a_figure_per_pair(summary, written, tmp_path):
    """write_report(pair_plots=True) (kryflex reduce --pair-plots) writes a Bode figure per configuration and pair
    besides the default files, their bytes unchanged; report.md links every figure written."""
    out, paths, _ = written
    paths2 = report.write_report(summary, str(tmp_path), pair_plots=True)
    names = {pathlib.Path(p).name for p in paths}
    names2 = {pathlib.Path(p).name for p in paths2}
    per_pair = {f"bode_{l}deg_{o}_force4.png" for l in LABELS for o in ("x1", "x4_rot")}
    assert names2 == names | per_pair
    for name in names - {"report.md"}:
        assert (tmp_path / name).read_bytes() == (out / name).read_bytes(), name
    for folder, files in ((out, names), (tmp_path, names2)):
        markdown = (folder / "report.md").read_text(encoding="utf-8")
        for name in files - {"report.md", "summary.json", "moment_ratios.png", "frf_error.png", "bode_overview.png"}:
            assert "](%s)" % name in markdown, name
    assert "![Bode plots at α_G (α = 30°)](bode_30deg.png)" in (out / "report.md").read_text(encoding="utf-8")


def test_many_pairs_get_a_figure_each(summary, tmp_path, monkeypatch):
    """A configuration with more than MAX_PAIRS_PER_FIGURE input/output pairs gets a Bode figure per pair (a figure of
    that many cells would not be read), linked from report.md; at most that many, one figure."""
    from kryflex.report import figures
    assert figures.MAX_PAIRS_PER_FIGURE >= 2 and set(figures.plot_file_names(summary)["bode_pairs"]) == set(LABELS)
    monkeypatch.setattr(figures, "MAX_PAIRS_PER_FIGURE", 1)          # the summary's two pairs are then too many
    names = figures.plot_file_names(summary)
    assert not names["bode_pairs"] and set(names["bode"]) == {(l, (o, 0)) for l in LABELS for o in (0, 1)}
    paths = report.write_report(summary, str(tmp_path))
    per_pair = {f"bode_{l}deg_{o}_force4.png" for l in LABELS for o in ("x1", "x4_rot")}
    assert per_pair <= {pathlib.Path(p).name for p in paths}
    assert not any(pathlib.Path(p).name == "bode_30deg.png" for p in paths)
    markdown = (tmp_path / "report.md").read_text(encoding="utf-8")
    assert all("](%s)" % name in markdown for name in per_pair)


def test_modules_import_standalone():
    """The report needs only the standard library, NumPy and matplotlib: importing it in a fresh interpreter loads no
    compiled kryflex code and no PETSc."""
    code = ("import sys, kryflex.report, kryflex.report.plots; "
            "print(sorted(m for m in sys.modules if m.endswith('_core') or m.startswith(('petsc4py', 'slepc4py'))))")
    env = dict(os.environ, PYTHONPATH=str(ROOT / "python"))
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == "[]"


def test_full_order_frequency_table(summary, written):
    markdown = written[2]
    rows = table_after(markdown, "Table 1b.")
    assert len(rows) - 1 == 4
    for m, row in enumerate(rows[1:]):
        assert int(row[0]) == m + 1
        for col, label in enumerate(LABELS, start=1):
            assert number(row[col]) == pytest.approx(summary["full"]["frequencies_hz"][label][m], rel=1e-4)


def test_krylov_importance_tables_mark_kept_modes(summary, written):
    markdown = written[2]
    for n, label in enumerate(LABELS, start=1):
        rows = table_after(markdown, f"Table 3.{n}.")[1:]
        kr = summary["krylov"][label]
        assert [r[0].endswith("*") for r in rows] == kr["kept"]
        assert [number(r[1]) for r in rows] == pytest.approx(kr["frequency_hz"], rel=1e-4)
        assert [number(r[2]) for r in rows] == pytest.approx(kr["importance"], abs=1e-4)


def test_moment_table_mantissas_times_scale_give_the_moments(summary, written):
    markdown = written[2]
    rows = table_after(markdown, "Table 5 (x4_rot ← force4)")
    for k, row in enumerate(rows[1:]):
        scale = float(row[1])
        values = [summary["full"]["moments"][l][k][1][0] for l in LABELS]
        biggest = max(abs(v) for v in values)
        assert 1.0 <= biggest / scale < 10.0
        for cell, value in zip(row[2:], values):
            assert number(cell) * scale == pytest.approx(value, abs=1e-4 * biggest)


def test_ratio_table_has_ten_digits_and_dashes(summary, written):
    markdown = written[2]
    for entry, name in ((0, "x1 ← force4"), (1, "x4_rot ← force4")):
        rows = table_after(markdown, f"Table 6 ({name})")[1:]
        assert len(rows) == C
        for k, row in enumerate(rows):
            for cell, label in zip(row[1:], LABELS):
                expected = summary["reduced"]["moment_ratios"][label][k][entry][0]
                if expected is None:
                    assert cell == "—"
                else:
                    assert number(cell) == pytest.approx(expected, rel=1e-9)
    # the vanishing reading at alpha = 0 has undefined ratios, shown as a dash
    assert summary["reduced"]["moment_ratios"]["0"][0][1][0] is None


def test_inexact_moments_are_called_out(summary, written):
    markdown = written[2]
    sentence = next(line for line in markdown.splitlines() if "single-angle model does NOT match" in line)
    quoted = [float(x) for x in re.findall(r"ratio (-?\d+\.\d+(?:e[-+]\d+)?)", sentence)]
    mismatched = [r for l in LABELS for matrix in summary["reduced"]["moment_ratios"][l] for row in matrix
                  for r in row if r is not None and abs(r - 1) > 1e-8]
    assert mismatched, "the test system must have moments that are not matched away from alpha_G"
    assert len(quoted) == len(mismatched)
    worst = max(mismatched, key=lambda r: abs(r - 1))
    assert any(q == pytest.approx(worst, rel=1e-9) for q in quoted)
    assert "α = 30° (α_G), k =" not in sentence          # exact at the reduction angle
    assert "multi-angle model equal 1" in markdown       # the union basis spans the whole space


def test_verdict_is_the_chosen_models_hinf_error_at_angles_and_midpoints(summary, written):
    """Table 7: one row per angle of interest and per midpoint; the error column is the relative H-inf error per pair
    (computed here independently), PASS/MISS on it; no pointwise column in the verdict table."""
    rows = table_after(written[2], "Table 7.")
    header = rows[0]
    assert header[2].startswith("relative H∞ error") and header[4] == "result"
    assert not any("pointwise" in cell for cell in header)
    expected = [(label, summary["chosen"]["frf_error"][label], "angle of interest") for label in LABELS]
    expected += [(m["label"], m["frf_error"], "midpoint") for m in summary["midpoints"]]
    assert len(rows) - 1 == len(expected) == 5
    verdicts = []
    for row, (label, err, where) in zip(rows[1:], expected):
        assert row[0].startswith(label + "°") and row[1] == where
        assert number(row[2]) == pytest.approx(err, rel=5e-3)
        assert number(row[3]) == pytest.approx(summary["accuracy"], rel=5e-3)
        assert row[4] == ("PASS" if err <= summary["accuracy"] else "MISS")
        verdicts.append(row[4])
    assert set(verdicts) == {"PASS", "MISS"}
    # the sentence under the table carries the C verdict (target_met, error_max) and where the worst error is
    assert summary["target_met"] is False
    line = next(x for x in written[2].splitlines() if x.startswith("Worst error"))
    assert f"{summary['error_max']:.3g} (measured)" in line and "**target MISSED**" in line
    assert summary["chosen"]["worst_kind"] == "angle" and "α = 60°" in line


def test_pointwise_error_is_a_separate_information_table(summary, written):
    markdown = written[2]
    caption = next(x for x in markdown.splitlines() if x.startswith("Table 7b."))
    assert "information only, not the verdict" in caption
    rows = table_after(markdown, "Table 7b.")
    assert "information" in rows[0][1] and len(rows[0]) == 2        # no PASS/MISS beside it
    for row, label in zip(rows[1:], LABELS):
        assert number(row[1]) == pytest.approx(summary["chosen"]["frf_pointwise_error"][label], rel=5e-3)
    # the notch of the test system: the pointwise error is far above the H-inf one, and it is not what is judged
    assert all(summary["chosen"]["frf_pointwise_error"][l] > 10 * summary["chosen"]["frf_error"][l] for l in LABELS)


def test_plotted_error_curve_peaks_at_the_verdicts_error(summary):
    """frf_error.png draws |Tf - Tr| / peak per worst pair: its maximum over the band is the H-inf measure."""
    for label in LABELS:
        freq, full, red = plots.frf_arrays(summary["frf"][label])
        curve = plots.frf_hinf_error_curve(full, red)
        assert curve.shape == freq.shape
        assert curve.max() == pytest.approx(hinf_error(full, red), rel=1e-12)
        assert curve.max() == pytest.approx(summary["frf"][label]["frf_error"], rel=1e-12)


def test_search_table_and_hankel_bound(summary, written):
    markdown = written[2]
    assert "How the model was chosen" in markdown
    rows = table_after(markdown, "Table 8.")
    assert rows[0][:9] == ["family", "moments c", "kept clusters", "expansion angles", "size (dofs, all bodies)",
                           "max system dofs", "error", "target", "variant"]
    assert len(rows) - 1 == len(summary["search"])
    for k, (row, cand) in enumerate(zip(rows[1:], summary["search"])):
        assert row[0] == cand["family"] and int(row[1]) == cand["moments"] and row[2] == "all"
        assert int(row[4]) == cand["reduced_dofs"]
        assert number(row[6]) == pytest.approx(cand["error"], rel=5e-3)
        assert row[8] == "—"                            # this summary's candidates carry no variant
        assert (row[9] == "◀ chosen") == (k == summary["search_chosen"])
    errors = [cand["error"] for cand in summary["search"]]
    assert errors == sorted(errors, reverse=True)     # more moments, smaller error (independently computed)
    rows = table_after(markdown, "Table 9.")
    assert "no model of k states can do better than" in rows[0][3]
    for row, label in zip(rows[1:], LABELS):
        hsv = summary["hankel"][label]["singular_values"]
        states = 2 * C                                  # the chosen model: C flexible dofs, no rigid modes
        assert int(row[1]) == C and int(row[2]) == states
        full = np.array(summary["frf"][label]["full_re"]) + 1j * np.array(summary["frf"][label]["full_im"])
        bound = hsv[states] / (math.sqrt(2) * np.abs(full).max())       # t a = 2 pairs
        assert number(row[3]) == pytest.approx(bound, rel=5e-3)
        # a lower bound: the chosen model's error (measured independently) is not below it
        assert bound <= summary["chosen"]["frf_error"][label]
        order = summary["hankel"][label]["order"]
        assert int(row[4]) == order and int(row[5]) == (order + 1) // 2


def test_a_multi_angle_choice_is_judged_on_the_multi_angle_model(summary, tmp_path):
    """When the reducer chose the multi-angle model, its errors and its responses are reported, not the single-angle
    model's (which miss the target here)."""
    s = json.loads(json.dumps(summary))
    M, G = np.diag(MASSES), input_matrix()
    V = m_orthonormal(np.hstack([krylov_basis(stiffness(a), M, G, 2)[0] for a in (0.0, 60.0)]), M)
    errors = {}
    for label, angle in zip(LABELS, ANGLES):
        K, H = stiffness(angle), output_matrix(angle)
        freq = np.array(s["frf"][label]["freq_hz"])
        f_red, phi_r = modes(V.T @ K @ V, V.T @ M @ V)
        T = frf(freq, f_red, V @ phi_r, G, H)
        full = np.array(s["frf"][label]["full_re"]) + 1j * np.array(s["frf"][label]["full_im"])
        errors[label] = hinf_error(full, T)
        s["frf"][label].update(chosen_re=T.real.tolist(), chosen_im=T.imag.tolist())
    s["chosen_method"] = "multi-angle"
    s["midpoints"] = []
    s["chosen"].update(method="multi-angle", frf_error=errors, frf_pointwise_error={l: None for l in LABELS},
                       kept_modes=None, expansion_angles_deg=[[0.0], [60.0]], worst_error=max(errors.values()))
    s["error_max"] = max(errors.values())
    s["target_met"] = s["error_max"] <= s["accuracy"]
    assert any(s["frf"][l]["frf_error"] > s["accuracy"] for l in LABELS)    # the single-angle model would miss
    report.write_report(s, str(tmp_path))
    markdown = (tmp_path / "report.md").read_text(encoding="utf-8")
    assert "The chosen model is the **multi-angle model**" in markdown
    assert "expansion angles 0°, 60°" in markdown
    for row, label in zip(table_after(markdown, "Table 7.")[1:], LABELS):
        assert number(row[2]) == pytest.approx(errors[label], rel=5e-3)
    assert "Table 7b." not in markdown                 # no pointwise numbers were given: no information table
    freq, full, red = plots.frf_arrays(s["frf"]["60"])
    np.testing.assert_array_equal(red, np.array(s["frf"]["60"]["chosen_re"]) + 1j * np.array(s["frf"]["60"]["chosen_im"]))


def test_dominant_mode_errors_and_kept_modes(summary, written):
    markdown = written[2]
    rows = table_after(markdown, "Table 4c.")[1:]
    expected = [e for l in LABELS for e in summary["dominant_freq_error"][l]]
    assert [number(r[3]) / 100 for r in rows] == pytest.approx(expected, rel=1e-2, abs=1e-12)
    kept = summary["kept_modes"]
    assert f"keeps {len(kept)} of the {C} Krylov modes" in markdown
    assert "![Bode overview](bode_overview.png)" in markdown


def test_missing_key_raises_and_writes_nothing(summary, tmp_path):
    broken = dict(summary)
    del broken["frf"]
    out = tmp_path / "out"
    with pytest.raises(report.ReportError, match=r"summary\['frf'\] is missing"):
        report.write_report(broken, str(out))
    assert not out.exists() or not any(out.iterdir())


def test_numpy_value_is_rejected_with_its_key(summary, tmp_path):
    broken = json.loads(json.dumps(summary))
    broken["frf"]["60"]["max_rel_error"] = np.float32(0.1)
    with pytest.raises(report.ReportError, match=r"\['frf'\]\['60'\]\['max_rel_error'\].*float"):
        report.write_report(broken, str(tmp_path))
    assert not any(tmp_path.iterdir())


def test_failure_mid_way_keeps_the_previous_report(summary, written, tmp_path, monkeypatch):
    out = tmp_path / "out"
    report.write_report(summary, str(out))
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    changed = json.loads(json.dumps(summary))
    changed["notes"] = ["second run"]

    def failing_figure(*args, **kwargs):
        raise RuntimeError("plot failed on purpose")

    monkeypatch.setattr(plots, "frf_error_figure", failing_figure)
    monkeypatch.setenv("KRYFLEX_REPORT_HELPER", "0")    # every figure drawn in this process, where the patch is
    with pytest.raises(RuntimeError, match="on purpose"):
        report.write_report(changed, str(out))
    after = {p.name: p.read_bytes() for p in out.iterdir()}
    assert after == before                              # no temporary file left, nothing half-replaced


def test_bode_phase_of_full_and_reduced_never_differs_by_a_wrap():
    """A lightly damped notch whose zero pair lies just left of the axis in one model and just right in the other:
    the two responses agree to 2e-5 away from the notch, but unwrap reads the jump across it as +180 degrees in one
    and -180 in the other. The drawn phases must differ by the true (wrapped) phase difference at every frequency,
    not by 360 degrees after the notch (the report's Bode plots at 30 degrees on the Galileo scene)."""
    freq = np.geomspace(0.5, 20.0, 300)
    s = 2j * np.pi * freq
    wp, wz = 2 * np.pi * 3.0, 2 * np.pi * 8.0

    def response(zeta_zero):
        return (s ** 2 + 2 * zeta_zero * wz * s + wz ** 2) / (s ** 2 + 2 * 0.01 * wp * s + wp ** 2) / wz ** 2

    full, reduced = response(1e-5), response(-1e-5)
    assert np.max(np.abs(full - reduced)) <= 2e-5 * np.max(np.abs(full))
    # the failure this guards against: each curve unwrapped alone ends 360 degrees from the other
    alone = plots.phase_deg(reduced, plots.phase_deg(full)[0]) - plots.phase_deg(full)
    assert np.max(np.abs(alone)) == pytest.approx(360.0, abs=1.0)
    ph_full, ph_red = plots.phase_pair_deg(full, reduced)
    true_difference = np.degrees(np.angle(reduced / full))
    np.testing.assert_allclose(ph_red - ph_full, true_difference, atol=1e-9)
    assert np.all(np.abs(np.diff(ph_full)) < 180.0)          # the full curve itself is unwrapped
    # the phases are those of the responses, up to whole turns
    np.testing.assert_allclose(np.exp(1j * np.radians(ph_full)), full / np.abs(full), atol=1e-12)


def test_a_bad_number_inside_an_frf_block_is_named(summary, tmp_path):
    # the FRF blocks (lists of lists of numbers) are checked in one pass; a bad number deep inside is still named
    for bad, what in ((float("nan"), "is nan"), (np.float32(0.5), "is a numpy.float32")):
        broken = json.loads(json.dumps(summary))
        broken["frf"]["60"]["full_re"][3][1][0] = bad
        with pytest.raises(report.ReportError, match=r"summary\['frf'\]\['60'\]\['full_re'\]\[3\]\[1\]\[0\] %s" % what):
            report.write_report(broken, str(tmp_path))
        assert not any(tmp_path.iterdir())
