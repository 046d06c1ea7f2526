"""A reduction started from a system assembled before it (KFReducerSetSystem, Reducer.start_from: kryflex reduce hands
it the model check's system at the first configuration). Checked on the solid at refine 0.5 (2,760 dofs), 1 and 2
ranks: the handed system's matrices (M_S, K_S, G, H^T), rigid modes and their products K_S Phi and M_S Phi (which the
model check reads from it) are bit for bit those of a system assembled fresh at the same angles (what the reducer would build), the reduction then assembles one configuration fewer
(PETSc's KFAssemble event), and its model file is the reduction's without the system: every numeric dataset equal
(1 rank; on 2 ranks MUMPS' scheduling makes two runs of the same reduction differ in round-off, so within that).
A system of another scene is refused with a clear error."""
import os
import sys

import pytest

HERE = os.path.dirname(os.path.abspath(__file__))
SUPPORT = os.path.join(os.path.dirname(HERE), "support")
sys.path.insert(0, SUPPORT)
import accuracy_scenes  # noqa: E402
from rank_runs import results_on_ranks  # noqa: E402
from test_mode_count import ENV  # noqa: E402

pytestmark = [pytest.mark.usefixtures("quiet_library")]

SCRIPT = r'''
import json
import h5py
import numpy as np
from mpi4py import MPI
import kryflex
from kryflex import _core
from petsc4py import PETSc

PETSc.Log.begin()
assemble = PETSc.Log.Event("KFAssemble")
comm = MPI.COMM_WORLD
scene = kryflex.load_scene(%(path)r)
first = scene.angles_rad(scene.configurations[0])


def system():
    s = _core.CSystem(scene.cscene)
    s.set_angles(first)
    return s


def local(A):
    if A.getType().endswith("dense"):
        return [A.getDenseArray().copy()]
    ai, aj, av = A.getValuesCSR()
    return [np.asarray(ai).copy(), np.asarray(aj).copy(), np.asarray(av).copy()]


handed, fresh = system(), system()
same = True
for A, B in zip(handed.matrices() + (handed.rigid_modes()[0],), fresh.matrices() + (fresh.rigid_modes()[0],)):
    same &= all(x.shape == y.shape and np.array_equal(x, y) for x, y in zip(local(A), local(B)))
same &= handed.rigid_modes()[1] == fresh.rigid_modes()[1]
same = comm.allreduce(bool(same), op=MPI.LAND)
# the rigid modes' K_S Phi and M_S Phi the C library keeps (the model check reads them): PETSc's products' bits
Ms_, Ks_ = fresh.matrices()[:2]
Phi_ = fresh.rigid_modes()[0]
products = handed.rigid_products()
same_products = all(np.array_equal(local(A)[0], local(B)[0])
                    for A, B in zip(products, (Ks_.matMult(Phi_), Ms_.matMult(Phi_))))
same_products = comm.allreduce(bool(same_products), op=MPI.LAND)
del fresh, Ms_, Ks_, Phi_, products


def reduced(name, start=None):
    r = kryflex.Reducer(scene, quiet=True, verify=False)
    r.start_from(start)
    before = assemble.getPerfInfo()["count"]
    model = r.reduce().model
    count = assemble.getPerfInfo()["count"] - before
    path = "%(folder)s/%%s-%%d.h5" %% (name, comm.size)
    model.save(path)
    return path, count


own, own_count = reduced("own")
given, given_count = reduced("given", handed)
del handed
# the reduction's own round-off from run to run (MUMPS' scheduling on 2 ranks; none on 1)
again = reduced("again")[0] if comm.size > 1 else own


def datasets(path):
    out = {}
    with h5py.File(path, "r") as f:
        f.visititems(lambda k, d: out.__setitem__(k, d[()]) if isinstance(d, h5py.Dataset)
                     and np.asarray(d[()]).dtype.kind in "fiu" else None)
    return out


def rel(a, b):
    return max(float(np.max(np.abs(a[k] - b[k]), initial=0) / max(np.max(np.abs(a[k]), initial=0), 1e-300))
               for k in a)


try:   # a system of another scene: refused
    s2 = kryflex.load_scene(%(path)r)
    foreign = _core.CSystem(s2.cscene)
    foreign.set_angles(first)
    kryflex.Reducer(scene, quiet=True, verify=False).start_from(foreign)
    refused = ""
except _core.Error as e:
    refused = str(e)

if comm.rank == 0:
    a, b, c = datasets(own), datasets(given), datasets(again)
    print("RESULT " + json.dumps(dict(
        same_system=same, same_products=same_products, own_count=own_count, given_count=given_count, keys_equal=sorted(a) == sorted(b),
        numeric=len(a), equal=sum(np.array_equal(a[k], b[k]) for k in a),
        rel_given=rel(a, b) if sorted(a) == sorted(b) else None, rel_again=rel(a, c), refused=refused)))
'''


@pytest.fixture(scope="module")
def solid(tmp_path_factory):
    return accuracy_scenes.solid_base(str(tmp_path_factory.mktemp("solid_handed")))


def test_the_handed_system_is_the_reducers_own(solid, tmp_path):
    one, two = results_on_ranks(SCRIPT % dict(path=solid, folder=str(tmp_path)), tmp_path, ENV)
    for res in (one, two):
        assert res["same_system"] and res["same_products"]
        assert res["own_count"] - res["given_count"] == 1      # the first configuration not assembled again
        assert res["keys_equal"] and res["numeric"] >= 10
        assert "another scene" in res["refused"]
    assert one["equal"] == one["numeric"]                       # bit for bit on 1 rank
    # two runs of the same 2-rank reduction differ by up to 1.6e-11 of a dataset's largest entry (the 2,760-dof solid,
    # kryflex reduce, three runs of main): round-off, not a different system
    assert two["rel_given"] <= max(10 * two["rel_again"], 1e-9)
