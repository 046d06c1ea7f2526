"""The system matrices sum_b P_b^T A_b P_b, written directly by src/assemble/sum.c, against NumPy.

A hand-made chain of three bodies: a root, a child on a revolute joint, and a grandchild fixed to the child's tied
interface node (its interface dofs read through the child's expressions: the root's dofs and the joint's rotation),
with a partly clamped root node.  M_S and K_S must equal the products P_b^T A_b P_b computed densely from kryflex's
own body maps P_b (the maps themselves are checked against the constraint equations in test_assembly.py), at a first
angle (a new matrix) and at a later one (the same pattern refilled, only the rows the angles reach written: bit for
bit a fresh system's, also after the matrices were written into between angles); AIJ and dense body matrices give the same
system; every diagonal entry is stored (a joint's free rotation has no row of its own in any body).
The same checks run on 2 ranks (this file under mpiexec), where each rank writes the diagonal and off-diagonal blocks
of its rows (MatCreateMPIAIJWithSplitArrays) and a later angle refills them through MatSetValues.

    mpiexec -n 2 python tests/python/model/test_system_sum.py aij|dense   (the 2-rank half: prints "sum ok" per rank)
"""
import os
import subprocess
import sys

import numpy as np
import pytest

pytestmark = pytest.mark.fast   # the fast tier (tests/README.md)

HERE = os.path.dirname(os.path.abspath(__file__))
SUPPORT = os.path.join(os.path.dirname(HERE), "support")   # the helpers (tests/python/support)
sys.path.insert(0, SUPPORT)
import run_env  # noqa: E402  (support/run_env.py: the repository's paths, the subprocesses' environment)
ROOT = run_env.ROOT
MPI_ENV = dict(run_env.ENV, PYTHONPATH=run_env.PACKAGE)

NODES = {"root": [1, 2], "child": [1, 2, 3], "grandchild": [1, 2]}


def spd(n, seed):
    rng = np.random.default_rng(seed)
    A = rng.standard_normal((n, n))
    S = A @ A.T + n * np.eye(n)
    S[np.abs(S) < 0.3] = 0.0  # some structural zeros, symmetric
    return S


def chain(dense):
    from kryflex import _core
    from reference import petsc_matrix
    s = _core.CScene()
    mats = {}
    for k, (name, ids) in enumerate(NODES.items()):
        n = 6 * len(ids)
        M, K = spd(n, 10 + k), spd(n, 20 + k)
        mats[name] = (M, K)
        xyz = np.arange(3.0 * len(ids)).reshape(-1, 3) + k
        s.add_body(name, petsc_matrix(M, dense), petsc_matrix(K, dense), ids, xyz, [6] * len(ids))
    s.add_interface(0, "hub", 2)
    s.add_interface(1, "hub", 1)
    s.add_interface(1, "arm", 1)        # the grandchild hangs on the child's tied node
    s.add_interface(2, "arm", 1)
    s.add_joint("spin", "revolute", 0, "hub", 1, "hub", axis=(0.0, 0.6, 0.8))
    s.add_joint("weld", "fixed", 1, "arm", 2, "arm")
    s.add_constraint(0, 1, "123")
    s.set_num_io(1, 1)
    s.add_input_load(0, 0, 2, 0)
    s.add_output_reading(0, 2, 2, 0)
    s.setup()
    return s, mats


def dense_of(A):
    """the whole matrix on every rank (each rank's rows, summed over ranks)"""
    n, m = A.getSize()
    out = np.zeros((n, m))
    r0, r1 = A.getOwnershipRange()
    for i in range(r0, r1):
        cols, vals = A.getRow(i)
        out[i, cols] = vals
    return A.getComm().tompi4py().allreduce(out) if A.getComm().getSize() > 1 else out


def check_sum_equals_dense_products(dense):
    from kryflex import _core
    scene, mats = chain(dense)
    system = _core.CSystem(scene)
    for angle in (0.0, 0.7, 2.9):      # 0: zero coefficients stay in the pattern; later angles refill it
        system.set_angles([angle])
        Ms, Ks, _, _ = system.matrices()
        P = [dense_of(system.body_map(b)) for b in range(3)]
        for S, which in ((Ms, 0), (Ks, 1)):
            ref = sum(P[b].T @ mats[name][which] @ P[b] for b, name in enumerate(NODES))
            got = dense_of(S)
            assert np.linalg.norm(got - ref) <= 1e-14 * np.linalg.norm(ref), (angle, which)
            assert np.allclose(got, got.T, rtol=0, atol=1e-13 * np.abs(ref).max())
            r0, r1 = S.getOwnershipRange()
            for i in range(r0, r1):                          # every diagonal entry stored
                assert i in S.getRow(i)[0], (angle, which, i)
        # the joint's free rotation (the last system dof) reads through both tied nodes
        assert np.count_nonzero(P[1][:, -1]) and np.count_nonzero(P[2][:, -1])
    # a refill writes only the rows the angles reach (src/assemble/sum.c): bit for bit a fresh sum at the same angle,
    # also after something else wrote into the system's matrices (their states make the next refill whole)
    fresh = _core.CSystem(scene)
    for angle, write in ((2.9, False), (0.7, True), (1.3, False)):
        if write:
            Ms, Ks, _, _ = system.matrices()
            Ms.scale(2.0)
            Ks.shift(5.0)
        system.set_angles([angle])
        fresh.set_angles([angle])
        for A, B in zip(system.matrices()[:2], fresh.matrices()[:2]):
            assert np.array_equal(dense_of(A), dense_of(B)), (angle, write)
        fresh = _core.CSystem(scene)


@pytest.mark.parametrize("dense", [False, True], ids=["aij", "dense"])
def test_sum_equals_dense_products(dense):
    check_sum_equals_dense_products(dense)


@pytest.mark.mpi
@pytest.mark.parametrize("dense", [False, True], ids=["aij", "dense"])
def test_sum_equals_dense_products_two_ranks(dense):
    out = subprocess.run(["mpiexec", "-n", "2", sys.executable, os.path.abspath(__file__), "dense" if dense else "aij"],
                         env=MPI_ENV, capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stdout[-2000:] + out.stderr[-3000:]
    assert out.stdout.count("sum ok") == 2, out.stdout   # both ranks checked every angle


def test_aij_and_dense_bodies_give_the_same_system():
    from kryflex import _core
    out = []
    for dense in (False, True):
        scene, _ = chain(dense)
        system = _core.CSystem(scene)
        system.set_angles([1.1])
        out.append([dense_of(A) for A in system.matrices()[:2]])
    for a, b in zip(*out):
        assert np.array_equal(a, b)


if __name__ == "__main__":
    sys.path.insert(0, os.path.join(ROOT, "python"))
    sys.path.insert(0, SUPPORT)
    import petsc4py
    petsc4py.init(sys.argv[:1])
    from petsc4py import PETSc
    try:
        check_sum_equals_dense_products(sys.argv[1] == "dense")
    except AssertionError as e:           # the other rank would wait in the next gather: stop both
        sys.stderr.write("rank %d: %r\n" % (PETSc.COMM_WORLD.getRank(), e))
        sys.stderr.flush()
        PETSc.COMM_WORLD.tompi4py().Abort(1)
    sys.stdout.write("sum ok\n")  # one write per rank: lines stay whole
    sys.stdout.flush()
