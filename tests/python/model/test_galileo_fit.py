"""The Galileo model's fit to the whole of Lee's example with physical masses, and what the tables imply.

The paper: A. Y. Lee, "A Krylov Model Reduction Methodology for Articulated, Multi-Flexible Body Structures", Jet
Propulsion Laboratory (JPL). meshes/galileo/fit.py fits the model to Table 1 (system at 0 deg), Table 4 (full-order
system at 60 deg) and Table 5 (moments L^0..L^9 at six angles), every lumped mass and inertia within a factor 2 of
a Galileo-class layout. Its targets: every system frequency within 0.5 %, every L^k within 5 % and of the paper's
sign. With physical masses Table 1 cannot be met (meshes/galileo/implied.py: a bound for any mode shapes), so the
committed model stays the fit to Table 1 (fit.json); the physical fits are fit_physical.json (the whole example)
and fit_physical_table5.json (Table 5 alone), each recording entry by entry what it reaches ("achieved").

Here every figure is measured independently of fit.py: the model generate.py builds from each file, written and
read back by reference.py, the system assembled there (its own constraint rows, null space by SVD), a dense SciPy
eigensolve, and the moments both as a modal sum and as H (K+ M)^k K+ G with the pseudo-inverse on the flexible
subspace. The paper's numbers are typed again here from the paper. The tests check the targets where a file says
they are met, and that its account of the entries it says are missed is true (so the README's residual tables
cannot claim more than the model does); and they check implied.py's bounds on sampled models.

Run: PYTHONPATH=python .venv/bin/python -m pytest -q tests/python/model/test_galileo_fit.py
"""
import importlib.util
import json
import os
import sys

import numpy as np
import pytest
import scipy.linalg as sl

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(os.path.dirname(HERE)))
sys.path.insert(0, os.path.join(os.path.dirname(HERE), "support"))   # the helpers (tests/python/support)
import reference as ref  # noqa: E402

pytestmark = pytest.mark.fast   # the fast tier (tests/README.md): dense 28-dof solves, seconds

GALILEO = os.path.join(ROOT, "meshes", "galileo", "galileo.yaml")
FITS = [os.path.join(ROOT, "meshes", "galileo", name) for name in ("fit_physical.json", "fit_physical_table5.json")]

# Table 1, system column at 0 deg, and Table 4's full-order column at 60 deg: flexible modes 8-28 (Hz)
SYSTEM_0 = [0.1106, 1.0521, 1.9403, 2.3975, 2.8446, 3.4648, 4.9930, 5.4793, 6.8081, 9.2953, 56.060, 73.429, 75.823,
            76.999, 144.69, 144.73, 712.64, 712.65, 1217.7, 1985.9, 2108.5]
SYSTEM_60 = [0.1123, 1.0520, 1.8163, 2.4863, 2.8750, 3.5946, 4.9689, 5.1388, 7.1262, 9.2069, 56.060, 73.429, 75.823,
             76.999, 144.69, 144.73, 712.64, 712.64, 1217.7, 1985.9, 2108.5]
# Table 5: L^k (k = 0..9, rows) at 0, 15, 30, 45, 60, 72 deg (columns), printed mantissa x row scale
ANGLES = [0, 15, 30, 45, 60, 72]
SCALE = [1e-7, 1e-8, 1e-8, 1e-7, 1e-7, 1e-7, 1e-6, 1e-6, 1e-6, 1e-6]
TABLE5 = [[-1.8910, -1.8009, -1.5520, -1.1973, -0.7973, -0.4739],
          [-0.2396, 0.4015, 1.8967, 3.2367, 3.4613, 2.5805],
          [-0.0042, 1.3059, 4.3198, 6.9248, 7.2071, 5.3085],
          [-0.0000, 0.2705, 0.8863, 1.4057, 1.4478, 1.0595],
          [-0.0000, 0.5587, 1.8169, 2.8524, 2.9075, 2.1140],
          [-0.0000, 1.1539, 3.7246, 5.7878, 5.8389, 4.2182],
          [-0.0000, 0.2383, 0.7635, 1.1744, 1.1726, 0.8417],
          [-0.0000, 0.4922, 1.5652, 2.3830, 2.3548, 1.6794],
          [-0.0000, 1.0164, 3.2086, 4.8353, 4.7290, 3.3509],
          [-0.0000, 2.0992, 6.5775, 9.8113, 9.4968, 6.6861]]
PAPER_L = np.array(TABLE5) * np.array(SCALE)[:, None]
# a printed 0.0000 means |L| below half a unit of the last digit
HALF_DIGIT = 0.5e-4 * np.array(SCALE)[:, None] * np.ones((1, len(ANGLES)))
FREQ_TOL, MOMENT_TOL = 0.005, 0.05


def load_module(name, path):
    spec = importlib.util.spec_from_file_location(name, path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


# the physical layout the fit is held to: every lumped mass and inertia within PHYS_BAND of generate.py's tables
# (README.md: Mass layout); typed here as the README states it
PHYS_BAND = 2.0


@pytest.fixture(scope="module")
def generate():
    sys.path.insert(0, os.path.join(ROOT, "meshes"))
    return load_module("galileo_generate_fit", os.path.join(ROOT, "meshes", "galileo", "generate.py"))


@pytest.fixture(scope="module", params=FITS, ids=os.path.basename)
def fit_file(request):
    return request.param


@pytest.fixture(scope="module")
def galileo(generate, fit_file, tmp_path_factory):
    """The model generate.py builds from the fit file, written to files and read back by reference.py."""
    out = str(tmp_path_factory.mktemp("galileo_fit"))
    (Ms, Ks, ts), (Mr, Kr, tr) = generate.build_bodies(fit_file)
    generate.write_body(out, "stator", Ms, Ks, ts, [n[1] for n in generate.STATOR_NODES])
    generate.write_body(out, "rotor", Mr, Kr, tr, [generate.ROTOR_HUB[1]] + [a[1] for a in generate.ROTOR_APPENDAGES])
    generate.write_scene(out)
    return ref.load_scene(os.path.join(out, "galileo.yaml"))


@pytest.fixture(scope="module")
def achieved(fit_file):
    with open(fit_file) as f:
        return json.load(f)["achieved"]


@pytest.fixture(scope="module")
def measured(galileo):
    """Frequencies (Hz, flexible) and moments L^0..L^9 at the six angles, by a dense eigensolve of the system."""
    out = {}
    for a in ANGLES:
        Ms, Ks, Gs, Hs = ref.assemble(galileo, a)
        lam = sl.eigh(Ks, Ms, eigvals_only=True)
        assert np.all(np.abs(lam[:7]) <= 1e-9 * lam[-1]) and lam[7] > 1e6 * np.abs(lam[:7]).max()
        # the modes from the flexibility form (M, K + s M), mu = 1 / (lambda + s): the lowest flexible modes to
        # machine precision relative to themselves (eigh(K, M) knows them only relative to the highest, and a
        # bearing node of a few kg under a tonne spreads the spectrum over 1e9)
        shift = 0.5 * lam[7]
        mu, X = sl.eigh(Ms, Ks + shift * Ms)
        mu, X = mu[::-1][7:], X[:, ::-1][:, 7:]
        lf, phi = 1.0 / mu - shift, X / np.sqrt(mu)
        r = (Hs[0] @ phi) * (phi.T @ Gs[:, 0])
        L = np.array([np.sum(r / lf ** (k + 1)) for k in range(10)])
        out[a] = (np.sqrt(lf) / (2 * np.pi), L, (Ms, Ks, Gs, Hs))
    return out


def moment_scale(Ms, Ks, Gs, Hs):
    """sum over flexible modes |H phi| |phi^T G| / lambda^(k+1), k = 0..9: what L^k would be without cancellation
    between modes, the scale of its round-off (at 0 deg L^3..L^9 cancel to ~1e-5 of it)."""
    lam, phi = sl.eigh(Ks, Ms)
    lam, phi = lam[7:], phi[:, 7:]
    r = np.abs(Hs[0] @ phi) * np.abs(phi.T @ Gs[:, 0])
    return np.array([np.sum(r / lam ** (k + 1)) for k in range(10)])


def moment_met(model, paper, floor, noise=0.0):
    """Within MOMENT_TOL and of the paper's sign; for a printed 0, within half its last digit. None when the model's
    round-off (noise) straddles the threshold: double precision cannot decide it."""
    if abs(paper) <= floor:
        return None if abs(abs(model) - floor) <= noise else abs(model) <= floor
    if abs(abs(model - paper) - MOMENT_TOL * abs(paper)) <= noise:
        return None
    return np.sign(model) == np.sign(paper) and abs(model / paper - 1) <= MOMENT_TOL


# round-off of the moments relative to each L^k's size over the angles: the routes below agree to 1e-7 of it on
# the stick-layout fits; a bearing node of a few kg under 2 t spreads the mass matrix over 1e3 and the spectrum
# over 1e9, and two flexibility-form solves (different shifts) then differ by up to 7e-6 of it (L^4 at 0 deg,
# where it cancels to 1e-5 of its size)
ROUNDOFF = 1e-5


def test_moments_two_ways_agree(measured):
    """The modal sum (reference.moments) against H (K+ M)^k K+ G with K+ the pseudo-inverse on the flexible
    subspace (rigid modes from the eigensolve removed by an M-orthogonal projector): the moment the fit targets is
    the one the paper defines (eq. 5)."""
    # each L^k against its size over the angles: at 0 deg L^3..L^9 cancel to 1e-5 of it, below the round-off of
    # either route
    scale = np.max([moment_scale(*measured[a][2]) for a in ANGLES], axis=0)
    for a in (0, 60):
        f, L, (Ms, Ks, Gs, Hs) = measured[a]
        lam, phi = sl.eigh(Ks, Ms)
        R = phi[:, :7]                                   # rigid and spin modes, M-orthonormal
        Pr = np.eye(len(lam)) - R @ R.T @ Ms             # removes them from a displacement
        Kp = np.linalg.pinv(Ks, rcond=1e-10, hermitian=True)
        x = Pr @ Kp @ (Pr.T @ Gs[:, 0])
        direct = []
        for k in range(10):
            direct.append(float(Hs[0] @ x))
            x = Pr @ Kp @ (Pr.T @ (Ms @ x))
        # both routes lose digits on the lowest mode (eigenvalues over 1e9; L^9 goes as its lambda^-10): measured
        # up to 6e-5 of the cancellation-free scale, far inside the fit's 5 % targets
        assert np.all(np.abs(np.array(direct) - L) <= 1e-4 * scale), (a, direct, L)


@pytest.mark.parametrize("angle, paper", [(0, SYSTEM_0), (60, SYSTEM_60)])
def test_frequencies_where_the_fit_says_met(measured, achieved, angle, paper):
    f = measured[angle][0]
    dev = f / np.array(paper) - 1
    met = np.array(achieved[f"frequency_{angle}_met"])
    assert np.all(np.abs(dev[met]) <= FREQ_TOL), np.round(100 * dev, 3)
    # and fit.json's account of the rest is true (a missed entry is missed, by the deviation it states)
    assert np.all(np.abs(dev[~met]) > FREQ_TOL)
    np.testing.assert_allclose(dev, achieved[f"frequency_{angle}_deviation"], atol=1e-6)


def test_moments_where_the_fit_says_met(measured, achieved):
    L = np.array([measured[a][1] for a in ANGLES]).T
    met = np.array(achieved["moments_met"])
    scale = np.max([moment_scale(*measured[a][2]) for a in ANGLES], axis=0)
    ours = np.array([[moment_met(L[k, j], PAPER_L[k, j], HALF_DIGIT[k, j], ROUNDOFF * scale[k])
                      for j in range(len(ANGLES))] for k in range(10)], dtype=object)
    decided = np.array([[v is not None for v in row] for row in ours])
    assert decided.sum() >= 55                   # the undecidable ones are few (round-off at a threshold)
    off = np.argwhere(decided & (ours != met))
    assert not len(off), [(k, ANGLES[j], L[k, j], np.array(achieved["moments"])[k, j], PAPER_L[k, j]) for k, j in off]
    # both solve a flexibility form (fit.py with its own shift): they agree to round-off of each L^k's size over
    # the angles, twice the round-off a decision above allows (the two are computed on different machines: up to
    # 1.07e-5 of the size measured between fit_physical.json's record and an AMD EPYC machine, L^1..L^3 at 0 deg)
    assert np.all(np.abs(L - np.array(achieved["moments"])) <= 2 * ROUNDOFF * scale[:, None])


def test_moments_sign_where_the_paper_prints_a_nonzero(measured, achieved):
    L = np.array([measured[a][1] for a in ANGLES]).T
    nonzero = np.abs(PAPER_L) > HALF_DIGIT
    same = np.sign(L) == np.sign(PAPER_L)
    np.testing.assert_array_equal(same[nonzero], np.array(achieved["moments_sign"])[nonzero])


def test_node_masses_are_physical(galileo, generate, achieved, fit_file):
    """Every lumped mass and inertia of the model within PHYS_BAND of the layout its file names (generate.py's
    tables times the file's layout factors: README.md "Mass layout"), read off the written mass matrices; and that
    layout a spacecraft's: node masses of 5 kg to 2 t, inertias of 1 kg m^2 to 20000 kg m^2."""
    with open(fit_file) as f:
        factors = json.load(f).get("layout_log_factors", {})
    layout_M = {}
    Ms, _, Mr, _ = generate.fitted_masses([factors.get(name, 0.0) for _, _, name in generate.MASS_PARAMETERS])
    layout_M["stator"], layout_M["rotor"] = Ms.diagonal(), Mr.diagonal()
    for body in galileo.bodies:
        d, ref_d = body.M.diagonal(), layout_M[body.name]
        assert np.all(d / ref_d <= PHYS_BAND * (1 + 1e-12)) and np.all(ref_d / d <= PHYS_BAND * (1 + 1e-12)), \
            (body.name, d / ref_d)
        for node, first in body.first_dof.items():
            assert 5.0 <= ref_d[first] <= 2000.0, (body.name, node, ref_d[first])
            if body.ndof[node] == 6:
                assert np.all((1.0 <= ref_d[first + 3:first + 6]) & (ref_d[first + 3:first + 6] <= 2e4)), (body.name, node)
        total = sum(d[body.first_dof[n]] for n in body.ndof)
        assert total == pytest.approx(achieved["masses_kg"][body.name], rel=1e-9)


def test_report_table5_says_row_by_row_where_it_matches():
    """The report's Table P5 verdicts follow the numbers: the paper's own moments match everywhere; one entry 10 %
    off, one of the other sign and one printed 0 that is not are named in their rows."""
    sys.path.insert(0, os.path.join(ROOT, "python"))
    from kryflex.report.paper import _table5
    labels = [str(a) for a in ANGLES]
    block = {"lee": {"angles": labels, "moment_scales": SCALE, "moments": TABLE5},
             "outputs": ["y"], "inputs": ["u"],
             "moments": {lab: [[[PAPER_L[k, j]]] for k in range(10)] for j, lab in enumerate(labels)}}
    same = "\n".join(_table5(block))
    assert "60 of 60 entries match" in same and "Differs" not in same
    assert "- L^4: matches at every angle" in same
    block["moments"]["30"][1] = [[PAPER_L[1, 2] * 1.1]]
    block["moments"]["60"][2] = [[-PAPER_L[2, 4]]]
    block["moments"]["0"][5] = [[3 * HALF_DIGIT[5, 0]]]
    other = "\n".join(_table5(block))
    assert "57 of 60 entries match" in other and "**Differs**" in other
    assert "- L^1: differs at 30° (+10.0 %)" in other
    assert "- L^2: differs at 60° (sign)" in other
    assert "- L^5: differs at 0° (≠ 0 (3 half-digits))" in other


# ------------------------------------------------------------------ what Table 1 implies (meshes/galileo/implied.py)

@pytest.fixture(scope="module")
def implied(generate):
    """meshes/galileo/implied.py, with the `generate` and `fit` it imports by name bound to meshes/galileo's (another
    test may have imported meshes/generate.py as `generate`); sys.modules restored after."""
    here = os.path.join(ROOT, "meshes", "galileo")
    saved = {name: sys.modules.pop(name) for name in ("generate", "fit") if name in sys.modules}
    try:
        sys.modules["generate"] = generate
        sys.modules["fit"] = load_module("fit", os.path.join(here, "fit.py"))
        return load_module("galileo_implied", os.path.join(here, "implied.py"))
    finally:
        for name in ("generate", "fit"):
            sys.modules.pop(name, None)
        sys.modules.update(saved)


def _system_at_0(Ms, Ks, Mr, Kr):
    """The bearing at 0 deg: ux uy uz rx ry of stator node 1 (dofs 0-4) tied to the rotor hub's (dofs 0-4)."""
    ns, nr = Ms.shape[0], Mr.shape[0]
    C = np.zeros((5, ns + nr))
    C[:, :5] = np.eye(5)
    C[:, ns:ns + 5] = -np.eye(5)
    P = sl.null_space(C)
    return P.T @ sl.block_diag(Ms, Mr) @ P, P.T @ sl.block_diag(Ks, Kr) @ P


@pytest.mark.parametrize("layout, band", [("stick", 1.0), ("stick", 2.0), ("stick", 5.0), ("bearing-ring", 2.0),
                                         ("light-bearing", 2.0)])
def test_mode_count_bound_holds_on_sampled_models(generate, implied, layout, band):
    """implied.py's bounds (the count of system modes at or below 9.2953 Hz, each mode's floor), checked on models
    the fit could reach: masses and inertias anywhere in the band (the worst corner included), random mode shapes.
    Both steps are measured with a dense eigensolve: the clamped bodies' frequencies are at or above the floors,
    and the system's are at or above the clamped ones, mode by mode (interlacing)."""
    bound, floor_s, floor_r = implied.mode_count_bound(band, layout=layout)
    center = implied.fit.layout_center(layout)
    top = implied.BAND_TOP
    rng = np.random.default_rng(7)
    nm = len(generate.MASS_PARAMETERS)
    # the worst corner: interface nodes (each body's first six dofs) light, the rest heavy
    corner = np.array([-1.0 if dofs[0] < 6 else 1.0 for _, dofs, _ in generate.MASS_PARAMETERS])
    n = nm + generate.n_rotation(12) + generate.n_rotation(21)
    for trial in range(6):
        p = np.zeros(n)
        p[:nm] = center + np.log(band) * (corner if trial == 0 else rng.uniform(-1, 1, nm))
        p[nm:] = rng.normal(0.0, 1.0, n - nm)
        (Ms, Ks, _), (Mr, Kr, _) = generate.fitted_bodies(p)
        fs = np.sqrt(np.abs(sl.eigh(Ks[6:, 6:], Ms[6:, 6:], eigvals_only=True))) / (2 * np.pi)
        fr = np.sqrt(np.abs(sl.eigh(Kr[6:, 6:], Mr[6:, 6:], eigvals_only=True))) / (2 * np.pi)
        assert np.all(fs >= floor_s * (1 - 1e-9)) and np.all(fr >= floor_r * (1 - 1e-9)), (trial, fs, floor_s)
        M, K = _system_at_0(Ms, Ks, Mr, Kr)
        lam = sl.eigh(K, M, eigvals_only=True)
        f = np.sqrt(np.abs(lam[7:])) / (2 * np.pi)
        clamped = int((fs <= top).sum() + (fr <= top).sum())
        assert (f <= top).sum() <= clamped <= bound, (trial, f[:12], clamped, bound)
        # each mode: the j-th flexible system frequency at or above the j-th clamped one, so the j-th floor
        assert np.all(f >= np.sort(np.r_[fs, fr]) * (1 - 1e-9)), trial
        assert np.all(f >= implied.frequency_floors(band, layout) * (1 - 1e-9)), trial


def test_table1_needs_a_light_bearing_node(implied):
    """Table 1's system column has ten flexible modes at or below 9.2953 Hz; within the physical band around the
    stick layout (a 420 kg bearing node) the bound allows fewer, so no choice of mode shapes meets it there, and
    the floors keep at least four modes of Tables 1 and 4 outside 0.5 %; around a 60 kg bearing node one mode
    stays out; around a 10 kg one the bound excludes nothing (README: what Table 1 implies)."""
    assert implied.mode_count_bound(PHYS_BAND)[0] < len([f for f in SYSTEM_0 if f <= implied.BAND_TOP])
    for paper in (SYSTEM_0, SYSTEM_60):
        assert (implied.least_deviation(PHYS_BAND, paper) > FREQ_TOL).sum() >= 4
    assert implied.mode_count_bound(implied.least_band())[0] >= 10 > implied.mode_count_bound(
        0.99 * implied.least_band())[0]
    # a 60 kg bearing assembly at the bearing node: still at least one mode of Table 1 outside 0.5 %
    assert (implied.least_deviation(PHYS_BAND, SYSTEM_0, "bearing-ring") > FREQ_TOL).sum() >= 1
    # a 10 kg bearing race and housing: the bound no longer excludes Table 1, even at the layout itself
    assert implied.mode_count_bound(1.0, layout="light-bearing")[0] >= 10
    assert np.all(implied.least_deviation(1.0, SYSTEM_0, "light-bearing") <= 0)


def test_physical_fits_stay_above_the_floors(measured, implied, fit_file):
    """The physical fits' system frequencies, at both angles, at or above implied.py's floors for their band."""
    with open(fit_file) as f:
        fit = json.load(f)
    floors = implied.frequency_floors(fit["mass_band"], fit.get("layout", "stick"))
    for a in (0, 60):
        assert np.all(measured[a][0] >= floors * (1 - 1e-9)), (a, measured[a][0], floors)


# ------------------------------------------------------------------ the trace bound (meshes/galileo/sumrule.py)

@pytest.fixture(scope="module")
def sumrule(generate, implied):
    """meshes/galileo/sumrule.py, bound to meshes/galileo's generate and fit (as implied)."""
    here = os.path.join(ROOT, "meshes", "galileo")
    saved = {name: sys.modules.pop(name) for name in ("generate", "fit") if name in sys.modules}
    try:
        sys.modules["generate"], sys.modules["fit"] = generate, implied.fit
        return load_module("galileo_sumrule", os.path.join(here, "sumrule.py"))
    finally:
        for name in ("generate", "fit"):
            sys.modules.pop(name, None)
        sys.modules.update(saved)


def _system_at(alpha, Ms, Ks, Mr, Kr):
    """The bearing at alpha, written here: the hub's ux uy uz and rx ry, turned by alpha about z, equal the stator
    node 1's; the system's (M, K) on the null space of those 5 rows."""
    ns, nr = Ms.shape[0], Mr.shape[0]
    c, s = np.cos(np.radians(alpha)), np.sin(np.radians(alpha))
    R = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    C = np.zeros((5, ns + nr))
    C[:3, :3], C[:3, ns:ns + 3] = np.eye(3), -R
    C[3:, 3:5], C[3:, ns + 3:ns + 6] = np.eye(2), -R[:2]
    P = sl.null_space(C)
    return P.T @ sl.block_diag(Ms, Mr) @ P, P.T @ sl.block_diag(Ks, Kr) @ P


def _sampled(generate, center, band, rng, corner=None):
    nm = len(generate.MASS_PARAMETERS)
    n = nm + generate.n_rotation(12) + generate.n_rotation(21)
    p = np.zeros(n)
    p[:nm] = center + np.log(band) * (corner if corner is not None else rng.uniform(-1, 1, nm))
    p[nm:] = rng.normal(0.0, 1.0, n - nm)
    return p


@pytest.mark.parametrize("layout, band", [("stick", 2.0), ("bearing-ring", 2.0), ("light-bearing", 2.0),
                                         ("mid-bearing", 2.0), ("light-bearing", 50.0)])
def test_trace_bound_holds_on_sampled_models(generate, sumrule, layout, band):
    """The deficit D (Table 1's component eigenvalues' sum less the system's) measured by a dense eigensolve of the
    system assembled here equals sumrule's trace formula, and stays under the bound for its masses (any mode
    shapes) and under the box bound of the band, at 0, 37 and 60 deg; masses anywhere in the band, both bodies'
    interface corners included, random mode shapes."""
    rng = np.random.default_rng(11)
    center = sumrule.fit.layout_center(layout)
    iface = np.array([1.0 if name in sumrule.INTERFACE["rotor"] else -1.0 if name in sumrule.INTERFACE["stator"]
                      else 0.0 for _, _, name in generate.MASS_PARAMETERS])
    ls, lr = sumrule.component_lambdas()
    for trial in range(6):
        corner = (iface, -iface)[trial] if trial < 2 else None
        p = _sampled(generate, center, band, rng, corner)
        bodies = generate.fitted_bodies(p)
        (Ms, Ks, _), (Mr, Kr, _) = bodies
        comp = np.r_[sl.eigh(Ks, Ms, eigvals_only=True), sl.eigh(Kr, Mr, eigvals_only=True)].sum()
        assert comp == pytest.approx(ls.sum() + lr.sum(), rel=1e-9)
        for alpha in (0.0, 37.0, 60.0):
            lam = sl.eigh(*_system_at(alpha, Ms, Ks, Mr, Kr)[::-1], eigvals_only=True)
            D = comp - lam.sum()
            assert sumrule.deficit(alpha, bodies) == pytest.approx(D, rel=1e-7, abs=1e-9 * comp)
            tight = sumrule.masses_bound(alpha, p[:len(center)])
            assert D <= tight * (1 + 1e-9) + 1e-9 * comp, (trial, alpha, D, tight)
            assert tight <= sumrule.masses_bound(alpha, p[:len(center)], rigid=False) * (1 + 1e-12)
            assert tight <= sumrule.box_bound(alpha, layout, band) * (1 + 1e-9), (trial, alpha)


def test_interlacing_on_sampled_models(generate, sumrule):
    """The model-independent interlacing sumrule checks the paper's tables with, measured on random models: each
    flexible system frequency between the components' (k-5)-th and k-th, and the systems at 0 and 60 deg within
    four modes of each other."""
    rng = np.random.default_rng(5)
    for trial in range(4):
        p = _sampled(generate, sumrule.fit.layout_center("light-bearing"), 5.0, rng)
        (Ms, Ks, _), (Mr, Kr, _) = generate.fitted_bodies(p)
        comp = np.sort(np.r_[sl.eigh(Ks, Ms, eigvals_only=True), sl.eigh(Kr, Mr, eigvals_only=True)])
        lam = {a: sl.eigh(*_system_at(a, Ms, Ks, Mr, Kr)[::-1], eigvals_only=True) for a in (0.0, 60.0)}
        tol = 1e-9 * comp[-1]
        for a in lam:
            assert np.all(comp[:28] <= lam[a] + tol) and np.all(lam[a] <= comp[5:] + tol), (trial, a)
        assert np.all(lam[60.0][:-4] <= lam[0.0][4:] + tol) and np.all(lam[0.0][:-4] <= lam[60.0][4:] + tol)


def test_paper_tables_pass_the_interlacing(sumrule):
    """Tables 1 and 4 against each other and the components: no model-independent check fails."""
    rows = sumrule.interlacing()
    assert len(rows) == 2 * 21 + 2 * 17 and all(r[-1] for r in rows)


def test_table1_needs_the_bearing_node_heavy_enough(sumrule, implied):
    """The trace bound excludes the light-bearing layout within the physical band (at least 4 % off somewhere,
    at 0 and 60 deg), not the stick or bearing-ring ones (whose clamped floors exclude them); mid-bearing passes
    both bounds."""
    for alpha in (0.0, 60.0):
        assert sumrule.least_deviation(alpha, sumrule.box_bound(alpha, "light-bearing", PHYS_BAND)) > 0.04
        for layout in ("stick", "bearing-ring", "mid-bearing"):
            assert sumrule.least_deviation(alpha, sumrule.box_bound(alpha, layout, PHYS_BAND)) == 0
    assert np.all(implied.least_deviation(PHYS_BAND, SYSTEM_0, "mid-bearing") <= 0)
    assert np.all(implied.least_deviation(PHYS_BAND, SYSTEM_60, "mid-bearing") <= 0)
    band = sumrule.least_band(0.0, "light-bearing")
    assert sumrule.box_bound(0.0, "light-bearing", band) >= sumrule.paper_deficit(0.0) > sumrule.box_bound(
        0.0, "light-bearing", 0.99 * band)


def test_physical_fits_respect_the_trace_bound(measured, sumrule, topmodes, fit_file):
    """A light-bearing fit's frequencies cannot all be within the trace bound's least deviation of the paper's,
    and stay at or above the rotor-mode floors of its band: measured on the fit's model at 0 and 60 deg."""
    with open(fit_file) as f:
        fit = json.load(f)
    for a, paper in ((0, SYSTEM_0), (60, SYSTEM_60)):
        floors = topmodes.floors(topmodes.box_tau(float(a), fit["layout"], fit["mass_band"]))
        assert np.all(measured[a][0] >= floors * (1 - 1e-9)), a
        least = sumrule.least_deviation(float(a), sumrule.box_bound(float(a), fit["layout"], fit["mass_band"]))
        assert np.abs(measured[a][0] / np.array(paper) - 1).max() >= least * (1 - 1e-6), a


# ------------------------------------------------------------------ the report's account (meshes/galileo/tables.py)

@pytest.fixture(scope="module")
def topmodes(generate, implied):
    """meshes/galileo/topmodes.py, bound to meshes/galileo's generate and fit (as implied)."""
    here = os.path.join(ROOT, "meshes", "galileo")
    saved = {name: sys.modules.pop(name) for name in ("generate", "fit") if name in sys.modules}
    try:
        sys.modules["generate"], sys.modules["fit"] = generate, implied.fit
        return load_module("galileo_topmodes", os.path.join(here, "topmodes.py"))
    finally:
        for name in ("generate", "fit"):
            sys.modules.pop(name, None)
        sys.modules.update(saved)


@pytest.mark.parametrize("layout, band", [("stick", 2.0), ("bearing-ring", 2.0), ("light-bearing", 2.0),
                                         ("mid-bearing", 2.0), ("light-bearing", 50.0)])
def test_rotor_mode_floors_hold_on_sampled_models(generate, topmodes, layout, band):
    """The system's j-th highest frequency (dense eigensolve of the system assembled here) is at least the rotor's
    j-th highest over sqrt(1 + tau), at 0, 37 and 60 deg, tau at its masses at most the box's; masses anywhere in
    the band (the bearing-heavy, hub-light corner included), random mode shapes."""
    rng = np.random.default_rng(13)
    center = topmodes.fit.layout_center(layout)
    corner = np.array([1.0 if name in topmodes.BEARING else -1.0 if name in topmodes.HUB else 0.0
                       for _, _, name in generate.MASS_PARAMETERS])
    for trial in range(5):
        p = _sampled(generate, center, band, rng, corner if trial == 0 else None)
        (Ms, Ks, _), (Mr, Kr, _) = generate.fitted_bodies(p)
        fr = np.sort(np.sqrt(np.abs(sl.eigh(Kr, Mr, eigvals_only=True))) / (2 * np.pi))[::-1]
        for alpha in (0.0, 37.0, 60.0):
            t = topmodes.tau(alpha, Ms, Mr)
            assert t <= topmodes.box_tau(alpha, layout, band) * (1 + 1e-9), (trial, alpha)
            lam = sl.eigh(*_system_at(alpha, Ms, Ks, Mr, Kr)[::-1], eigvals_only=True)
            f = np.sort(np.sqrt(np.abs(lam)) / (2 * np.pi))[::-1]
            assert np.all(f[:15] >= fr[:15] / np.sqrt(1 + t) * (1 - 1e-9)), (trial, alpha, f[:4], fr[:4], t)
            flex = np.sort(f[:21])
            assert np.all(flex >= topmodes.floors(t) * (1 - 1e-9)), (trial, alpha)


def test_table1_needs_a_bearing_node_as_heavy_as_the_hub(topmodes):
    """Table 1's mode 25 (712.65 Hz) has the rotor's 994.7 Hz pair above it: within 0.5 % it needs tau >= 0.93,
    which no layout but the stick one reaches within the band; the others keep modes 25 and 28 out."""
    assert topmodes.tau_needed(0.0) > 0.9
    for layout in ("bearing-ring", "light-bearing", "mid-bearing"):
        dev = topmodes.least_deviation(0.0, topmodes.box_tau(0.0, layout, PHYS_BAND))
        assert dev[25 - 8] > 0.2 and dev[28 - 8] > FREQ_TOL, layout
    assert topmodes.box_tau(0.0, "stick", 1.0) > topmodes.tau_needed(0.0)


def _load_bound(script, **modules):
    """A meshes/galileo script with the modules it imports by name bound to the given ones; sys.modules restored."""
    saved = {name: sys.modules.pop(name) for name in modules if name in sys.modules}
    try:
        sys.modules.update(modules)
        return load_module("galileo_" + script, os.path.join(ROOT, "meshes", "galileo", script + ".py"))
    finally:
        for name in modules:
            sys.modules.pop(name, None)
        sys.modules.update(saved)


@pytest.fixture(scope="module")
def family(generate, implied, sumrule, topmodes):
    return _load_bound("family", generate=generate, fit=implied.fit, implied=implied, sumrule=sumrule,
                       topmodes=topmodes)


def test_family_with_a_bearing_assembly_stays_off(family, implied, sumrule, topmodes):
    """Every layout of family.py's grid whose bearing node is no wider than its radius of gyration keeps some mode
    of Tables 1 and 4 more than 0.5 % off; a cell is the largest of the three bounds, computed again here."""
    for m in family.MASSES:
        for J in family.INERTIAS:
            dev, _ = family.least_deviation(m, J)
            if np.sqrt(J / m) <= family.R_GYRATION:
                assert dev > FREQ_TOL, (m, J)
    implied.fit.LAYOUTS["probe"] = family.layout(80.0, 1.0)
    try:
        again = max(max(np.max(implied.least_deviation(PHYS_BAND, paper, "probe")),
                        np.max(topmodes.least_deviation(a, topmodes.box_tau(a, "probe", PHYS_BAND))),
                        sumrule.least_deviation_above(a, sumrule.box_bound(a, "probe", PHYS_BAND)))
                    for a, paper in ((0.0, SYSTEM_0), (60.0, SYSTEM_60)))
    finally:
        del implied.fit.LAYOUTS["probe"]
    assert family.least_deviation(80.0, 1.0)[0] == pytest.approx(again, rel=1e-12)


@pytest.fixture(scope="module")
def tables(generate, implied, sumrule, topmodes, family, envelope):
    """meshes/galileo/tables.py, bound to meshes/galileo's generate, fit and the bound scripts."""
    return _load_bound("tables", generate=generate, fit=implied.fit, implied=implied, sumrule=sumrule,
                       topmodes=topmodes, family=family, envelope=envelope)


@pytest.fixture(scope="module")
def account(tables):
    """tables.py's account, computed once here (as plain JSON)."""
    return json.loads(json.dumps(tables.account()))


def test_tables_bounds_file_is_what_the_scripts_compute(tables, account):
    """tables_bounds.json (committed, read by the report) is what tables.py computes now."""
    with open(tables.OUT) as f:
        committed = json.load(f)
    assert _close(committed, account)


def _close(a, b):
    if isinstance(a, dict):
        return a.keys() == b.keys() and all(_close(a[k], b[k]) for k in a)
    if isinstance(a, list):
        return len(a) == len(b) and all(_close(x, y) for x, y in zip(a, b))
    if isinstance(a, float):
        return a == pytest.approx(b, rel=1e-7, abs=1e-12)
    return a == b


@pytest.mark.parametrize("angle, paper", [(0, SYSTEM_0), (60, SYSTEM_60)])
def test_table5_residues_meet_the_column(tables, angle, paper):
    """The linear program's residues, summed here as L^k = sum r_i / lambda_i^(k+1) at the paper's frequencies,
    meet every entry of Table 5's column (the LP's least sum is attained), so the frequencies alone do not
    exclude Table 5."""
    least, r = tables.least_residue_sum(float(angle))
    lam = (2 * np.pi * np.array(paper)) ** 2
    j = ANGLES.index(angle)
    assert np.abs(r).sum() == pytest.approx(least, rel=1e-6)
    for k in range(10):
        L = np.sum(r / lam ** (k + 1))
        paper_l, half = PAPER_L[k, j], HALF_DIGIT[k, j]
        # the LP's optimum lies on its constraints: met up to its feasibility tolerance (1e-7 of the entry)
        if abs(paper_l) <= half:
            assert abs(L) <= half * (1 + 1e-7), (k, L)
        else:
            assert np.sign(L) == np.sign(paper_l) and abs(L / paper_l - 1) <= MOMENT_TOL + 1e-7, (k, L)


def test_residue_cap_holds_on_sampled_models(generate, tables):
    """sum_i |r_i| over the system's flexible modes (dense eigensolve, input and output written here) is at most
    sqrt(h^T M^-1 h g^T M^-1 g), and tables.residue_cap is at most that for every mass in the band."""
    rng = np.random.default_rng(3)
    for layout in ("stick", "light-bearing"):
        cap = tables.residue_cap(layout, PHYS_BAND)
        for trial in range(3):
            p = _sampled(generate, tables.fit.layout_center(layout), PHYS_BAND, rng)
            (Ms, Ks, _), (Mr, Kr, _) = generate.fitted_bodies(p)
            ns = Ms.shape[0]
            h, gin = np.zeros(ns + Mr.shape[0]), np.zeros(ns + Mr.shape[0])
            h[10], gin[5], gin[ns + 5] = 1.0, 1.0, -1.0
            for alpha in (0.0, 60.0):
                M, K = _system_at(alpha, Ms, Ks, Mr, Kr)
                c, s = np.cos(np.radians(alpha)), np.sin(np.radians(alpha))
                R = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
                C = np.zeros((5, ns + Mr.shape[0]))
                C[:3, :3], C[:3, ns:ns + 3] = np.eye(3), -R
                C[3:, 3:5], C[3:, ns + 3:ns + 6] = np.eye(2), -R[:2]
                P = sl.null_space(C)
                lam, X = sl.eigh(K, M)
                U = P @ X[:, 7:]
                total = np.abs((h @ U) * (gin @ U)).sum()
                Minv = np.diag(1.0 / np.r_[np.diag(Ms), np.diag(Mr)])
                own = np.sqrt((h @ Minv @ h) * (gin @ Minv @ gin))
                assert total <= own * (1 + 1e-9) and cap <= own * (1 + 1e-12), (layout, trial, alpha)


def test_report_table7_names_each_entrys_bound(account, implied, sumrule, topmodes, family, envelope):
    """The report's Table P7, on the account tables.py computes: a mode the model misses is marked with what the
    bounds say at its own masses; each layout's cell names the larger floor where implied.py's or topmodes.py's
    is more than 0.5 % above the paper (its figure), ‡ on modes 18-28 where the trace bound excludes them, open
    elsewhere."""
    sys.path.insert(0, os.path.join(ROOT, "python"))
    from kryflex.paper import LEE
    from kryflex.report.paper import _allowed
    off60 = list(SYSTEM_60)
    off60[10] *= 0.7                                   # mode 18 at 60 deg 30 % low
    block = {"lee": LEE, "rigid_modes": 7, "full_hz": {"0": list(SYSTEM_0), "60": off60},
             "bounds": account}
    text = "\n".join(_allowed(block))
    rows = {int(line.split("|")[1]): [c.strip() for c in line.split("|")[2:-1]]
            for line in text.splitlines() if line.startswith("| ") and line.split("|")[1].strip().isdigit()}
    layouts = sorted(block["bounds"]["layouts"])
    assert sorted(rows) == list(range(8, 29)) and all(rows[m][1] == "met" for m in rows)
    assert rows[18][3] == "-30.0 % (open)" and all(rows[m][3] == "met" for m in rows if m != 18)
    trace = {name: sumrule.least_deviation_above(0.0, sumrule.box_bound(0.0, name, PHYS_BAND)) > FREQ_TOL
             for name in layouts}
    for col, name in enumerate(layouts, start=4):
        clamped = np.maximum(implied.least_deviation(PHYS_BAND, SYSTEM_0, name), 0.0)
        rotor = topmodes.least_deviation(0.0, topmodes.box_tau(0.0, name, PHYS_BAND))
        dev0 = np.maximum(clamped, rotor)
        for m in rows:
            cell = rows[m][col].split(" / ")[0]
            if dev0[m - 8] > FREQ_TOL:
                which = "clamped" if clamped[m - 8] >= rotor[m - 8] else "rotor modes"
                assert cell.startswith(f"≥ +{100 * dev0[m - 8]:.1f} % ({which})"), (name, m, cell)
            assert cell.endswith("‡") == (trace[name] and m >= 18), (name, m, cell)
            assert (cell == "open") == (dev0[m - 8] <= FREQ_TOL and not cell.endswith("‡")), (name, m, cell)
    assert trace["light-bearing"] and not trace["stick"] and "‡ light-bearing: modes 18-28" in text
    # a layout is excluded when some entry is (a floor or the trace bound, at either angle), computed here again
    out = [name for name in layouts
           if max(max(np.max(implied.least_deviation(PHYS_BAND, paper, name)),
                      np.max(topmodes.least_deviation(a, topmodes.box_tau(a, name, PHYS_BAND))),
                      sumrule.least_deviation_above(a, sumrule.box_bound(a, name, PHYS_BAND)))
                  for a, paper in ((0.0, SYSTEM_0), (60.0, SYSTEM_60))) > FREQ_TOL]
    assert set(out) == {"stick", "bearing-ring", "light-bearing", "mid-bearing"}
    assert (f"{', '.join(out)} of the {len(layouts)} layouts; open: "
            + ", ".join(n for n in layouts if n not in out) + ".") in text
    assert "no bound excludes Table 5 for any layout" in text
    # the family's closest layouts, as the account has them and as family.py computes the cell again
    for hub, c in account["family"]["hub_scales"].items():
        ring = c["closest_ring"]
        assert f"with the hub at {hub}x the layout's, the closest node no wider than 2 m keeps a mode " \
               f"{100 * ring['least_deviation']:.1f} % ({ring['mass_kg']:g} kg" in text
        assert family.least_deviation(ring["mass_kg"], ring["inertia_kg_m2"], float(hub))[0] == pytest.approx(
            ring["least_deviation"], rel=1e-12, abs=1e-15)
    assert account["family"]["hub_scales"]["1"]["closest_ring"]["least_deviation"] > FREQ_TOL
    # the envelope: its column per mode (from the floors at the envelope's corners, computed again here), its
    # proved least deviation, what lies outside it, and Table 5 against its cap
    env = account["envelope"]
    box = envelope.envelope_box()
    again = envelope.per_mode(box[0], box[1])
    for m in rows:
        cells = [f"≥ +{100 * again[a][m - 8][0]:.1f} % ({again[a][m - 8][1]})" if again[a][m - 8][0] > FREQ_TOL
                 else "with the others" for a in ("0", "60")]
        assert rows[m][-1] == (cells[0] if cells[0] == cells[1] else " / ".join(cells)), m
    assert f"keeps some entry of Tables 1 and 4 at least {100 * env['rows'][0]['proved']:.2f} % off" in text
    assert "Outside the envelope: light-hub (hub mass 225 outside 600-1800)" in text
    assert "Outside the envelope: committed fit" in text
    assert env["table5"]["residue_cap"] == pytest.approx(envelope.residue_cap(), rel=1e-12)
    assert not any(env["table5"]["excluded"].values()) and "So Table 5 is excluded by nothing alone" in text


# ---------------------------------------------------------------- the envelope: a bound over a continuum of masses

@pytest.fixture(scope="module")
def envelope(generate, implied, sumrule, topmodes):
    return _load_bound("envelope", generate=generate, fit=implied.fit, implied=implied, sumrule=sumrule,
                       topmodes=topmodes)


def _named(generate, p):
    return {name: q for (_, _, name), q in zip(generate.MASS_PARAMETERS, p)}


def _bump(generate, p, names, step):
    """p with the log factors of the named masses raised by step."""
    return np.array([q + (step if name in names else 0.0) for (_, _, name), q in zip(generate.MASS_PARAMETERS, p)])


BEARING = ("bearing node mass", "bearing node Jxx", "bearing node Jyy", "bearing node Jzz")
HUB = ("hub mass", "hub Jxx", "hub Jyy", "hub Jzz")
REST_STATOR = ("point A mass", "point A Jxx", "point A Jyy", "point A Jzz")


def _floors(implied, generate, p):
    Ms, ts, Mr, tr = generate.fitted_masses(p)
    return (implied.clamped_floors(generate.PAPER_STATOR_HZ, implied.clamped_ratios(Ms, ts, 1.0)),
            implied.clamped_floors(generate.PAPER_ROTOR_HZ, implied.clamped_ratios(Mr, tr, 1.0)))


def test_envelope_bounds_move_the_way_the_proof_says(generate, implied, sumrule, topmodes):
    """The monotonicity each cell's claim rests on, on random masses: a heavier interface node raises its body's
    clamped floors, a heavier rest (point A, a tip) lowers them; a heavier bearing node raises tau, a heavier hub
    lowers it; the trace bound's stator term falls with the bearing node and rises with the hub, its rotor term the
    other way round. Each mass is moved alone, by a random factor up to 3."""
    rng = np.random.default_rng(17)
    nm = len(generate.MASS_PARAMETERS)
    tips = tuple(name for _, _, name in generate.MASS_PARAMETERS if name.endswith(" mass")
                 and name not in ("bearing node mass", "point A mass", "hub mass"))
    eps = 1e-9
    for trial in range(6):
        p = rng.uniform(-2.0, 2.0, nm)
        for names in [(n,) for n in BEARING + HUB + REST_STATOR + tips]:
            q = _bump(generate, p, names, rng.uniform(0.05, np.log(3.0)))
            (fs, fr), (fs2, fr2) = _floors(implied, generate, p), _floors(implied, generate, q)
            if names[0] in BEARING:
                assert np.all(fs2 >= fs * (1 - eps)) and np.allclose(fr2, fr), (trial, names)
            elif names[0] in HUB:
                assert np.all(fr2 >= fr * (1 - eps)) and np.allclose(fs2, fs), (trial, names)
            elif names[0] in REST_STATOR:
                assert np.all(fs2 <= fs * (1 + eps)), (trial, names)
            else:
                assert np.all(fr2 <= fr * (1 + eps)), (trial, names)
            for alpha in (0.0, 60.0):
                Ms, _, Mr, _ = generate.fitted_masses(p)
                Ms2, _, Mr2, _ = generate.fitted_masses(q)
                t, t2 = topmodes.tau(alpha, Ms, Mr), topmodes.tau(alpha, Ms2, Mr2)
                s, s2 = sumrule.pair_bound(alpha, q, p), sumrule.pair_bound(alpha, p, p)
                r, r2 = sumrule.pair_bound(alpha, p, q), sumrule.pair_bound(alpha, p, p)
                if names[0] in BEARING:
                    assert t2 >= t * (1 - eps) and s <= s2 * (1 + eps) and r >= r2 * (1 - eps), (trial, names)
                elif names[0] in HUB:
                    assert t2 <= t * (1 + eps) and s >= s2 * (1 - eps) and r <= r2 * (1 + eps), (trial, names)
                else:
                    assert t2 == pytest.approx(t, rel=1e-9) and s == pytest.approx(s2, rel=1e-9), (trial, names)
    # and the bounds' deviations fall as the floors fall and the trace bound rises
    assert topmodes.least_deviation(0.0, 0.1).sum() >= topmodes.least_deviation(0.0, 0.2).sum()
    d = sumrule.paper_deficit(0.0)
    assert sumrule.least_deviation_above(0.0, 0.5 * d) >= sumrule.least_deviation_above(0.0, 0.6 * d)


def _model_in_cell(generate, envelope, lo, hi, rng):
    """Random masses inside the cell [lo, hi] and the envelope (rejection), random mode shapes: the parameter
    vector generate.fitted_bodies takes."""
    nm = len(generate.MASS_PARAMETERS)
    n = nm + generate.n_rotation(12) + generate.n_rotation(21)
    # a cell thin against the envelope can take more than 2,000 draws: the weakest cell after branch and bound,
    # its corners placed by LAPACK's rounding, did on an AMD EPYC machine (the draws are cheap: 1.5 s for the test)
    for _ in range(200000):
        c = dict(zip(envelope.COORDS, np.exp(rng.uniform(lo, hi))))
        for node in ("bearing node", "hub"):
            k0, k1 = envelope.GYRATION[node]
            c[f"{node} Jzz"] = c[f"{node} mass"] * np.exp(rng.uniform(np.log(k0 ** 2), np.log(k1 ** 2)))
        for name, (least, most) in envelope.ENVELOPE.items():
            if name not in c:
                least = least if least is not None else envelope.STICK[name] / 4
                c[name] = np.exp(rng.uniform(np.log(least), np.log(most)))
        if envelope.holds(c)[0]:
            p = np.zeros(n)
            p[:nm] = envelope._params(c)
            p[nm:] = rng.normal(0.0, 1.0, n - nm)
            return p
    raise AssertionError("no model of the envelope found in the cell")


def test_envelope_cell_claims_hold_on_sampled_models(generate, envelope, implied, sumrule, topmodes):
    """A cell's claim (the three bounds at their least favourable corners) holds for every model in it: random
    masses in the cell and the envelope, random mode shapes, the system assembled here and solved densely at 0 and
    60 deg; each bound's floor or trace below the model's, and some mode of Tables 1 and 4 at least the claim off.
    Cells: the weakest after a short branch and bound, and random ones."""
    rng = np.random.default_rng(23)
    proved, _, (lo0, hi0, dev0, _), _, _ = envelope.branch_and_bound(cells=80)
    assert proved == dev0
    box = envelope.envelope_box()
    cells = [(lo0, hi0)]
    while len(cells) < 5:
        a, b = np.sort(rng.uniform(box[0], box[1], (2, 6)), axis=0)
        if envelope.inside(a, b):
            cells.append((a, b))
    paper = {0.0: np.array(SYSTEM_0), 60.0: np.array(SYSTEM_60)}
    for lo, hi in cells:
        dev, _ = envelope.claim(lo, hi)
        corner = envelope.corners(lo, hi)
        fs, fr = _floors(implied, generate, corner["clamped"])
        floors = np.sort(np.r_[fs, fr])
        for trial in range(3):
            p = _model_in_cell(generate, envelope, lo, hi, rng)
            (Ms, Ks, ts), (Mr, Kr, tr) = generate.fitted_bodies(p)
            worst = 0.0
            for alpha in (0.0, 60.0):
                lam = sl.eigh(*_system_at(alpha, Ms, Ks, Mr, Kr)[::-1], eigvals_only=True)
                f = np.sqrt(np.abs(lam[7:])) / (2 * np.pi)
                assert np.all(f >= floors * (1 - 1e-9)), (lo, hi, alpha)
                Mst, _, Mrt, _ = generate.fitted_masses(corner["tau"])
                assert np.all(f >= topmodes.floors(topmodes.tau(alpha, Mst, Mrt)) * (1 - 1e-9)), (lo, hi, alpha)
                D = sumrule.deficit(alpha, ((Ms, Ks, ts), (Mr, Kr, tr)))
                assert D <= sumrule.pair_bound(alpha, corner["trace stator"], corner["trace rotor"]) * (1 + 1e-9)
                worst = max(worst, np.max(np.abs(f / paper[alpha] - 1)))
            assert worst >= dev * (1 - 1e-9), (lo, hi, worst, dev)


def test_envelope_keeps_out_the_open_layouts(generate, envelope):
    """The two layouts the grid left open are outside the envelope: the light hub (225 kg) below the hub's least
    mass, the committed fit's bearing node (8.4 kg, 540-1870 kg m^2) far wider than the spacecraft; the layouts of
    a bearing assembly under a 900 kg hub are inside."""
    light = {name: envelope.STICK[name] * np.exp(q) for name, q in envelope.fit.LAYOUTS["light-hub"].items()}
    ok, why = envelope.holds(light)
    assert not ok and any(w.startswith("hub mass") for w in why)
    fitted = {name: envelope.STICK[name] * np.exp(q) for name, q in
              _named(generate, generate.load_fit()[:len(generate.MASS_PARAMETERS)]).items()}
    ok, why = envelope.holds(fitted)
    assert not ok and any("bearing node Jyy: radius of gyration" in w for w in why)
    for name in ("light-bearing", "bearing-ring", "mid-bearing"):
        values = {n: envelope.STICK[n] * np.exp(q) for n, q in envelope.fit.LAYOUTS[name].items()}
        assert envelope.holds(values)[0], (name, envelope.holds(values)[1])


def test_envelope_file_is_what_the_script_computes(envelope):
    """envelope.json (committed; tables.py and the report read it): its weakest box's claim and its best centre's
    bound computed again here, the proved figure no larger than the best (a proof cannot exceed what the bounds
    reach), the envelope's own figure above 0.5 %, and per mode what the floors force at the envelope's corners.
    The branch and bound itself takes minutes: it is re-run by the slow test below."""
    with open(envelope.OUT) as f:
        acc = json.load(f)
    row = acc["rows"][0]
    assert row["hub_min_kg"] == envelope.HUB_MIN_KG
    lo, hi = (np.log([row["weakest_cell"][n][k] for n in envelope.COORDS]) for k in (0, 1))
    dev, name = envelope.claim(lo, hi)
    assert dev == pytest.approx(row["proved"], rel=1e-9) and name == row["bound"]
    mid = np.log([row["at_best_masses"][n] for n in envelope.COORDS])
    assert envelope.claim(mid, mid)[0] == pytest.approx(row["at_best"], rel=1e-9)
    assert envelope.inside(mid, mid) and row["proved"] <= row["at_best"]
    assert row["proved"] > FREQ_TOL
    box = envelope.envelope_box()
    assert json.loads(json.dumps(envelope.per_mode(box[0], box[1]))) == acc["per_mode"]
    light = {name: envelope.STICK[name] * np.exp(q) for name, q in envelope.fit.LAYOUTS["light-hub"].items()}
    assert acc["outside"]["light-hub"] == envelope.holds(light)[1]


def test_a_lighter_hub_lets_a_point_through(envelope):
    """The exclusion rests on the hub's least mass: with 450 kg allowed, a bearing node of 20.4 kg (Jxx 56, Jyy
    107 kg m^2) under a 450 kg hub of 112.5 kg m^2 is excluded by none of the three bounds; it is outside the
    envelope (hub below 600 kg)."""
    p = np.log([20.4, 56.0, 107.0, 450.0, 112.5, 112.5])
    assert envelope.claim(p, p) == (0.0, "none")
    assert envelope.inside(p, p, hub_min=450.0) and not envelope.inside(p, p)


def test_envelope_refinement_only_tightens(envelope):
    """A box inside another has each bound's weakest corner inside it too, so its claim is at least the larger
    box's: a shorter branch and bound proves no more than the file's (4000 evaluations) and finds no lower centre.
    (The full run takes minutes: meshes/galileo/envelope.py.)"""
    with open(envelope.OUT) as f:
        row = json.load(f)["rows"][0]
    proved, best, (lo, hi, _, _), _, _ = envelope.branch_and_bound(150)
    assert proved <= row["proved"] * (1 + 1e-12) and best >= row["at_best"] * (1 - 1e-12)
    mid = 0.5 * (lo + hi)
    for k in range(6):
        half = hi.copy()
        half[k] = mid[k]
        assert envelope.claim(lo, half)[0] >= envelope.claim(lo, hi)[0] * (1 - 1e-12)
