"""kryflex runs on the peers bench's scene and damping (bench.py's kryflex_spec), measured by bench.py's independent
elastic error, with each body's reduced size. --srcf F sets KF_SRCF, read only by the temporary patch
source_factor.patch (the search run at accuracy x F, the compression at the accuracy): without it F has no effect.
    PETSC_OPTIONS="-info :KFReducer" python probe.py [--scene S] --targets 1e-3 --srcf 1 0.1 --opts "NAME:key=value ..."
"""
import sys, os, time, argparse, subprocess, tempfile
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
import numpy as np
import bench
from bench import ref

ap = argparse.ArgumentParser()
ap.add_argument("--scene")
ap.add_argument("--refine", type=float, default=0.5)
ap.add_argument("--angle", type=float, default=0.0)
ap.add_argument("--targets", type=float, nargs="+", default=[1e-3])
ap.add_argument("--srcf", nargs="+", default=["1"])
ap.add_argument("--opts", nargs="+", default=["default:"])
args = ap.parse_args()
folder = tempfile.mkdtemp()
if args.scene:
    scene_path = os.path.abspath(args.scene)
else:
    subprocess.run([sys.executable, os.path.join(bench.ROOT, "meshes", "solid", "generate.py"), "--refine",
                    str(args.refine), "-o", folder], check=True, capture_output=True)
    scene_path = os.path.join(folder, "spacecraft.yaml")
scene = ref.load_scene(scene_path)
band, zeta = scene.raw["band"], float(scene.raw["damping"])
M, K, G, H, PhiR = bench.full_order(scene, args.angle)
nrigid = PhiR.shape[1]
lam, Phi = bench.modes(M, K, band[1], nrigid)
w1 = np.sqrt(lam[nrigid]); beta = 2 * zeta / w1
f_res = np.sqrt(np.maximum(lam[nrigid:], 0)) / (2 * np.pi); f_res = f_res[f_res <= band[1]]
freqs = bench.grid(band, f_res, beta * 2 * np.pi * f_res / 2)
Ge = G - M @ (PhiR @ (PhiR.T @ G)); He = H - (H @ PhiR) @ (PhiR.T @ M)
T_el = bench.direct_response(M, K, beta, Ge, He, freqs)
w = 2 * np.pi * freqs
T_full = T_el + (-(H @ PhiR @ PhiR.T @ G)[None] / (w ** 2)[:, None, None])
print("modes in band", f_res, flush=True)
for name, opts in bench.parse_options(args.opts).items():
    for target in args.targets:
      for f in args.srcf:
        os.environ["KF_SRCF"] = f
        import kryflex
        t0 = time.perf_counter()
        red = kryflex.Reducer(kryflex.scene_from_dict(bench.kryflex_spec(scene_path, args.angle, beta, target)), quiet=True, **opts)
        out = red.reduce()
        sec = time.perf_counter() - t0
        s = out.model.at([args.angle])
        reported = float(np.ravel(red.result(-1, "error_max"))[0])
        csec = float(np.ravel(red.result(-1, "time_compress"))[0]) if "time_compress" in red.result_names(-1) else 0.0
        static = bench.static_text(out.summary) + " bodies " + "+".join(str(v) for v in out.model.sizes)
        err = bench.elastic_error(T_full, s.frf(freqs), T_el)
        print("RESULT srcf", f, "%s %g: %d dofs %d states err %.3g rep %.3g %.2fs comp %.3fs %s" % (name, target, s.dofs, 2 * (s.dofs - s.rigid_modes.shape[1]), err, reported, sec, csec, static), flush=True)
