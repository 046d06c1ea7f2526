#!/usr/bin/env python3
"""A stress scene's truth at 50 digits (meshes/stress.py; light-mass by default), for the estimator bench.

The pencil of the assembled full order solved by mpmath at 50 digits on the M-orthogonal complement of the geometric
rigid modes (tests/python/support/extended_truth.py), and the elastic measure of tests/python/support/elastic_measure.py
against it. Prints, per line:
  reference  how far the SciPy whole-pencil reference (geometric rigid modes, accuracy_scenes.modal_data) is from it;
  chosen     kryflex's chosen model, estimated (verify false) and measured, at each accuracy: kryflex's error, truth;
  candidate  light-mass only: the single-angle c = 2 model at each alpha_G (the bench's light-mass-1e-4 candidates).
Takes about 2 minutes.

    .venv/bin/python benchmarks/estimator/light_mass_truth.py [--scene light-mass] [--accuracies 1e-3,1e-4,1e-5,1e-6]
"""
import argparse
import os
import subprocess
import sys
import tempfile

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "tests", "python", "support"))
import accuracy_scenes as acc  # noqa: E402
import elastic_measure as em  # noqa: E402
from extended_truth import ExtendedTruth  # noqa: E402
import reference as ref  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scene", default="light-mass", help="a scene of meshes/stress.py")
    ap.add_argument("--accuracies", default="1e-3,1e-4,1e-5,1e-6")
    args = ap.parse_args()
    work = tempfile.mkdtemp()
    subprocess.run([sys.executable, os.path.join(ROOT, "meshes", "stress.py"), "--out", work, "--names", args.scene],
                   check=True, capture_output=True)
    path = os.path.join(work, args.scene, "scene.yaml")
    scene = ref.load_scene(path)
    truth = ExtendedTruth(scene)
    raw = scene.raw
    zeta, band = float(raw["damping"]), raw["band"]
    points = acc.with_midpoints([[float(a)] for a in raw["angles"]])
    for angles, _ in points:
        t = truth.at(angles)
        Ms, Ks, Gs, Hs = ref.assemble(scene, angles)
        d = acc.modal_data(Ms, Ks, Gs, Hs, ref.geometric_rigid_modes(scene, angles))
        f = acc.check_grid(band, 200, t.flexible_hz, zeta)
        Tt = t.frf(f, zeta)
        elastic = np.abs(Tt - em.rigid_response(t, f)).max(axis=0)     # the elastic measure's denominator per pair
        floor = np.maximum(np.maximum(elastic, em.PAIR_FLOOR * elastic.max()), em.ELASTIC_FLOOR * np.abs(Tt).max(axis=0))
        print("reference %5.1f deg: SciPy whole pencil, geometric rigid modes, %.3g of the elastic floor off"
              % (angles[0], (np.abs(d.frf(f, zeta) - Tt).max(axis=0) / floor).max()), flush=True)
    import kryflex

    def true_error(model):
        return max(em.errors_at(model, truth, a, band, zeta)[0] for a, _ in points)

    for a in [float(x) for x in args.accuracies.split(",")]:
        for verify in (False, True):
            red = kryflex.reduce(kryflex.load_scene(path), quiet=True, accuracy=a, verify=verify)
            v, t = red.summary.verdict, true_error(red.model)
            print("chosen accuracy %g %s: system dofs %d, kryflex %.4g (%s), truth %.4g%s" % (
                a, "measured" if verify else "estimated", max(int(red.model.at(c).dofs) for c, _ in points),
                v.error_max, "met" if v.target_met else "missed", t,
                " FALSE PASS" if v.target_met and t > a else (" false fail" if not v.target_met and t <= a else "")),
                flush=True)
    for ag in (0, 15, 30, 45, 60, 72) if args.scene == "light-mass" else ():
        red = kryflex.reduce(kryflex.load_scene(path), quiet=True, accuracy=1e-4, verify=False, search=False,
                             moments=2, method="single-angle", reduction_angle=str(ag), compress=False)
        print("candidate single-angle c = 2, alpha_G %d deg: system dofs %d, truth %.4g"
              % (ag, max(int(red.model.at(c).dofs) for c, _ in points), true_error(red.model)), flush=True)


if __name__ == "__main__":
    main()
