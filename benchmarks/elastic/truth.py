"""The elastic error of kryflex's default run measured independently at any size, with SciPy (not kryflex).

For the solid spacecraft of meshes/solid (generate.py --refine R; 1.55 gives 57,031 dofs after the ties, where a dense
reference is out of reach) and each target: `kryflex reduce` with its default run (accuracy search on, moments auto),
its exit code, reported error (summary.json error_max) and wall time; then the model it wrote (reduced.h5) against
this file's own full-order reference at every angle of interest and every midpoint.

The reference, per configuration (SciPy's SuperLU and ARPACK only):
- the full order after the joint ties (benchmarks/peers/bench.py full_order: sparse M, K, G, H), and the rigid-body
  and mechanism modes Q from geometry (node coordinates and ties, M-orthonormal; exact where an eigensolver's null
  space is not);
- the flexible modes up to --cover times the band's top, by shift-invert Lanczos (scipy eigsh on one SuperLU
  factorization of K + M);
- the exact static residual of the modes not computed: x = K^+ Ge, Ge = G - M Q Q^T G, by fixed-point iteration on
  the same factorization (x <- (K + M)^-1 (Ge + M x), which converges as 1 / (1 + lam_1)), minus the computed modes'
  part sum phi phi^T G / lam;
- T(w) = sum H phi phi^T G / (lam - w^2 + 2 i zeta sqrt(lam) w) + H (x - ...) - H Q Q^T G / w^2, the scene's modal
  damping on every flexible mode (kryflex's damping model for `damping: zeta`);
- validated at --check-points frequencies per configuration in the band, away from resonances, by a direct sparse
  solve: SuperLU of K - w^2 M, with the computed modes' modal damping C = M Phi diag(2 zeta w_k) Phi^T M applied
  exactly by the Woodbury identity (complex), the rigid part as above. The disagreement, relative to each pair's
  elastic peak, is printed; it bounds what the static residual leaves out.

The check grid is the one of tests/python/reducer/test_elastic_accuracy.py: 4x kryflex's log-spaced points plus 29
points over fr (1 + zeta [-2, 2]) across every full-order resonance and every resonance of the reduced model in the
band. The measure: per pair max |T_full - T_red| over the peak of the pair's elastic response (T_full minus the rigid
part), a pair's peak floored at 1e-4 of the largest; the model's error is the largest over pairs and configurations.

    nice -n 10 .venv/bin/python benchmarks/elastic/truth.py --refine 1.55 --targets 0.05 1e-2 1e-3 --out DIR

Each process stays under about 2 GB at 57k dofs (one SuperLU factor of 53M entries at a time). kryflex runs one at a
time, as a subprocess.
"""
import argparse
import json
import os
import resource
import subprocess
import sys
import time

import numpy as np
import yaml

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(ROOT, "tests", "python", "support"))
sys.path.insert(0, os.path.join(ROOT, "benchmarks", "peers"))
sys.path.insert(0, os.path.join(ROOT, "python"))
import accuracy_scenes as acs  # noqa: E402
import bench as peers  # noqa: E402
import modal_reference as mref  # noqa: E402  (SuperLU, the modes by shift-invert and K^+: shared with the peers' reference)
import reference as ref  # noqa: E402

KRYFLEX = os.path.join(ROOT, "build", "kryflex")


class Reference:
    """The full-order modal data at one configuration: lam, H Phi, Phi^T G of the computed flexible modes, the static
    residual H (K^+ Ge - Phi lam^-1 Phi^T G) and the rigid part's H Q Q^T G."""

    FIELDS = ("lam", "hp", "pg", "residual", "rigid", "zeta", "dofs", "seconds", "check")

    @classmethod
    def cached(cls, path, *args):
        """The reference from path (npz) if there, else computed and saved there."""
        if os.path.exists(path):
            R = cls.__new__(cls)
            with np.load(path) as z:
                for k in cls.FIELDS:
                    setattr(R, k, z[k])
            R.check = [tuple(c) for c in R.check]
            return R
        R = cls(*args)
        np.savez(path + ".tmp.npz", **{k: np.asarray(getattr(R, k)) for k in cls.FIELDS})
        os.replace(path + ".tmp.npz", path)
        return R

    def __init__(self, scene, angle, band, zeta, cover, check_points):
        t0 = time.perf_counter()
        M, K, G, H, Q = peers.full_order(scene, angle)
        lu = mref.factor(K + M)
        lam, Phi = mref.flexible_modes(M, K, Q, lu, cover * band[1], first=40)
        x = mref.pinv(M, Q, lu, G - M @ (Q @ (Q.T @ G)))   # K^+ Ge, Ge = G - M Q Q^T G
        del lu
        self.lam, self.hp, self.pg = lam, H @ Phi, Phi.T @ G
        self.residual = H @ x - (self.hp / lam) @ self.pg
        self.rigid = H @ Q @ (Q.T @ G)
        self.zeta, self.dofs = zeta, M.shape[0]
        self.seconds = time.perf_counter() - t0
        self.check = self.validate(M, K, G, H, Q, Phi, band, check_points)

    @property
    def flexible_hz(self):
        return np.sqrt(self.lam) / (2 * np.pi)

    def frf(self, f_hz, rigid=True):
        w = 2 * np.pi * np.asarray(f_hz, float)
        inv = 1.0 / (self.lam[None] - w[:, None] ** 2 + 2j * self.zeta * np.sqrt(self.lam)[None] * w[:, None])
        T = np.einsum("tn,fn,na->fta", self.hp, inv, self.pg) + self.residual[None]
        return T - self.rigid[None] / (w ** 2)[:, None, None] if rigid else T

    def validate(self, M, K, G, H, Q, Phi, band, npoints):
        """[(f, max over pairs of |T_direct - T| / pair's elastic peak)] at npoints frequencies between resonances."""
        fr = [f for f in self.flexible_hz if band[0] <= f <= band[1]]
        edges = [band[0]] + fr + [band[1]]
        gaps = sorted(zip(edges[1:], edges[:-1]), reverse=True)[:npoints]   # the highest first: the residual's

        Ge, He = G - M @ (Q @ (Q.T @ G)), H - (H @ Q) @ (Q.T @ M)
        U = M @ Phi
        peak = np.abs(self.frf(np.geomspace(band[0], band[1], 400), rigid=False)).max(axis=0)
        peak = np.maximum(peak, acs.PAIR_FLOOR * peak.max())
        out = []
        for hi, lo in sorted(gaps):                                          # error grows as w^2
            f = float(np.sqrt(lo * hi))
            w = 2 * np.pi * f
            lu = mref.factor(K - w ** 2 * M)
            Zb, ZU = lu.solve(np.asarray(Ge)), lu.solve(np.asarray(U))
            d = 2j * self.zeta * np.sqrt(self.lam) * w         # modal damping of the computed modes, exactly
            small = np.diag(1.0 / d) + U.T @ ZU
            x = Zb - ZU @ np.linalg.solve(small, U.T @ Zb)
            del lu
            out.append((f, float((np.abs(He @ x - self.frf([f], rigid=False)[0]) / peak).max())))
        return out


def reduce(scene_path, target, out):
    """kryflex reduce with the default run at target: (exit code, summary or None, wall s, reduced.h5 path). A run
    already in out (run.json beside its summary) is reused."""
    done = os.path.join(out, "run.json")
    if os.path.exists(done):
        with open(done) as f:
            rc, wall = json.load(f)
        with open(os.path.join(out, "summary.json")) as f:
            return rc, json.load(f), wall, os.path.join(out, "reduced.h5")
    with open(scene_path) as f:
        spec = yaml.safe_load(f)
    base = os.path.dirname(os.path.abspath(scene_path))
    for b in spec["bodies"].values():
        for k in ("mass", "stiffness", "nodes"):
            b[k] = os.path.join(base, b[k])
    reduction = dict(spec.get("reduction") or {}, moments="auto", search=True)
    reduction.pop("keep_threshold", None)
    spec.update(accuracy=target, reduction=reduction)
    os.makedirs(out, exist_ok=True)
    path = os.path.join(out, "scene.yaml")
    with open(path, "w") as f:
        yaml.safe_dump(spec, f, sort_keys=False, default_flow_style=None, width=120)
    t0 = time.perf_counter()
    p = subprocess.run([KRYFLEX, "reduce", path, "-o", out, "-kf_quiet"], capture_output=True, text=True)
    wall = time.perf_counter() - t0
    summary = None
    if os.path.exists(os.path.join(out, "summary.json")):
        with open(os.path.join(out, "summary.json")) as f:
            summary = json.load(f)
    if p.returncode not in (0, 6):
        print(p.stdout[-2000:], p.stderr[-2000:])
    elif summary is not None:
        with open(done, "w") as f:
            json.dump([p.returncode, wall], f)
    return p.returncode, summary, wall, os.path.join(out, "reduced.h5")


def measure(model, refs, band, zeta, n_log):
    """[(angle, kind, elastic error)] of a reduced model against the references."""
    rows = []
    for (angle, kind), R in refs.items():
        s = model.at([angle])
        f = acs.check_grid(band, n_log, np.concatenate([R.flexible_hz, s.frequencies_hz]), zeta)
        Tf, Tr = R.frf(f), s.frf(f)
        Tel = Tf + R.rigid[None] / ((2 * np.pi * f) ** 2)[:, None, None]
        peak = np.abs(Tel).max(axis=0)
        e = np.abs(Tf - Tr).max(axis=0) / np.maximum(peak, acs.PAIR_FLOOR * peak.max())
        rows.append((angle, kind, float(e.max())))
    return rows


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--refine", type=float, default=1.55)
    ap.add_argument("--targets", type=float, nargs="+", default=[0.05, 1e-2, 1e-3])
    ap.add_argument("--cover", type=float, default=4.0, help="modes computed up to this times the band's top")
    ap.add_argument("--check-points", type=int, default=1, help="direct solves per configuration")
    ap.add_argument("--out", default=os.path.join(ROOT, "out", "bench-elastic-truth"))
    args = ap.parse_args(argv)
    import kryflex
    folder = os.path.join(args.out, "solid_%g" % args.refine)
    scene_path = os.path.join(folder, "spacecraft.yaml")
    if not os.path.exists(scene_path):
        subprocess.run([sys.executable, os.path.join(ROOT, "meshes", "solid", "generate.py"), "--refine",
                        str(args.refine), "-o", folder], check=True, capture_output=True)
    scene = ref.load_scene(scene_path)
    band, zeta = scene.raw["band"], scene.raw["damping"]
    if not isinstance(zeta, (int, float)):
        raise SystemExit("truth.py: the scene's damping must be one modal ratio (damping: 0.0025), got %r" % zeta)
    print("elastic truth, %s UTC, solid spacecraft --refine %g, 1 rank" % (time.strftime("%Y-%m-%d %H:%M", time.gmtime()),
                                                                         args.refine), flush=True)
    runs = []
    for target in args.targets:       # kryflex first, one run at a time: the references are built afterwards
        rc, summary, wall, h5 = reduce(scene_path, target, os.path.join(args.out, "run_%g_%g" % (args.refine, target)))
        runs.append((target, rc, summary, wall, h5))
        print("kryflex reduce at %g: exit %d, reported %s error %s, %.0f s" % (
            target, rc, (summary or {}).get("accuracy_measure"), (summary or {}).get("error_max"), wall), flush=True)
    refs = {}
    for angle, kind in by_reported(scene, runs):
        cache = os.path.join(args.out, "reference_%g_%g_%g_%d.npz" % (args.refine, angle, args.cover,
                                                                       args.check_points))
        R = Reference.cached(cache, scene, angle, band, float(zeta), args.cover, args.check_points)
        refs[(angle, kind)] = R
        print("reference at %g deg (%s): %d dofs, %d flexible modes up to %.3g Hz (%d in the band), %.0f s, maxrss "
              "%.2f GB; direct check %s" % (angle, kind, R.dofs, R.lam.size, R.flexible_hz[-1],
                                            np.sum(R.flexible_hz <= band[1]), R.seconds,
                                            resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e6,
                                            ", ".join("%.3g Hz %.2e" % tuple(c) for c in R.check)), flush=True)
        table(runs, refs, band, float(zeta), kryflex)


def by_reported(scene, runs):
    """The configurations (angle, kind), those where kryflex reported the largest error relative to its target first:
    a run stopped early has measured the configurations that decide its maximum."""
    worst = {}
    for target, rc, summary, wall, h5 in runs:
        reported = {}
        for label, v in ((summary or {}).get("frf") or {}).items():
            reported[float(label)] = v["frf_error"]
        for m in (summary or {}).get("midpoints") or []:
            reported[float(m["angles_deg"][0])] = m["frf_error"]
        for a, e in reported.items():
            worst[a] = max(worst.get(a, 0.0), e / target)
    order = acs.with_midpoints([[float(a)] for a in scene.raw["angles"]])
    return sorted(((a[0], kind) for a, kind in order), key=lambda c: -worst.get(c[0], 0.0))


def table(runs, refs, band, zeta, kryflex):
    print("\nmeasured at %d configuration(s): %s" % (len(refs), ", ".join("%g" % a for a, _ in refs)))
    print("| target | exit | dofs per body | reported elastic error | measured elastic error | reported / measured "
          "| worst at | kryflex wall s |")
    print("|---|---|---|---|---|---|---|---|")
    for target, rc, summary, wall, h5 in runs:
        if summary is None or not os.path.exists(h5):
            print("| %g | %d | (no model) | | | | | %.0f |" % (target, rc, wall))
            continue
        model = kryflex.ReducedModel.load(h5)
        n_log = max(len(v["freq_hz"]) for v in summary["frf"].values()) if summary.get("frf") else 400
        rows = measure(model, refs, band, zeta, n_log)
        angle, kind, e = max(rows, key=lambda r: r[2])
        rep = float(summary["error_max"])
        print("| %g | %d | %s | %.4g | %.4g | %.3f | %g deg (%s) | %.0f |" % (
            target, rc, " + ".join(str(int(v)) for v in model.sizes), rep, e, rep / e, angle, kind, wall), flush=True)


if __name__ == "__main__":
    main()
