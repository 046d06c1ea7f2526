"""The whole reduction of a scene and its verification (paper eq. 5-24), on the C library's stages.

For every configuration of interest: assemble, factor once, build the deflated block Krylov basis, solve the small
eigenproblem, rank the Krylov modes, compute the full-order moments and (for verification) the full-order modes.
Then choose the reduction angle alpha_G, project rigid + kept + static-correction modes onto the bodies, and check
the reassembled model against the full order at every configuration. With method multi-angle (or for comparison),
the Krylov bases of several configurations are projected together so that every moment matches at each of them.
"""
import json
import time

import numpy as np
from petsc4py import PETSc

from . import _core
from .api import ReducedModel

NEGLIGIBLE = 1e-8   # a moment entry below this fraction of its largest value over the angles counts as zero


class Progress:
    """Progress lines on rank 0, on the C library's clock; quiet=True (or -kryflex_quiet) silences them."""

    def __init__(self, comm, quiet=None):
        self.comm = comm
        self.quiet = PETSc.Options().getBool("kryflex_quiet", False) if quiet is None else quiet

    def __call__(self, msg):
        if not self.quiet:
            _core.progress(msg, self.comm)


class Timer(dict):
    def add(self, key, t0):
        self[key] = self.get(key, 0.0) + time.perf_counter() - t0


class Result:
    """A reduction: the model of the scene's method, both models by name, and the summary."""

    def __init__(self, model, summary, single_angle_model, multi_angle_model=None):
        self.model = model
        self.summary = summary
        self.single_angle_model = single_angle_model
        self.multi_angle_model = multi_angle_model


def frequency_grid(band, full_freqs, zeta, npoints):
    """Log-spaced points over the band plus points around each resonance in it (peaks are 1/zeta sharp)."""
    f = list(np.geomspace(band[0], band[1], npoints))
    for fr in full_freqs:
        if band[0] <= fr <= band[1]:
            f.extend(fr * (1 + zeta * np.array([-2, -1, -0.5, 0, 0.5, 1, 2])))
    f = np.unique(np.clip(f, band[0], band[1]))
    return f


def frf_error(Tf, Tr, floor_db=-60.0):
    """max over frequency of ||T_full - T_red||_F / max(||T_full||_F, floor): relative error, except that in
    antiresonance notches deeper than floor_db below the band's peak it is measured against that floor (a notch
    1e-9 below the peak would otherwise turn rounding into a 'large' relative error)."""
    num = np.linalg.norm((Tf - Tr).reshape(len(Tf), -1), axis=1)
    den = np.linalg.norm(Tf.reshape(len(Tf), -1), axis=1)
    floor = 10 ** (floor_db / 20.0) * den.max()
    return float(np.max(num / np.maximum(den, max(floor, 1e-300))))


def _jsonable(a):
    return np.asarray(a, dtype=float).tolist()


def _static_correction(Phi, lam, kept, Gr):
    """Eq. (15-17): the static response of the discarded modes, one vector per input."""
    if kept.all():
        return np.zeros((Phi.shape[0], 0))
    return _core.static_correction(Phi[:, ~kept], lam[~kept], Gr)


def _full_frf(entry, freqs, zeta):
    """Full-order response: rigid modes, computed flexible modes, and the static residual of the modes not computed."""
    w = 2 * np.pi * freqs
    lam = np.concatenate([np.zeros(entry["HPr"].shape[1]), entry["w2"]])
    HPhi = np.hstack([entry["HPr"], entry["HPhi"]])
    PhiG = np.vstack([entry["PrG"], entry["PhiG"]])
    T = _core.modal_frf(lam, HPhi, PhiG, zeta, w, 1e-300)
    resid = entry["L"][0] - np.einsum("ti,ia->ta", entry["HPhi"] / entry["w2"], entry["PhiG"])
    return T + resid[None, :, :]


def _dominant(entry, band, zeta, threshold):
    """Full-order modes in the band whose peak contribution to the I/O map reaches threshold of the largest."""
    w2 = entry["w2"]
    f = np.sqrt(w2) / (2 * np.pi)
    peak = np.array([np.linalg.norm(np.outer(entry["HPhi"][:, i], entry["PhiG"][i, :])) / (2 * zeta * w2[i])
                     for i in range(len(w2))])
    inband = (f >= band[0]) & (f <= band[1])
    if not inband.any():
        return []
    top = peak[inband].max()
    return [int(i) for i in np.nonzero(inband & (peak >= threshold * top))[0]]


def _ratios(Lfull_all, Lred, label):
    """L_full / L_red per entry; None where the full moment is negligible at this angle."""
    Lf = Lfull_all[label]
    scale = np.max(np.abs(np.stack(list(Lfull_all.values()))), axis=0)
    out = []
    for k in range(Lf.shape[0]):
        rows = []
        for i in range(Lf.shape[1]):
            rows.append([None if abs(Lf[k, i, j]) <= NEGLIGIBLE * scale[k, i, j] or Lred[k, i, j] == 0
                         else float(Lf[k, i, j] / Lred[k, i, j]) for j in range(Lf.shape[2])])
        out.append(rows)
    return out


def _max_ratio_dev(ratios):
    devs = [abs(x - 1) for k in ratios for row in k for x in row if x is not None]
    return max(devs) if devs else 0.0


def moment_errors(Lfull_all, Lred, label):
    """Normwise relative error ||L_full^k - L_red^k||_F / ||L_full^k||_F per k, None where the whole moment is
    negligible. For one input and one output it is |L_full/L_red - 1| up to second order; for blocks it does not
    let an entry that is small by geometry (and so carries the solves' rounding relative to the block) dominate."""
    Lf = Lfull_all[label]
    scale = np.max([np.linalg.norm(L.reshape(L.shape[0], -1), axis=1) for L in Lfull_all.values()], axis=0)
    out = []
    for k in range(Lf.shape[0]):
        nf = np.linalg.norm(Lf[k])
        out.append(None if nf <= NEGLIGIBLE * scale[k] else float(np.linalg.norm(Lf[k] - Lred[k]) / nf))
    return out


def _max_error(errors):
    vals = [e for e in errors if e is not None]
    return max(vals) if vals else 0.0


def reduce(scene, quiet=None):
    """Reduces a loaded Scene; returns a Result (model, summary). quiet=True silences progress lines."""
    opts = PETSc.Options()
    was_quiet = opts.getBool("kryflex_quiet", False)
    if quiet:
        opts.setValue("kryflex_quiet", True)
    try:
        return _reduce(scene, quiet)
    finally:
        if quiet and not was_quiet:
            opts.delValue("kryflex_quiet")


def _reduce(scene, quiet):
    red, ver = scene.reduction, scene.verify
    progress = Progress(scene.comm, quiet)
    timer = Timer()
    nmom, nout = int(red["moments"]), int(red["output_blocks"])
    nin = nmom - nout
    zeta = scene.damping
    nrigid = 6 + len(scene.revolute)
    labels = [scene.label(c) for c in scene.configurations]
    configs = dict(zip(labels, scene.configurations))
    named_g = red["reduction_angle"] if red["reduction_angle"] != "auto" else None
    label_g = scene.label(named_g) if named_g is not None else None
    if label_g is not None and label_g not in configs:
        configs[label_g] = named_g   # reduction angle outside the angles of interest: processed, not verified
    multi_labels = [scene.label(c) for c in (red["reduction_angles"] or scene.configurations)]
    for lab, c in zip(multi_labels, red["reduction_angles"] or scene.configurations):
        configs.setdefault(lab, c)
    # the named reduction angle last, so nothing has to be factored twice
    order = [lab for lab in configs if lab != label_g] + ([label_g] if label_g else [])

    system = _core.CSystem(scene.cscene)
    nsys = scene.info["system_dofs"]
    progress("scene '%s': %d bodies (%s dofs), %d system dofs, %d rigid-body and mechanism modes, %d inputs, %d outputs"
             % (scene.name, len(scene.body_names), " + ".join(str(n) for n in scene.body_dofs), nsys, nrigid,
                len(scene.input_names), len(scene.output_names)))
    per, candidates = {}, {}
    multi_basis = _core.BodyBasis(scene.cscene) if len(multi_labels) > 1 or red["method"] == "multi-angle" else None
    for lab in order:
        cfg = configs[lab]
        progress("configuration %s deg" % lab)
        t0 = time.perf_counter()
        system.set_angles(scene.angles_rad(cfg))
        Phir, rigid_res = system.rigid_modes()
        timer.add("assembly", t0)
        t0 = time.perf_counter()
        solver = _core.FlexSolver(system, red["shift"] or None)
        solver.setup()
        timer.add("factorization", t0)
        t0 = time.perf_counter()
        if red["basis"] == "krylov":
            basis = _krylov_basis(solver, nin, nout, red)
            timer.add("krylov", t0)
        else:
            basis = _eigen_basis(system, solver, scene)
            timer.add("eigen basis", t0)
        lam, Phi, Gr, Hr, ndefl, csize = basis["lam"], basis["Phi"], basis["Gr"], basis["Hr"], basis["ndefl"], basis["size"]
        t0 = time.perf_counter()
        imp = _core.mode_importance(lam, Phi, Gr, Hr, zeta, red["importance"], 0.0)
        kept = imp >= float(red["keep_threshold"])
        timer.add("krylov modes", t0)
        t0 = time.perf_counter()
        L = solver.moments(nmom)
        timer.add("moments", t0)
        gram_cond = None
        if nsys <= 20000 and red["basis"] == "krylov":
            gram_cond = float(min(solver.raw_basis(nin, nout)[1], 1e300))
        entry = dict(L=L, lam=lam, imp=imp, kept=kept, ndefl=ndefl, c=csize, gram_cond=gram_cond,
                     rigid_res=rigid_res, stats=solver.stats())
        t0 = time.perf_counter()
        if lab == label_g or label_g is None:
            X = basis["kept_and_static"](kept, bool(red["static_correction"]))
            entry["nstatic"] = X.getSize()[1] - int(kept.sum())
            bb = _core.BodyBasis(scene.cscene)
            bb.add(system, Phir)
            bb.add(system, X)
            candidates[lab] = bb
        if multi_basis is not None and lab in multi_labels:
            multi_basis.add(system, Phir)
            multi_basis.add(system, basis["all"]())
        timer.add("projection", t0)
        if ver["full_order"] and lab in labels:
            t0 = time.perf_counter()
            entry.update(_verify_full(system, scene, nsys - nrigid))
            timer.add("verification eigensolve", t0)
        per[lab] = entry
        del solver
        progress("  %d %s vectors (%d deflated), %d of %d modes kept; held dofs %d"
                 % (csize, red["basis"], ndefl, int(kept.sum()), csize, entry["stats"]["held"]))

    # the reduction angle: named, or the configuration whose Krylov model needs the most modes
    if label_g is None:
        label_g = max(labels, key=lambda lab: (int(per[lab]["kept"].sum()), float(per[lab]["imp"][per[lab]["kept"]].sum())))
        rule = ("alpha_G = %s deg: of the angles of interest, its Krylov model needs the most modes above the "
                "importance threshold %g (%d), so its kept set covers the others' (the paper's rule)"
                % (label_g, float(red["keep_threshold"]), int(per[label_g]["kept"].sum())))
    else:
        rule = "alpha_G = %s deg, named in the scene" % label_g
    progress(rule)
    t0 = time.perf_counter()
    bb = candidates[label_g]
    bb.finish(float(red["body_tol"]))
    model = _make_model(scene, bb, red, [configs[label_g]], "single-angle")
    multi_model = None
    if multi_basis is not None:
        multi_basis.finish(float(red["body_tol"]))
        multi_model = _make_model(scene, multi_basis, red, [configs[lab] for lab in multi_labels], "multi-angle")
    timer.add("projection", t0)
    progress("reduced bodies: %s dofs (single-angle)%s" % (" + ".join(str(v) for v in model.sizes),
             "; %s dofs (multi-angle)" % " + ".join(str(v) for v in multi_model.sizes) if multi_model else ""))

    chosen = model if red["method"] == "single-angle" else multi_model
    summary = _summary(scene, per, labels, label_g, rule, model, multi_model, chosen, timer, progress)
    return Result(chosen, summary, model, multi_model)


def _krylov_basis(solver, nin, nout, red):
    """kryflex's basis: the deflated block Krylov vectors, their small eigenproblem (eq. 12-13), and how to build the
    projected vectors from them (kept modes + the paper's static correction, eq. 15-17)."""
    kb, ndefl = solver.krylov_basis(nin, nout, float(red["deflation_tol"]))
    Mr, Kr, Gr, Hr = kb.project()
    lam, Phi = _core.dense_eig(Kr, Mr)

    def kept_and_static(kept, static):
        S = _static_correction(Phi, lam, kept, Gr) if static else np.zeros((kb.size, 0))
        return kb.combine(np.hstack([Phi[:, kept], S]))

    return dict(lam=lam, Phi=Phi, Gr=Gr, Hr=Hr, ndefl=ndefl, size=kb.size, kept_and_static=kept_and_static,
                all=lambda: kb.combine(np.eye(kb.size)))


def _eigen_basis(system, solver, scene):
    """The baseline kryflex replaces (EP&A / COMPARE style): full-order modes covering the band (SLEPc), ranked
    the same way, with the static correction of every mode not kept (one solve with K+)."""
    fmax = float(scene.reduction["eigen_cover"]) * scene.band[1]
    nflex = scene.info["system_dofs"] - 6 - len(scene.revolute)
    nev = min(nflex, 10)
    while True:
        w2, modes = system.eigen_modes(nev)
        if nev >= nflex or (len(w2) and np.sqrt(w2[-1]) / (2 * np.pi) > fmax):
            break
        nev = min(nflex, 2 * nev)
    keep = np.sqrt(np.maximum(w2, 0)) / (2 * np.pi) <= fmax
    keep[:1] = True
    m = int(keep.sum())
    modes = _core.combine(modes, np.eye(len(w2))[:, :m])
    lam = w2[:m]
    Ms, Ks, G, Ht = system.matrices()
    Gr, Hr = _core.inner(modes, G), _core.inner(modes, Ht).T

    def kept_and_static(kept, static):
        cols = [_core.combine(modes, np.eye(m)[:, kept])]
        if not static:
            return cols[0]
        # residual flexibility: K+ G minus what the kept modes already carry
        X0 = solver.apply(G)
        C = np.zeros((m, Gr.shape[1]))
        C[kept] = Gr[kept] / lam[kept, None]
        S = _core.combine(modes, C)
        X0.axpy(-1.0, S)
        return _core.combine(_hstack(cols[0], X0), np.eye(int(kept.sum()) + Gr.shape[1]))

    return dict(lam=lam, Phi=np.eye(m), Gr=Gr, Hr=Hr, ndefl=0, size=m, kept_and_static=kept_and_static,
                all=lambda: modes)


def _hstack(A, B):
    """[A, B] for two tall dense Mats with the same rows."""
    p, q = A.getSize()[1], B.getSize()[1]
    out = _core.combine(A, np.hstack([np.eye(p), np.zeros((p, q))]))
    out.axpy(1.0, _core.combine(B, np.hstack([np.zeros((q, p)), np.eye(q)])))
    return out


def _verify_full(system, scene, nflex):
    """Full-order modes covering three times the band's top (SLEPc), with rigid-mode participation."""
    want = scene.verify["modes"]
    fmax = 3 * scene.band[1]
    nev = min(nflex, int(want) if want != "auto" else 20)
    while True:
        w2, HPhi, PhiG = system.eigen(nev)
        if want != "auto" or nev >= nflex or (len(w2) and np.sqrt(w2[-1]) / (2 * np.pi) >= fmax):
            break
        nev = min(nflex, 2 * nev)
    HPr, PrG = system.rigid_io()
    return dict(w2=w2, HPhi=HPhi, PhiG=PhiG, HPr=HPr, PrG=PrG)


def _make_model(scene, bb, red, configs, method):
    """The C reduced model of a finished body basis, with the settings that made it (JSON values)."""
    save_maps = red["save_maps"]
    keep_maps = save_maps is True or (save_maps == "auto" and max(scene.body_dofs) <= 200000)
    model = ReducedModel.from_body_basis(scene.cscene, bb, [scene.angles_rad(c) for c in configs], keep_maps)
    settings = {k: (v if not isinstance(v, np.ndarray) else v.tolist()) for k, v in red.items()}
    settings.update(method=method, reduction_angles_deg=configs, damping=scene.damping, band_hz=scene.band)
    for key, value in settings.items():
        model.set_setting(key, json.dumps(value))
    return model


def _summary(scene, per, labels, label_g, rule, model, multi_model, chosen, timer, progress):
    red = scene.reduction
    zeta = scene.damping
    nrigid = 6 + len(scene.revolute)
    Lfull = {lab: per[lab]["L"] for lab in labels}
    full_freqs, red_freqs, red_mom, ratios, frf, dom, dom_err = {}, {}, {}, {}, {}, {}, {}
    sgain, rank, sratio, hsize, merr = {}, {}, {}, {}, {}
    notes = []
    t_reasm = []
    for lab, cfg in zip(labels, scene.configurations):
        e = per[lab]
        t0 = time.perf_counter()
        system = model.at(cfg)
        t_reasm.append(time.perf_counter() - t0)
        Kh, rk, sr, Phir = system.K, system.constraint_rank, system.sigma_ratio, system.rigid_modes
        if Phir is None or Phir.shape[1] != nrigid:
            notes.append("reassembled model at %s deg: %s rigid-body and mechanism modes from the bodies' rigid motions, "
                         "expected %d" % (lab, "no" if Phir is None else Phir.shape[1], nrigid))
        fr = system.frequencies_hz
        Lr = system.moments(Lfull[lab].shape[0])
        red_freqs[lab] = _jsonable(fr)
        red_mom[lab] = _jsonable(Lr)
        ratios[lab] = _ratios(Lfull, Lr, lab)
        merr[lab] = moment_errors(Lfull, Lr, lab)
        sgain[lab] = float(np.linalg.norm(Lfull[lab][0] - Lr[0]) / np.linalg.norm(Lfull[lab][0]))
        rank[lab], sratio[lab], hsize[lab] = int(rk), float(sr), int(Kh.shape[0])
        dev = _max_error(merr[lab])
        if dev > 1e-8:
            notes.append("single-angle model at %s deg: moments not matched exactly, max ||L_full - L_red|| / "
                         "||L_full|| = %.3e (max entrywise |L_full/L_red - 1| = %.3e)%s"
                         % (lab, dev, _max_ratio_dev(ratios[lab]), " (alpha_G)" if lab == label_g else ""))
        if "w2" in e:
            ff = np.sqrt(e["w2"]) / (2 * np.pi)
            full_freqs[lab] = _jsonable(ff)
            freqs = frequency_grid(scene.band, ff, zeta, int(scene.verify["frequency_points"]))
            Tf = _full_frf(e, freqs, zeta)
            Tr = system.frf(freqs, zeta)
            err = frf_error(Tf, Tr, float(scene.verify["frf_floor_db"]))
            frf[lab] = dict(freq_hz=_jsonable(freqs), full_re=_jsonable(Tf.real), full_im=_jsonable(Tf.imag),
                            reduced_re=_jsonable(Tr.real), reduced_im=_jsonable(Tr.imag), max_rel_error=err)
            dom[lab] = _dominant(e, scene.band, zeta, float(red["keep_threshold"]))
            dom_err[lab] = [float(np.min(np.abs(fr - ff[i])) / ff[i]) if fr.size else None for i in dom[lab]]
        progress("  %s deg: reduced system %d dofs, moment error %.2e, static gain error %.2e%s"
                 % (lab, Kh.shape[0], dev, sgain[lab],
                    ", FRF max rel. error %.3g" % frf[lab]["max_rel_error"] if lab in frf else ""))
    summary = {
        "kryflex_version": __import__("kryflex").__version__,
        "scene": scene.name, "scene_file": scene.path,
        "inputs": scene.input_names, "outputs": scene.output_names, "joints": scene.revolute,
        "angles_deg": scene.configurations, "angle_labels": labels,
        "band_hz": scene.band, "damping": zeta, "accuracy": scene.accuracy,
        "settings": {"basis": red["basis"], "moments": int(red["moments"]), "output_blocks": int(red["output_blocks"]),
                     "importance": red["importance"], "keep_threshold": float(red["keep_threshold"]),
                     "deflation_tol": float(red["deflation_tol"]), "body_tol": float(red["body_tol"]),
                     "reduction_angles_deg": chosen.settings["reduction_angles_deg"], "method": red["method"]},
        "full": {"dofs_per_body": dict(zip(scene.body_names, scene.body_dofs)),
                 "system_dofs": scene.info["system_dofs"], "rigid_modes": nrigid,
                 "frequencies_hz": full_freqs,
                 "moments": {lab: _jsonable(Lfull[lab]) for lab in labels}},
        "krylov": {lab: {"frequency_hz": _jsonable(np.sqrt(np.maximum(per[lab]["lam"], 0)) / (2 * np.pi)),
                         "importance": _jsonable(per[lab]["imp"]), "kept": [bool(x) for x in per[lab]["kept"]],
                         "deflations": int(per[lab]["ndefl"]), "gram_condition_raw": per[lab]["gram_cond"]}
                   for lab in labels},
        "reduction_label": label_g, "reduction_rule": rule,
        "kept_modes": [int(i) + 1 for i in np.nonzero(per[label_g]["kept"])[0]],
        "static_correction_modes": int(per[label_g].get("nstatic", 0)),
        "reduced": {"dofs_per_body": dict(zip(scene.body_names, model.sizes)),
                    "system_dofs": hsize, "frequencies_hz": red_freqs, "moments": red_mom,
                    "moment_ratios": ratios, "moment_error": merr, "static_gain_error": sgain, "reassembly_rank": rank,
                    "reassembly_sigma_ratio": sratio,
                    "reassembly_seconds": float(np.median(t_reasm)) if t_reasm else None},
        "frf": frf, "dominant_modes": dom, "dominant_freq_error": dom_err,
        "timings_s": {k: float(v) for k, v in timer.items()},
        "notes": notes,
    }
    if multi_model is not None:
        m_ratios, m_err, m_size, m_merr = {}, {}, {}, {}
        for lab, cfg in zip(labels, scene.configurations):
            system = multi_model.at(cfg)
            Lr = system.moments(Lfull[lab].shape[0])
            m_ratios[lab] = _ratios(Lfull, Lr, lab)
            m_merr[lab] = moment_errors(Lfull, Lr, lab)
            m_size[lab] = int(system.dofs)
            if lab in frf:
                freqs = np.asarray(frf[lab]["freq_hz"])
                Tf = np.asarray(frf[lab]["full_re"]) + 1j * np.asarray(frf[lab]["full_im"])
                Tr = system.frf(freqs, zeta)
                m_err[lab] = frf_error(Tf, Tr, float(scene.verify["frf_floor_db"]))
        summary["multi_angle"] = {"system_dofs": m_size, "dofs_per_body": dict(zip(scene.body_names, multi_model.sizes)),
                                  "moment_ratios": m_ratios, "frf_max_rel_error": m_err,
                                  "reduction_angles_deg": multi_model.settings["reduction_angles_deg"],
                                  "moment_error": m_merr,
                                  "max_moment_ratio_deviation": {lab: _max_ratio_dev(m_ratios[lab]) for lab in labels},
                                  "max_moment_error": {lab: _max_error(m_merr[lab]) for lab in labels}}
        progress("multi-angle model: %s dofs per body, reassembled %s dofs, max moment error %.2e"
                 % (" + ".join(str(v) for v in multi_model.sizes), max(m_size.values()),
                    max(summary["multi_angle"]["max_moment_error"].values())))
    return summary
