"""1 against 2 ranks on the peers bench's one-angle scenes (kryflex reduce's summary.json and reduced.h5 in
out/SCENE_TARGET_VARIANT_{1,2}): system dofs, chosen search candidate (family, moments, kept clusters, variant),
ties, frequencies at 0 deg; and the chosen model's static moment L^0 against the full order's, computed here from the
bench's full order (bench.full_order: the bodies' files and joint ties, rigid modes from geometry), dense NumPy, as
tests/python/reducer/test_shared_directions.py does, beside kryflex's own reported L^0 error."""
import json, os, sys
import numpy as np
ROOT, D = sys.argv[1], sys.argv[2]
sys.path.insert(0, os.path.join(ROOT, "benchmarks", "peers"))
sys.path.insert(0, os.path.join(ROOT, "python"))
import bench
import kryflex

full = {}
def L0_full(scene_name, path):
    if scene_name not in full:
        M, K, G, H, R = bench.full_order(bench.ref.load_scene(path), 0.0)
        M, K = M.toarray(), K.toarray()
        Ge = G - M @ R @ (R.T @ G)
        x = np.linalg.solve(K + M @ R @ R.T @ M, Ge)
        x -= R @ (R.T @ (M @ x))
        full[scene_name] = H @ x
    return full[scene_name]

print("| scene | target | variant | ranks 1 / 2: system dofs | chosen candidate (family, c, kept clusters, variant) 1 / 2 "
      "| ties 1 / 2 | frequencies at 0 deg, max rel. diff | L0 error: kryflex's (1 rank) | L0 error: here |")
print("|---|---|---|---|---|---|---|---|---|")
for s in ("galileo", "solid"):
    for t in ("0.01", "0.001", "0.0001"):
        for v in ("default", "nse"):
            runs = []
            for n in (1, 2):
                o = os.path.join(D, "out", "%s_%s_%s_%d" % (s, t, v, n))
                sm = json.load(open(os.path.join(o, "summary.json")))
                m = kryflex.ReducedModel.load(os.path.join(o, "reduced.h5"))
                cand = sm["search"][sm["search_chosen"]]
                runs.append((sm, m, cand))
            (s1, m1, c1), (s2, m2, c2) = runs
            f1, f2 = m1.at([0.0]).frequencies_hz, m2.at([0.0]).frequencies_hz
            df = np.max(np.abs(f1 - f2) / np.maximum(np.abs(f1), 1e-300)) if len(f1) == len(f2) else float("nan")
            # the 7 rigid frequencies are ~0: compare the flexible ones relative to themselves, the rigid absolutely
            flex = f1 > 1e-6
            df = np.max(np.abs(f1[flex] - f2[flex]) / f1[flex]) if len(f1) == len(f2) else float("nan")
            key = lambda c: (c["family"], c["moments"], c["kept_clusters"], c["variant"])
            L0 = L0_full(s, os.path.join(D, "%s_%s.yaml" % (s, t)))
            L0r = m1.at([0.0]).moments(1)[0]
            err = np.linalg.norm(L0r - L0) / np.linalg.norm(L0)
            ties = lambda m: 0 if m.ties is None else m.ties.shape[0]
            print("| %s | %s | %s | %s / %s | %s / %s | %d / %d | %.1e | %.2e (%s) | %.2e |" % (
                s, t, v, s1["chosen"]["system_dofs"]["0"], s2["chosen"]["system_dofs"]["0"], key(c1), key(c2),
                ties(m1), ties(m2), df, max(s1["chosen"]["static_moment_error"].values()),
                "kept" if s1["chosen"]["static_exact"] else "truncated", err), flush=True)
