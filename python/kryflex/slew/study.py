"""The slewing study (docs/guide/slewing.md): time histories of the full-order and the reduced model along the same angle
history, at slew rates from quasi-static to faster than the first flexible period, and the error of the outputs
against the rate.

    study = SlewStudy(scene, model)              # model: a ReducedModel of the scene (kryflex.reduce(scene).model)
    rows = study.sweep()                         # one row per slew duration, fastest last
    limit = study.limit(rows)                    # the first rate whose error exceeds the scene's accuracy (or None)

Error of a run: per output, max_t |y_full,e - y_red,e| / max_t |y_full,e| over the simulated window, with y_e the
output of the elastic part (integrator.elastic_outputs: the rigid-body and mechanism modes, which both models carry
exactly, taken out, so a slow slew's large rigid motion does not hide the elastic error); the run's error is the
largest over outputs (elastic_error), and the same of the total outputs (total_error). The error that decides
adequacy is the larger of the two: the elastic one alone is blind to an error of the rigid-body motion (in the
time-varying model the rigid and elastic motions exchange momentum as the ties turn), the total one alone is made
small by a large rigid motion.

A structure without revolute joints has no angle to slew: its study is the response at rest to a force history on
its inputs (profiles.HELD: a step of rise time T or a pulse of length T, swept over the same durations), full order
(the assembled system, SlewBodies.from_system) against reduced, with the same error measure and files. A jointed
scene takes the held profiles too (the angles held at the first configuration).
"""
import time

import numpy as np

from .bodies import SlewBodies
from .damping import time_damping
from .integrator import Integrator
from .profiles import HELD, Profile


class SlewStudy:
    """The study of one scene and one reduced model of it.

    profile: slew (rest to rest) or spinup; amplitude_deg: the slew's angle change per revolute joint (default: the
    span of the scene's angles of interest, or 60 deg when they span nothing); durations: slew durations as
    multiples of the first flexible period P1 (from periods_max down to periods_min, nrates of them, geometric);
    steps_per_period: time steps per period of the band's top frequency (h = 1 / (steps_per_period f_top), and at
    most T/100); settle_periods: first flexible periods simulated after the slew; damping: with the angle held, the
    scene's damping model as the frequency domain applies it (damping.py: modal ratios on each model's own modes,
    Rayleigh on the bodies; structural damping and bodies' damping matrices are left out and noted in notes); while
    slewing, stiffness-proportional with the scene's ratio at the first flexible frequency."""

    def __init__(self, scene, model, profile=None, amplitude_deg=None, periods_max=20.0, periods_min=0.1, nrates=8,
                 steps_per_period=20, settle_periods=2.0, progress=None, inputs=None, force=1.0):
        jointfree = scene.info["revolute"] < 1
        profile = _checked_settings(scene.name, jointfree, profile, amplitude_deg, force, periods_max, periods_min,
                                    nrates, steps_per_period, settle_periods)
        self.scene, self.model, self.kind, self.force = scene, model, profile, float(force)
        self.held, self.jointfree = profile in HELD, jointfree
        self.damping_matrices = list(getattr(scene, "damping_matrices", []))
        self.progress = progress or (lambda msg: None)
        configs = np.array(scene.configurations, float).reshape(len(scene.configurations), -1)
        self.alpha0_deg = configs.min(axis=0)
        if amplitude_deg is None:
            span = configs.max(axis=0) - configs.min(axis=0)
            amplitude_deg = np.where(span > 0, span, 60.0)
        self.amplitude_deg = np.broadcast_to(np.asarray(amplitude_deg, float), self.alpha0_deg.shape).copy()
        Profile(profile, 1.0, self.amplitude_deg, self.alpha0_deg)   # checks the profile name
        system = model.at(self.alpha0_deg)
        if not len(system.frequencies_hz):
            raise ValueError("the reduced model of scene '%s' has no flexible mode: nothing to compare in time"
                             % scene.name)
        self.f1 = float(system.frequencies_hz[0])
        self.P1 = 1.0 / self.f1
        self.f_top = float(scene.band[1])
        self.zeta = float(scene.damping)
        self.damping_beta = 2 * self.zeta / (2 * np.pi * self.f1)   # slewing runs and the Exudyn cross-check
        self.damping_model = dict(scene.damping_model)
        self.notes = []
        if float(self.damping_model.get("structural") or 0.0):
            self.notes.append("structural damping (%g) has no viscous equivalent in time: left out of both models"
                              % float(self.damping_model["structural"]))
        if getattr(scene, "damping_matrices", None):
            self.notes.append("the bodies' damping matrices (%s) are left out of both models in time"
                              % ", ".join(scene.damping_matrices))
        self._damping = {}
        self.accuracy = float(scene.accuracy)
        self.periods = np.geomspace(periods_max, periods_min, int(nrates))
        self.steps_per_period = int(steps_per_period)
        self.settle_periods = float(settle_periods)
        self.full = SlewBodies.from_system(scene) if jointfree else SlewBodies.from_scene(scene)
        self.reduced = SlewBodies.from_model(model)
        # a model reduced with reduction.max_frequency is integrated trimmed (trimmed.py): its modes above the limit
        # out of the dynamics at every angle of the slew, as the model reassembles them
        limit = model.settings.get("max_frequency_hz")
        self.trim_hz = float(limit) if limit else 0.0
        self.reassembly_rtol = float(model.settings.get("reassembly_rtol", 1e-9))
        self.top_hz = float(system.top_frequency_hz)
        self.untrimmed_top_hz = float(system.untrimmed_top_hz)
        self.inputs = list(scene.input_names) if inputs is None else list(inputs)
        unknown = [name for name in self.inputs if name not in scene.input_names]
        if unknown or not self.inputs:
            raise ValueError("--input %s: give input names of scene '%s' (%s)"
                             % (",".join(unknown) or "(empty)", scene.name, ", ".join(scene.input_names)))
        driven = [scene.input_names.index(name) for name in self.inputs]
        for bodies in (self.full, self.reduced):   # the drive u(t) on the chosen inputs only
            bodies.G = bodies.G[:, driven]

    def profile(self, duration, still=False):
        """The angle history of the given duration; still=True: the same drive torque with the angle held at alpha0."""
        amplitude = 0.0 * self.amplitude_deg if still else self.amplitude_deg
        return Profile(self.kind, duration, np.radians(amplitude), np.radians(self.alpha0_deg), self.force)

    def step(self, duration):
        return min(1.0 / (self.steps_per_period * self.f_top), duration / 100.0)

    def simulate(self, bodies, duration, h=None, still=False):
        """One model along the profile of the given duration: (t, y, y_elastic)."""
        h = self.step(duration) if h is None else h
        t_end = duration + self.settle_periods * self.P1
        every = max(1, int(np.ceil(t_end / h / 2000)))     # at most ~2000 recorded samples per run
        return self.integrator(bodies, h, still).run(self.profile(duration, still), t_end, record_every=every)

    def damping(self, bodies):
        """The viscous operator of one model (damping.time_damping), its modal part on the model's own modes at
        alpha0, made once."""
        if bodies.label not in self._damping:
            self._damping[bodies.label] = time_damping(bodies, np.radians(self.alpha0_deg), self.damping_model)
        return self._damping[bodies.label]

    def integrator(self, bodies, h, still=False):
        """The integrator of one model: the trimmed one for the reduced bodies of a trimmed model. The angle held
        (still, or a held profile): the frequency domain's damping model (damping()); slewing: stiffness-proportional damping with the
        scene's ratio at f1 (modal damping is defined per configuration; docs/guide/slewing.md says why it is not
        carried through a slew)."""
        damping = self.damping(bodies) if still or self.held else None
        if bodies is self.reduced and self.trim_hz > 0:
            from .trimmed import TrimmedIntegrator
            return TrimmedIntegrator(bodies, h, self.damping_beta, self.trim_hz, self.reassembly_rtol, damping=damping)
        return Integrator(bodies, h, self.damping_beta, damping=damping)

    @property
    def explicit_step(self):
        """The reduced model's stable explicit (central-difference) step at alpha0, 2 / omega_max, trimmed when the
        model is; and the untrimmed model's."""
        return 1.0 / (np.pi * self.top_hz), 1.0 / (np.pi * self.untrimmed_top_hz)

    @staticmethod
    def errors(full, reduced):
        """Per output: max_t |y_f - y_r| / max_t |y_f| (of the elastic parts, and of the totals)."""
        _, yf, ef = full
        _, yr, er = reduced
        tiny = np.finfo(float).tiny
        elastic = np.abs(ef - er).max(axis=0) / np.maximum(np.abs(ef).max(axis=0), tiny)
        total = np.abs(yf - yr).max(axis=0) / np.maximum(np.abs(yf).max(axis=0), tiny)
        return elastic, total

    def run(self, periods, h=None, still=False):
        duration = periods * self.P1
        t0 = time.perf_counter()
        full = self.simulate(self.full, duration, h, still)
        t1 = time.perf_counter()
        red = self.simulate(self.reduced, duration, h, still)
        t2 = time.perf_counter()
        elastic, total = self.errors(full, red)
        prof = self.profile(duration, still)
        return dict(duration_s=duration, periods=periods, peak_rate_deg_s=float(np.degrees(prof.peak_rate)),
                    step_s=self.step(duration) if h is None else h,
                    error=float(max(elastic.max(), total.max())), elastic_error=float(elastic.max()),
                    errors=np.maximum(elastic, total).tolist(), total_error=float(total.max()), full_seconds=t1 - t0,
                    reduced_seconds=t2 - t1, full=full, reduced=red)

    def sweep(self):
        """One row per slew duration (rise time or pulse length for the held profiles), slowest first."""
        rows = []
        for p in self.periods:
            row = self.run(p)
            what = ("%s of %.4g s (%.3g P1)" % (self.kind, row["duration_s"], p) if self.held else
                    "slew of %.4g s (%.3g P1, peak %.4g deg/s)" % (row["duration_s"], p, row["peak_rate_deg_s"]))
            self.progress("%s: error %.3g (full %.1f s, reduced %.1f s)"
                          % (what, row["error"], row["full_seconds"], row["reduced_seconds"]))
            rows.append(row)
        return rows

    def baseline(self, periods=None):
        """The slowest slew's drive torque with the angle held at alpha0: the reduced model's time-domain error at a
        fixed angle, which the slewing errors are to be read against (None for a held profile: every run is one)."""
        if self.held:
            return None
        return self.run(self.periods[0] if periods is None else periods, still=True)

    def convergence(self, periods=None):
        """The fastest slew again with half the step: the change of its error (the time discretization's share)."""
        p = self.periods[-1] if periods is None else periods
        h = self.step(p * self.P1)
        a, b = self.run(p, h), self.run(p, h / 2)
        return dict(periods=p, step_s=h, error=a["error"], error_half_step=b["error"],
                    output_change=float(np.abs(a["full"][2][::1] - _resample(b["full"], a["full"][0])).max()
                                        / max(np.abs(b["full"][2]).max(), np.finfo(float).tiny)))

    def exudyn_check(self, periods=None):
        """The full model's history of the fastest slew by Exudyn's solver (exudyn_check.py) at the same step:
        its relative max difference from the Newmark history (round-off when both are right)."""
        from .exudyn_check import exudyn_history
        p = self.periods[-1] if periods is None else periods
        duration = p * self.P1
        h = self.step(duration)
        t_end = duration + self.settle_periods * self.P1
        t, y, _ = Integrator(self.full, h, self.damping_beta).run(self.profile(duration), t_end)
        te, ye = exudyn_history(self.full, self.profile(duration), t_end, h, self.damping_beta)
        if len(te) != len(t) or not np.allclose(te, t):
            raise RuntimeError("Exudyn recorded %d steps, the integrator %d" % (len(te), len(t)))
        return dict(periods=p, step_s=h, difference=float(np.abs(ye - y).max() / max(np.abs(y).max(),
                                                                                        np.finfo(float).tiny)))

    def exudyn_ffrf(self, periods=None):
        """The reduced bodies in Exudyn's floating-frame formulation against this integrator's full and reduced
        bodies (exudyn_check.ffrf_comparison), for the slowest slew and the middle one of the sweep (or the given
        durations, in P1): one dict per duration."""
        from .exudyn_check import ffrf_comparison
        if periods is None:
            periods = [self.periods[0], self.periods[len(self.periods) // 2]]
        return [ffrf_comparison(self, p) for p in periods]

    def limit(self, rows):
        """The first row (slowest to fastest: longest to shortest duration) whose error exceeds the scene's accuracy,
        or None."""
        for row in sorted(rows, key=lambda r: -r["duration_s"]):
            if row["error"] > self.accuracy:
                return row
        return None


def _checked_settings(name, jointfree, profile, amplitude_deg, force, periods_max, periods_min, nrates,
                      steps_per_period, settle_periods):
    """The profile to run (the default: slew, or step without revolute joints), after checking the settings: a
    ValueError naming the option otherwise."""
    if profile is None:
        profile = "step" if jointfree else "slew"
    if jointfree and profile not in HELD:
        raise ValueError("scene '%s' has no revolute joint: there is no angle to slew with --profile %s; use "
                         "--profile step or pulse (a force history on the structure at rest; step is the default)"
                         % (name, profile))
    if profile in HELD and amplitude_deg is not None:
        raise ValueError("--amplitude is the slew's angle change: --profile %s holds the angles; give the input "
                         "history's peak with --force" % profile)
    if not (np.isfinite(force) and force != 0):
        raise ValueError("--force must be a finite, non-zero number (got %g)" % force)
    if not (periods_max > periods_min > 0) or nrates < 2:
        raise ValueError("give 0 < --periods-min < --periods-max and --rates of at least 2 (got %g, %g, %d)"
                         % (periods_min, periods_max, nrates))
    if steps_per_period < 4:
        raise ValueError("--steps-per-period must be at least 4 (got %d)" % steps_per_period)
    if not settle_periods >= 0:
        raise ValueError("--settle-periods must be >= 0 (got %g)" % settle_periods)
    if amplitude_deg is not None and not np.all(np.isfinite(amplitude_deg)):
        raise ValueError("--amplitude must be a finite angle in degrees (got %s)" % amplitude_deg)
    return profile


def _resample(run, t):
    """The elastic outputs of a run at the times t (linear interpolation)."""
    tr, _, e = run
    return np.stack([np.interp(t, tr, e[:, o]) for o in range(e.shape[1])], axis=1)
