"""The reduction of a scene, in pyMOR's shape, on the C reducer (KFReducer, src/reducer):

    reducer = kryflex.Reducer(scene)                 # every scene key set on the C reducer, then its -kf_ options
    reduction = reducer.reduce()                     # a Reduction: model, summary, both models
    system = reduction.model.at([37.5])              # the reduced system at any angle (a ReducedSystem)
    reducer.result(0, "frf_error")                   # the C reducer's named results, per angle of interest

The policy (bases, importance, alpha_G, static correction, projection, verification) and every number are C's;
this module maps the scene onto the reducer's setters, hands out the models and builds the report's summary from the
reducer's results (report/summary.py).
"""
import contextlib

import numpy as np

from . import _core, settings
from .api import ReducedModel
from ._runtime import quiet_progress


class Reduction:
    """What a reduction made: the model of the scene's method (model), both models by name (multi_angle_model is
    None when no multi-angle model was built) and the summary (a kryflex.results.Summary: the typed results the
    report and summary.json are written from)."""

    def __init__(self, model, summary, single_angle_model, multi_angle_model=None):
        self.model = model
        self.summary = summary
        self.single_angle_model = single_angle_model
        self.multi_angle_model = multi_angle_model

    def __repr__(self):
        return "Reduction(model=%s dofs per body (%s), multi_angle_model=%s)" % (
            self.model.sizes, self.model.settings.get("method"),
            None if self.multi_angle_model is None else self.multi_angle_model.sizes)


@contextlib.contextmanager
def kf_options(options):
    """The given -kf_ options (names without the -kf_, e.g. moments=12, reducer_type="eigen", band=(0.01, 5)) set
    in PETSc's options database for the duration of the block, and what was there before put back."""
    from petsc4py import PETSc
    opts = PETSc.Options()
    before = {}
    for key, value in options.items():
        name = "kf_" + key
        before[name] = opts.getString(name) if opts.hasName(name) else None
        if isinstance(value, bool):
            text = "true" if value else "false"
        elif isinstance(value, (list, tuple)) or hasattr(value, "tolist"):
            text = ",".join("%.17g" % float(x) for x in (value.tolist() if hasattr(value, "tolist") else value))
        else:
            text = str(value)
        opts.setValue(name, text)
    try:
        yield
    finally:
        for name, value in before.items():
            if value is None:
                opts.delValue(name)
            else:
                opts.setValue(name, value)


def _save_maps(value):
    return "auto" if value in (None, "auto") else bool(value)


def _shared_directions(value):
    """reduction.shared_directions: False (split), True (tied) or "auto" (the search measures both, keeps the smaller)."""
    return "auto" if value in (None, "auto") else value in (True, "true")


def _on_command_line(name):
    """Whether PETSc's options database holds name (without its leading -)."""
    from petsc4py import PETSc
    return PETSc.Options().hasName(name)


def _full_order(value):
    """verify.full_order: True (measured), False (estimated) or "auto" (by size: measured or certified)."""
    return "auto" if value in (None, "auto") else value in (True, "true")


class Reducer:
    """The reduction of a loaded Scene (io/scene.py) by the C reducer.

    Every scene key (reduction.*, verify.*, band, damping, accuracy, angles) is set on the reducer, then the -kf_
    PETSc options are applied (KFReducerSetFromOptions): command-line options override the scene. quiet=True
    silences the progress lines while this object works (-kf_quiet for the call); None leaves -kf_quiet as it is.
    Keyword options are -kf_ options by their names without -kf_ (moments=12, reducer_type="eigen",
    band=(0.01, 5), static_correction=False); they override the scene and the command line for this reducer only."""

    def __init__(self, scene, quiet=None, **options):
        self.scene = scene
        self.quiet = quiet
        red, ver = scene.reduction, scene.verify
        # the flexible solve is read by every solver the solve makes, not by the reducer: kept for reduce()
        self._flex_solver = (options.pop("flex_solver"), True) if "flex_solver" in options else \
            (red.get("flex_solver", "auto"), False)
        kinds = settings.row("-kf_flex_solver")["choices"]
        if self._flex_solver[0] not in kinds:
            raise ValueError("flex_solver: give %s or %s, got %r" % (", ".join(kinds[:-1]), kinds[-1],
                                                                     self._flex_solver[0]))
        r = _core.CReducer(scene.comm)
        r.set_type(red["basis"])
        r.set_scene(scene.cscene)
        r.set_angles([scene.angles_rad(c) for c in scene.configurations])
        named = red["reduction_angle"]
        r.set_reduction_angle(None if named == "auto" else scene.angles_rad(named))
        multi = red["reduction_angles"]
        r.set_multi_angles([scene.angles_rad(c) for c in multi] if multi else None)
        r.set_method(red["method"])
        r.set_band(*scene.band)
        if getattr(scene, "damping_uniform", True):
            r.set_damping(scene.damping)
        else:
            r.set_damping_model(scene.damping_model)
        r.set_accuracy(scene.accuracy)
        r.set_accuracy_measure(getattr(scene, "accuracy_measure", "elastic"))
        r.set_moments(red["moments"], int(red["output_blocks"]))
        r.set_search(bool(red["search"]), int(red["moments_max"]))
        r.set_cluster_tolerance(float(red["cluster_rtol"]))
        r.set_compress(bool(red["compress"]))
        r.set_static_exact(bool(red["static_exact"]))
        r.set_importance(red["importance"], float(red["keep_threshold"]))
        r.set_static_correction(bool(red["static_correction"]))
        r.set_tolerances(float(red["deflation_tol"]), float(red["body_tol"]), float(red["reassembly_rtol"]))
        r.set_shift(float(red["shift"]))
        r.set_max_frequency(red.get("max_frequency"))
        r.set_save_maps(_save_maps(red["save_maps"]))
        r.eigen_set_cover(float(red["eigen_cover"]))
        r.set_verification(_full_order(ver["full_order"]), ver["modes"], int(ver["frequency_points"]),
                           float(ver["frf_floor_db"]), ver.get("certified_min_dofs"))
        # the search's option (-kf_shared_directions), set from the scene unless given here or on the command line
        # (which overrides the scene): false too, since the option's default is auto
        if "shared_directions" not in options and not _on_command_line("kf_shared_directions"):
            options = dict(options, shared_directions=_shared_directions(red.get("shared_directions", "auto")))
        if red.get("damped_moments") and "krylov_damped" not in options:
            options = dict(options, krylov_damped=True)   # the Krylov implementation's option (docs/guide/damping.md)
        with quiet_progress(quiet), kf_options(options):
            r.set_from_options()
        self.handle = r
        self._options = options     # again during reduce(): the options the solve's stages read (refine_rtol, blr...)
        self.configurations = self._angles_of_interest()
        self._reduction = None

    def _angles_of_interest(self):
        """The configurations of interest in degrees, as the reducer has them: the scene's, or those of -kf_angles
        (given in degrees, written back with the 12 digits a user gives)."""
        angles = self.handle.get_angles()
        scene = [list(c) for c in self.scene.configurations]
        if len(angles) == len(scene) and all(np.array_equal(a, self.scene.angles_rad(c)) for a, c in zip(angles, scene)):
            return scene
        return [[float("%.12g" % d) for d in np.degrees(a)] for a in angles]

    # ------------------------------------------------------------------ the reduction

    def setup(self):
        """Checks the settings against the scene before any heavy work (KFReducerSetUp; reduce() calls it too):
        collective, and cheap."""
        self.handle.setup()

    def start_from(self, system):
        """The system of the scene's first configuration, assembled with its rigid modes (a CSystem after set_angles,
        e.g. the model check's): the next reduce() takes its matrices and rigid modes there instead of making them
        again, and then assembles it at the other configurations (do not use it afterwards). Collective: None on the
        ranks that have none (then no rank uses it)."""
        self.handle.set_system(system)

    def verification_plan(self):
        """(measured, certified) as the solve will give its verdict: measured against the full order, or estimated
        and certified by the mode count (verify.full_order auto from verify.certified_min_dofs; where the count finds
        a mode the richest candidate lacks, the verdict is measured after all). After setup()."""
        return self.handle.verification_plan()

    def reduce(self):
        """Sets up and solves (collective: every rank calls it and gets the same small dense models back); returns a
        Reduction. A second call returns the same Reduction."""
        if self._reduction is None:
            # objects every rank has released since (earlier models and reducers under MPI wait in PETSc's garbage,
            # see _binding/common.pxi): destroyed here, a collective point, before the new ones are made
            from petsc4py import PETSc
            PETSc.garbage_cleanup(self.scene.comm)
            with quiet_progress(self.quiet), kf_options(self._options), self._flex_solver_option():
                self.handle.setup()
                self.handle.solve()
            chosen, single, multi = self.handle.models(ReducedModel)
            from .report.summary import build_summary
            from .results import Summary
            summary = Summary.from_json(build_summary(self, single, multi, chosen))
            self._reduction = Reduction(chosen, summary, single, multi)
        return self._reduction

    def count_certificate(self, fd):
        """The certificate's counts at every configuration written to the file descriptor fd, as the solve would make
        them (the helper process of count_helper.py; one process)."""
        with quiet_progress(self.quiet), kf_options(self._options), self._flex_solver_option():
            self.handle.setup()
            self.handle.certify_count_write(fd)

    def _flex_solver_option(self):
        """-kf_flex_solver for the solve: the keyword given to this reducer; else the scene's reduction.flex_solver
        unless the options (command line) give one."""
        from petsc4py import PETSc
        value, keyword = self._flex_solver
        opts = {}
        if keyword or (value != "auto" and not PETSc.Options().hasName("kf_flex_solver")):
            opts["flex_solver"] = value
        # reduction.bodywise_spread: false unless the options (command line, keyword bodywise_spread) say
        if not self.scene.reduction.get("bodywise_spread", True) and "bodywise_spread" not in self._options \
                and not PETSc.Options().hasName("kf_bodywise_spread"):
            opts["bodywise_spread"] = False
        return kf_options(opts) if opts else contextlib.nullcontext()

    # ------------------------------------------------------------------ what the solve recorded

    @property
    def nconfig(self):
        return len(self.configurations)

    def result_names(self, config=-1):
        """Names of the results of configuration config (an index into the scene's angles of interest), or of the
        whole solve (-1)."""
        return self.handle.result_names(int(config))

    def result(self, config, name):
        """A named result as C recorded it: a NumPy array of C's shape (column-major), NaN where not available."""
        return self.handle.result(int(config), name)

    def moments(self, config, name):
        """A moment result (full_moments, reduced_moments, moment_ratios, multi_moment_ratios) as (k, outputs, inputs)."""
        return self.result(config, name).transpose(2, 0, 1)

    def frf(self, config, which):
        """The full ("full") or reduced ("reduced") frequency response of the verification at configuration config,
        or the full one's rigid-body and mechanism part ("full_rigid", recorded with the elastic accuracy measure):
        complex (frequencies, outputs, inputs), at the frequencies of result frf_frequencies_hz."""
        re = self.result(config, "frf_%s_re" % which)
        im = self.result(config, "frf_%s_im" % which)
        return (re + 1j * im).transpose(2, 0, 1)

    def accuracy_measure(self):
        """elastic | total: the response the reducer's errors are of (KFReducerGetAccuracyMeasure)."""
        return self.handle.accuracy_measure()

    def accuracy(self):
        """The accuracy target the solve used (the scene's accuracy, unless -kf_accuracy or this reducer's keyword
        said otherwise), from the chosen model's settings: reduces first if not done yet."""
        return float(self.reduce().model.settings["accuracy"])

    def full_rigid(self, config):
        """The rigid part of frf(config, "full") when the reducer measured the elastic response, else None."""
        if self.accuracy_measure() != "elastic":
            return None
        try:
            return self.frf(config, "full_rigid")
        except Exception:       # no verification at this configuration: no reference, no rigid part of it
            return None

    @property
    def notes(self):
        return self.handle.notes()

    @property
    def rule(self):
        return self.handle.rule()

    def view(self, viewer=None):
        self.handle.view(viewer)

    @property
    def type(self):
        return self.handle.get_type()


def reduce(scene, quiet=None, **options):
    """Reduces a loaded Scene (Reducer(scene, quiet, **options).reduce()): a Reduction (model, summary,
    single_angle_model, multi_angle_model). quiet=True silences the progress lines for the call."""
    return Reducer(scene, quiet, **options).reduce()


def print_options_help(comm=None):
    """Prints the reducer's options (-kf_*, with their defaults) as PETSc's -help does: a reducer without a scene
    reads its options with -help in the options database."""
    from petsc4py import PETSc
    opts = PETSc.Options()
    added = not opts.hasName("help")
    if added:
        opts.setValue("help", True)
    try:
        _core.CReducer(comm).set_from_options()
    finally:
        if added:
            opts.delValue("help")

