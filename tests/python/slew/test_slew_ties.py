"""The slewing study on a model of shared directions (-kf_shared_directions true): its bodies' coordinates obey the
model's ties D_s besides the joints' (ReducedModel.ties), and SlewBodies.from_model keeps them, so the time-domain
models have the reassembled model's freedom, not more.

Checked on the solid bus/rotor pair (2,760 dofs, one reduction angle): the null space of the slew bodies' ties at the
reduction angle and at another one gives C's reassembled frequencies (the same as without ties it does not: the
bodies would keep directions the model ties away), and the integrator's states obey D_s (without the ties they
break them by 3e-6 of the state's size; with them 2e-17)."""
import os
import sys

import numpy as np
import pytest
import scipy.linalg as sl

import kryflex

HERE = os.path.dirname(os.path.abspath(__file__))
SUPPORT = os.path.join(os.path.dirname(HERE), "support")
sys.path.insert(0, SUPPORT)
import accuracy_scenes as acc  # noqa: E402

TARGET = 1e-3
ANGLE, OTHER = 0.0, 40.0

pytestmark = pytest.mark.usefixtures("quiet_library")


@pytest.fixture(scope="module")
def tied(tmp_path_factory):
    base = acc.solid_base(str(tmp_path_factory.mktemp("solid")))
    path = acc.write_variant(base, str(tmp_path_factory.mktemp("tied") / "one.yaml"), accuracy=TARGET,
                             angles=[[ANGLE]], band=acc.SOLID_BAND)
    scene = kryflex.load_scene(path)
    model = kryflex.reduce(scene, quiet=True, shared_directions=True).model
    assert model.ties is not None and model.ties.shape[0] > 0
    return scene, model


def _flexible_hz(N, M, K, nrigid):
    lam = sl.eigh(N.T @ K @ N, N.T @ M @ N, eigvals_only=True)
    return np.sqrt(np.maximum(lam[nrigid:], 0.0)) / (2 * np.pi)


def test_slew_bodies_tie_the_shared_directions(tied):
    from kryflex.slew.bodies import SlewBodies
    _, model = tied
    red = SlewBodies.from_model(model)
    assert red.nmodel_ties == model.ties.shape[0]
    for angle in (ANGLE, OTHER):
        rs = model.at([angle])
        N = sl.null_space(red.ties(np.radians([angle])))
        assert N.shape[1] == rs.dofs
        f = _flexible_hz(N, red.M.toarray(), red.K.toarray(), model.nrigid)
        assert np.allclose(f, rs.frequencies_hz[:len(f)], rtol=1e-8)
        # the model's ties are rows of D: without them the bodies keep more freedom than the model
        D = red.ties(np.radians([angle]))
        assert np.allclose(D[-model.ties.shape[0]:], model.ties, rtol=0, atol=0)
        joints_only = sl.null_space(D[:-model.ties.shape[0]])
        assert joints_only.shape[1] > rs.dofs
    # the ties do not move a rigid motion: the structure's rigid and mechanism modes are as many as C counts
    assert np.asarray(red.rigid_modes(np.radians([OTHER]))).shape[1] == model.nrigid


def test_integrator_states_obey_the_ties(tied):
    from kryflex.slew.bodies import SlewBodies
    from kryflex.slew.integrator import Integrator
    from kryflex.slew.profiles import Profile
    _, model = tied
    red = SlewBodies.from_model(model)
    profile = Profile("slew", 0.5, [np.radians(30.0)], [np.radians(ANGLE)])
    _, _, _, z = Integrator(red, 0.002, 1e-3).run(profile, 0.5, state=True)
    violation = np.abs(z @ model.ties.T).max() / np.abs(z).max()
    print("largest |D_s z| / |z|: %.2e" % violation)
    assert violation <= 1e-10

