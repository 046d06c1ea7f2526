"""Lee's example, side by side: the paper's published tables and kryflex's answer on the same scene.

    block = paper_block(scene, summary)        # scene.paper == "lee"; summary of the scene's own reduction

The paper is A. Y. Lee, "A Krylov Model Reduction Methodology for Articulated, Multi-Flexible Body Structures",
Jet Propulsion Laboratory (JPL). Its example is a 28-dof Galileo model (12-dof stator, 21-dof rotor, spin bearing);
meshes/galileo is kryflex's model of it, fitted to Table 1 (meshes/galileo/fit.py). LEE holds the paper's numbers
as published (Tables 1-6): they are inputs to compare with, never results. kryflex's columns are computed here by
the library, in the paper's fixed recipe: the scene's Reducer with the accuracy search off (reduction.search:
false: c = the scene's moments, its importance measure and keep_threshold, the paper's alpha_G rule) and the
single-angle method; the component frequencies by the library's dense eigensolver (KFDenseEig) on the body files.
The block goes into the summary's paper (summary.json's "paper" key); report/paper.py renders it.
"""
import numpy as np

from . import _core

# ------------------------------------------------------------------ the paper's tables, as published
LEE = {
    "citation": 'A. Y. Lee, "A Krylov Model Reduction Methodology for Articulated, Multi-Flexible Body Structures", '
                "Jet Propulsion Laboratory (JPL)",
    # Table 1: free-free flexible frequencies (Hz) of the components, and of the system at alpha = 0 (modes 8-28)
    "rotor_hz": [0.1221, 1.0579, 2.8638, 3.4223, 4.9894, 5.2217, 73.425, 75.821, 76.998, 116.50, 116.51,
                 994.70, 994.70, 2108.5, 2431.9],
    "stator_hz": [57.253, 57.455, 225.24, 225.31, 1217.7, 1404.7],
    "system_hz": [0.1106, 1.0521, 1.9403, 2.3975, 2.8446, 3.4648, 4.9930, 5.4793, 6.8081, 9.2953, 56.060, 73.429,
                  75.823, 76.999, 144.69, 144.73, 712.64, 712.65, 1217.7, 1985.9, 2108.5],
    # Tables 2 and 3: the Krylov model's modes (c = 10): frequency (Hz), normalized MIC, kept. Table 2's mode 8 is
    # printed "14466"; read as 144.66 Hz (it lies between 46.199 and 1204.9 Hz in the list)
    "krylov": {
        "0": {"frequency_hz": [0.1106, 1.0521, 2.3975, 4.9930, 5.4793, 9.2953, 46.199, 144.66, 1204.9, 1989.7],
              "importance": [0.0000, 0.4305, 1.0000, 0.6039, 0.2524, 0.0153, 0.0, 0.0, 0.0, 0.0],
              "kept": [False, True, True, True, True, False, False, False, False, False]},
        "60": {"frequency_hz": [0.1123, 1.0520, 1.8163, 2.4863, 2.8750, 3.5947, 4.9689, 5.1389, 7.1271, 9.2079],
               "importance": [0.1196, 0.2665, 0.1149, 0.4082, 0.0343, 0.0820, 1.0000, 0.7427, 0.0054, 0.0100],
               "kept": [True, True, True, True, False, False, True, True, False, False]},
    },
    "alpha_g": "60",
    "kept_modes": [1, 2, 3, 4, 7, 8],
    "static_correction_hz": 3.5939,
    # Table 4 (alpha_G = 60 deg): projected component models and the reduced system
    "reduced_dofs": {"rotor": 13, "stator": 10, "system": 18},
    "reduced_rotor_hz": [0.1221, 1.0579, 3.2387, 4.9895, 5.2234, 29.578, 116.65],
    "reduced_stator_hz": [57.254, 57.461, 225.25, 226.74],
    "full_system_60_hz": [0.1123, 1.0520, 1.8163, 2.4863, 2.8750, 3.5946, 4.9689, 5.1388, 7.1262, 9.2069, 56.060,
                          73.429, 75.823, 76.999, 144.69, 144.73, 712.64, 712.64, 1217.7, 1985.9, 2108.5],
    "reduced_system_60_hz": [0.1123, 1.0520, 1.8194, 2.4872, 3.4041, 4.9680, 5.1358, 7.1554, 9.1837, 51.280, 145.95],
    # Table 5: full-order moments L^k, k = 0..9, at 0, 15, 30, 45, 60, 72 deg (mantissa x scale)
    "angles": ["0", "15", "30", "45", "60", "72"],
    "moment_scales": [1e-7, 1e-8, 1e-8, 1e-7, 1e-7, 1e-7, 1e-6, 1e-6, 1e-6, 1e-6],
    "moments": [[-1.8910, -1.8009, -1.5520, -1.1973, -0.7973, -0.4739],
                [-0.2396, 0.4015, 1.8967, 3.2367, 3.4613, 2.5805],
                [-0.0042, 1.3059, 4.3198, 6.9248, 7.2071, 5.3085],
                [-0.0000, 0.2705, 0.8863, 1.4057, 1.4478, 1.0595],
                [-0.0000, 0.5587, 1.8169, 2.8524, 2.9075, 2.1140],
                [-0.0000, 1.1539, 3.7246, 5.7878, 5.8389, 4.2182],
                [-0.0000, 0.2383, 0.7635, 1.1744, 1.1726, 0.8417],
                [-0.0000, 0.4922, 1.5652, 2.3830, 2.3548, 1.6794],
                [-0.0000, 1.0164, 3.2086, 4.8353, 4.7290, 3.3509],
                [-0.0000, 2.0992, 6.5775, 9.8113, 9.4968, 6.6861]],
    # Table 6: L_full^k / L_reduced^k is 1.0000 at every angle and k (undefined at 0 deg for k >= 3)
    "moment_ratio": 1.0,
}


def _dense(mat):
    """A small PETSc matrix as a dense NumPy array (every rank gets the whole matrix)."""
    from petsc4py import PETSc
    seq = mat.createRedundantMatrix(mat.getComm().getSize()) if mat.getComm().getSize() > 1 else mat
    seq = seq.convert(PETSc.Mat.Type.SEQDENSE) if seq.getType() != PETSc.Mat.Type.SEQDENSE else seq
    return np.array(seq.getDenseArray(), copy=True)


def component_frequencies(scene):
    """Free-free frequencies (Hz, ascending, rigid modes included as 0) of each body: the library's dense
    eigensolver on the body files, read on this process alone (the paper's bodies are small)."""
    from petsc4py import PETSc
    out = {}
    for name in scene.body_names:
        if (name, "mass") not in scene.matrix_files or (name, "stiffness") not in scene.matrix_files:
            continue                      # a body given in memory: no file to read (the paper's are files)
        mats = [_core.load_matrix(scene.matrix_files[name, key], PETSc.COMM_SELF) for key in ("mass", "stiffness")]
        M, K = (_dense(m) for m in mats)
        for m in mats:
            m.destroy()
        lam = _core.dense_eig(K, M)[0]
        lam[np.abs(lam) <= 1e-9 * np.abs(lam).max()] = 0.0
        out[name] = [float(np.sqrt(max(v, 0.0)) / (2 * np.pi)) for v in lam]
    return out


def _body_frequencies(model):
    out = {}
    for name, body in zip(model.body_names, model.bodies):
        lam = _core.dense_eig(body["K"], body["M"])[0]
        lam[np.abs(lam) <= 1e-9 * np.abs(lam).max()] = 0.0
        out[name] = [float(np.sqrt(max(v, 0.0)) / (2 * np.pi)) for v in lam]
    return out


def fixed_recipe(scene):
    """The paper's recipe on the scene by the library: (summary, model) of the single-angle model with the search
    off (c, importance measure and keep_threshold from the scene, alpha_G by the paper's rule)."""
    from .reducer import Reducer
    result = Reducer(scene, quiet=True, search=False, method="single-angle").reduce()
    return result.summary, result.model


BOUNDS_FILE = "tables_bounds.json"


def table_bounds(scene):
    """What the bounds say of the paper's tables per mass layout (meshes/galileo/tables.py writes it beside the
    scene), or None when the scene's folder has no such file."""
    import json
    import os
    where = getattr(scene, "path", None)
    path = os.path.join(os.path.dirname(where), BOUNDS_FILE) if where else None
    if not path or not os.path.isfile(path):
        return None
    with open(path) as f:
        return json.load(f)


def paper_block(scene, summary=None):
    """kryflex's side of the comparison with LEE (plain JSON): component frequencies, and the fixed recipe's
    Krylov tables, alpha_G, kept set, reduced sizes and frequencies, moments, ratios and frequency responses.
    summary: the scene's own reduction; when it already is the fixed recipe (search off, single-angle) it is used
    as it is, else the fixed recipe is run."""
    settings = summary.settings if summary is not None else None
    if settings is not None and settings.search is False and settings.method == "single-angle":
        s, model = summary, None
    else:
        s, model = fixed_recipe(scene)
    s = s.to_json()     # the block is plain JSON, its parts the summary's own
    label_g = s["reduction_label"]
    block = {
        "paper": "lee",
        "citation": LEE["citation"],
        "lee": LEE,
        "component_hz": component_frequencies(scene),
        "recipe": {"moments": s["settings"].get("moments"), "importance": s["settings"].get("importance"),
                   "keep_threshold": s["settings"].get("keep_threshold"), "search": False, "method": "single-angle"},
        "angle_labels": s["angle_labels"],
        "full_hz": s["full"]["frequencies_hz"],
        "rigid_modes": s["full"]["rigid_modes"],
        "krylov": s["krylov"],
        "reduction_label": label_g,
        "reduction_rule": s.get("reduction_rule"),
        "kept_modes": s["kept_modes"],
        "static_correction_modes": s.get("static_correction_modes"),
        "reduced_dofs": dict(s["reduced"]["dofs_per_body"], system=s["reduced"]["system_dofs"][label_g]),
        "reduced_hz": s["reduced"]["frequencies_hz"],
        "moments": s["full"]["moments"],
        "moment_ratios": s["reduced"]["moment_ratios"],
        "frf": s["frf"],
        "frf_error": {lab: v.get("frf_error") for lab, v in s["frf"].items()},
        "outputs": s["outputs"], "inputs": s["inputs"],
        "bounds": table_bounds(scene),
    }
    if model is not None:
        block["reduced_body_hz"] = _body_frequencies(model)
    return block
