"""The results of a reduction as typed objects: the tree of dataclasses that ``summary.json`` holds.

    summary = Summary.load("out/summary.json")       # any summary version kryflex wrote
    summary.verdict.target_met, summary.verdict.error_max, summary.chosen.worst_where
    summary.performance.solves_s, summary.search[summary.search_chosen].error
    summary.configuration("30").frf.full()            # one angle of interest: complex (frequencies, outputs, inputs)
    summary.to_json()                                 # the dict summary.json holds: same keys, same values

Every field is named as its key in summary.json; a field whose key a summary lacks (an older kryflex, a reducer that
did not record it) is None or empty and is left out again by to_json, and keys this version does not know are kept
in ``extra`` and written back, so ``Summary.from_json(d).to_json() == d`` for every summary kryflex wrote (plus the
version field). The verdict's keys sit at the top of summary.json; here they are one object, ``summary.verdict``.
Angle labels (``angle_labels``: "0", "15", "0_30" with several joints, "structure" without a revolute joint) key the
per-configuration blocks. Numbers that are undefined are None (JSON has no NaN). docs/guide/results.md describes
every block; this module depends on the standard library and NumPy only.

Versions: 1, summaries without a ``summary_version`` key (before the typed summary); 2, the same keys and values
plus ``summary_version``. from_json reads both; to_json writes version 2.
"""
import dataclasses
import itertools
import json
import warnings
from dataclasses import dataclass, field

import numpy as np

SUMMARY_VERSION = 2


class SummaryError(ValueError):
    """A summary that cannot be read: the message names the key and the fix."""


_SCALARS = frozenset((str, int, float, bool, type(None)))


def _json_leaf(value):
    """Whether a value holds no object: written on one line. The lists are looked into a level at a time, all of one
    level's elements together: their types collected in one pass of C (set(map(type, ...))), and only the lists and
    tuples among them taken to the next level (a summary's FRF blocks, 449 x 3 x 2 numbers per configuration, were a
    Python call per number, then one per inner list)."""
    if isinstance(value, dict):
        return False
    if not isinstance(value, (list, tuple)):
        return True
    level = [value]
    while level:
        items = list(itertools.chain.from_iterable(level))
        types = set(map(type, items))
        if types <= _SCALARS:
            return True
        if any(issubclass(t, dict) for t in types):
            return False
        level = [v for v in items if isinstance(v, (list, tuple))]
    return True


def _json_text(value, level=0):
    """json.dumps(value, indent=1, allow_nan=False) but for lists without objects, each on one line."""
    leaf = _json_leaf(value)
    if leaf or (isinstance(value, dict) and not all(isinstance(k, str) for k in value)):
        return json.dumps(value, allow_nan=False) if leaf else json.dumps(value, indent=1, allow_nan=False)
    if not value:
        return json.dumps(value)
    pad = "\n" + " " * (level + 1)
    if isinstance(value, dict):
        body = ",".join(pad + json.dumps(k) + ": " + _json_text(v, level + 1) for k, v in value.items())
        return "{" + body + "\n" + " " * level + "}"
    return "[" + ",".join(pad + _json_text(v, level + 1) for v in value) + "\n" + " " * level + "]"


# =============================================================================================== how a field is stored

class _Plain:
    """A JSON value kept as it is (numbers, strings, lists, dicts of them)."""

    def decode(self, value, where):
        return value

    def encode(self, value):
        return value


PLAIN = _Plain()


class _One(_Plain):
    """One record (a JSON object), or None."""

    def __init__(self, cls):
        self.cls = cls

    def decode(self, value, where):
        return None if value is None else self.cls._decode(value, where)

    def encode(self, value):
        return None if value is None else value.to_json()


class _ListOf(_One):
    """A list of records."""

    def decode(self, value, where):
        if value is None:
            return None
        if not isinstance(value, list):
            raise SummaryError("%s is a %s, not a list: a summary written by another program?"
                               % (where, type(value).__name__))
        return [self.cls._decode(v, "%s[%d]" % (where, k)) for k, v in enumerate(value)]

    def encode(self, value):
        return None if value is None else [v.to_json() for v in value]


class _ByLabel(_One):
    """A record per angle label ({label: record})."""

    def decode(self, value, where):
        if value is None:
            return None
        if not isinstance(value, dict):
            raise SummaryError("%s is a %s, not an object keyed by angle label" % (where, type(value).__name__))
        return {label: self.cls._decode(v, "%s[%r]" % (where, label)) for label, v in value.items()}

    def encode(self, value):
        return None if value is None else {label: v.to_json() for label, v in value.items()}


class _Flat(_One):
    """A record whose keys sit in its parent's JSON object (the verdict's keys are at summary.json's top)."""


def _value(default=None, doc=""):
    """A plain JSON field (default: None, or a fresh copy of a list or dict)."""
    if isinstance(default, (list, dict)):
        return field(default_factory=lambda: type(default)(default), metadata={"codec": PLAIN, "doc": doc})
    return field(default=default, metadata={"codec": PLAIN, "doc": doc})


def _record(cls, doc=""):
    return field(default=None, metadata={"codec": _One(cls), "doc": doc})


def _records(cls, doc=""):
    return field(default_factory=list, metadata={"codec": _ListOf(cls), "doc": doc})


def _by_label(cls, doc=""):
    return field(default_factory=dict, metadata={"codec": _ByLabel(cls), "doc": doc})


def _flat(cls, doc=""):
    return field(default_factory=cls, metadata={"codec": _Flat(cls), "doc": doc})


# =============================================================================================== the record base

@dataclass(kw_only=True)
class Record:
    """A JSON object of summary.json as a dataclass: its fields are its keys (kryflex.results)."""

    extra: dict = field(default_factory=dict, repr=False, metadata={"internal": True})
    absent: frozenset = field(default=frozenset(), repr=False, compare=False, metadata={"internal": True})

    @classmethod
    def json_fields(cls):
        """The dataclass fields that are keys of the JSON object (or, flat, records whose keys are)."""
        return [f for f in dataclasses.fields(cls) if not f.metadata.get("internal")]

    @classmethod
    def json_keys(cls):
        """Every key of this object in summary.json, the flat records' included."""
        keys = []
        for f in cls.json_fields():
            codec = f.metadata["codec"]
            keys += codec.cls.json_keys() if isinstance(codec, _Flat) else [f.name]
        return keys

    @classmethod
    def _read(cls, data, where):
        """(constructor arguments, absent keys, keys used) from a JSON object."""
        kwargs, absent, used = {}, set(), set()
        for f in cls.json_fields():
            codec = f.metadata["codec"]
            if isinstance(codec, _Flat):
                sub, sub_absent, sub_used = codec.cls._read(data, where)
                kwargs[f.name] = codec.cls(**sub, absent=frozenset(sub_absent))
                used |= sub_used
            elif f.name in data:
                kwargs[f.name] = codec.decode(data[f.name], "%s[%r]" % (where, f.name))
                used.add(f.name)
            else:
                absent.add(f.name)
        return kwargs, absent, used

    @classmethod
    def _decode(cls, data, where):
        if not isinstance(data, dict):
            raise SummaryError("%s is a %s, not a JSON object: a summary written by another program?"
                               % (where, type(data).__name__))
        kwargs, absent, used = cls._read(data, where)
        extra = {k: v for k, v in data.items() if k not in used}
        return cls(**kwargs, extra=extra, absent=frozenset(absent))

    @classmethod
    def from_json(cls, data):
        """The record of a JSON object (a dict as json.load gives it); keys it does not know go into extra."""
        return cls._decode(data, cls.__name__)

    def _json_value_of(self, key):
        """The JSON value of one of this record's keys (KeyError when the source lacked it)."""
        f = next(f for f in self.json_fields() if f.name == key)
        value = getattr(self, key)
        if key in self.absent and self._is_default(f, value):
            raise KeyError(key)
        return f.metadata["codec"].encode(value)

    def _is_default(self, f, value):
        if f.default is not dataclasses.MISSING:
            return value is f.default or value == f.default
        return value == f.default_factory()

    def to_json(self):
        """The JSON object (dict) of this record: its fields in order, then extra; keys the source lacked and that
        still hold their default are left out."""
        out = {}
        for f in self.json_fields():
            value = getattr(self, f.name)
            codec = f.metadata["codec"]
            if isinstance(codec, _Flat):
                out.update(value.to_json())
            elif f.name in self.absent and self._is_default(f, value):
                continue
            else:
                out[f.name] = codec.encode(value)
        out.update(self.extra)
        return out


# =============================================================================================== the blocks

@dataclass(kw_only=True)
class Settings(Record):
    """The reduction settings the chosen model was made with (its own settings, as the reducer records them)."""
    basis: str = _value(doc="krylov | eigen")
    moments: object = _value(doc="c, the moments matched per input (an int; 'auto' when searched)")
    moments_max: int = _value(doc="the largest c the search tries")
    output_blocks: int = _value()
    importance: str = _value(doc="the Krylov-mode importance measure")
    keep_threshold: float = _value()
    cluster_rtol: float = _value()
    search: bool = _value()
    deflation_tol: float = _value()
    body_tol: float = _value()
    reduction_angles_deg: list = _value(doc="the expansion configurations [[deg per revolute joint], ..]")
    method: str = _value(doc="single-angle | multi-angle")


@dataclass(kw_only=True)
class FullOrder(Record):
    """The full-order system at the angles of interest: sizes, frequencies, moments."""
    dofs_per_body: dict = _value(doc="{body: dofs}")
    system_dofs: int = _value(doc="dofs of the assembled system")
    rigid_modes: int = _value(doc="rigid-body and mechanism modes")
    body_frequencies_hz: dict = _value(doc="{body: lowest free-free component frequencies}")
    frequencies_hz: dict = _value({}, doc="{label: lowest flexible system frequencies}")
    mode_count: dict = _value({}, doc="{label: {count, below_hz}}: flexible modes below the verification's cut by "
                                      "the inertia of K_S - sigma M_S (-kf_verify_count), where counted")
    moments: dict = _value({}, doc="{label: [k][output][input]} moments L^k (None entries: not computed)")


@dataclass(kw_only=True)
class KrylovModes(Record):
    """The Krylov modes at one configuration: their frequencies, normalized importance and which were kept."""
    frequency_hz: list = _value([])
    importance: list = _value([])
    kept: list = _value([], doc="one bool per mode")
    deflations: int = _value()
    gram_condition_raw: float = _value()


@dataclass(kw_only=True)
class Trimming(Record):
    """The chosen model's highest flexible frequency and explicit step per angle, with reduction.max_frequency."""
    max_frequency: object = _value(doc="the setting as given (text, number or None)")
    max_frequency_hz: float = _value()
    top_frequency_hz: dict = _value({}, doc="{label: Hz}")
    explicit_step_s: dict = _value({}, doc="{label: 2 / omega_max, s} (None without flexible modes)")
    trimmed_modes: dict = _value({}, doc="{label: modes taken out}")
    untrimmed_top_frequency_hz: dict = _value({})
    top_frequency_hz_max: float = _value()
    explicit_step_s_min: float = _value()


@dataclass(kw_only=True)
class ReducedOrder(Record):
    """The single-angle reduced model at the angles of interest (paper Tables 3-6)."""
    dofs_per_body: dict = _value(doc="{body: reduced dofs}")
    body_frequencies_hz: dict = _value()
    system_dofs: dict = _value(doc="{label: reassembled dofs}")
    frequencies_hz: dict = _value({}, doc="{label: flexible frequencies}")
    moments: dict = _value(doc="{label: [k][output][input]}")
    moment_ratios: dict = _value({}, doc="{label: [k][output][input] full / reduced} (None: negligible full moment)")
    moment_error: dict = _value(doc="{label: [k] relative moment error}")
    static_gain_error: dict = _value()
    reassembly_rank: dict = _value()
    reassembly_sigma_ratio: dict = _value()
    reassembly_seconds: float = _value(doc="median reassembly time over the angles")
    trimming: Trimming = _record(Trimming)


@dataclass(kw_only=True)
class FrequencyResponse(Record):
    """Full and reduced frequency responses at one configuration, each [frequency][output][input] real and imaginary
    parts; reduced_* is the single-angle model's, chosen_* the multi-angle model's when it was chosen."""
    freq_hz: list = _value([])
    full_re: list = _value([])
    full_im: list = _value([])
    reduced_re: list = _value([])
    reduced_im: list = _value([])
    frf_error: float = _value(doc="the single-angle model's relative H-inf error (the verdict's measure)")
    frf_pointwise_error: float = _value(doc="pointwise error with a floor (information)")
    max_rel_error: float = _value(doc="= frf_error, under the name scripts of version 1 read")
    full_rigid_re: list = _value(doc="the full response's rigid-body and mechanism part (elastic measure)")
    full_rigid_im: list = _value()
    chosen_re: list = _value()
    chosen_im: list = _value()
    chosen_model: str = _value()

    @staticmethod
    def _complex(re, im):
        return None if re is None else np.asarray(re, dtype=float) + 1j * np.asarray(im, dtype=float)

    def full(self):
        """The full-order response, complex (frequencies, outputs, inputs)."""
        return self._complex(self.full_re, self.full_im)

    def reduced(self):
        """The single-angle model's response, complex."""
        return self._complex(self.reduced_re, self.reduced_im)

    def chosen(self):
        """The chosen model's response: the multi-angle model's when it was chosen, else the single-angle one's."""
        if self.chosen_re is not None:
            return self._complex(self.chosen_re, self.chosen_im)
        return self.reduced()


@dataclass(kw_only=True)
class Performance(Record):
    """The flexible solver's share of the run: seconds, solve counts and residuals (C KFReducerSolve's timings)."""
    factorization_s: float = _value()
    solves_s: float = _value()
    whole_s: float = _value()
    ratio: float = _value(doc="(whole - verification) / (factorization + solves)")
    solve_calls: int = _value()
    solve_columns: int = _value()
    refinement_solves: int = _value()
    blocks_unconverged: int = _value(doc="block solves left above -kf_refine_rtol after escalation")
    blocks_escalated: int = _value()
    residual_first_max: float = _value()
    residual_final_max: float = _value()
    memory_estimate_mb: float = _value()
    reference_eigensolve_s: float = _value(doc="the verification's full-order eigensolves")
    reference_check_s: float = _value(doc="the verification's direct solves of the full system")
    reference_count_s: float = _value(doc="the verification's mode counts by inertia (-kf_verify_count)")
    certificate_count_s: float = _value(doc="the certified estimate's mode counts by inertia (-kf_verify auto); "
                                            "counted by the helper process: this process's wait for its counts")
    certificate_count_helper_s: float = _value(doc="the helper process's own seconds for the counts (None: counted "
                                                   "in-process)")
    certificate_count_helper_rss_mb: float = _value(doc="the helper process's peak resident memory (its own factors)")
    search_s: float = _value(doc="the accuracy search")
    compress_s: float = _value(doc="the compression of the chosen model (-kf_compress)")



@dataclass(kw_only=True)
class ReferencePoint(Record):
    """The full-order reference against a direct solve at one angle: worst disagreement and where."""
    error: float = _value()
    frequency_hz: float = _value()


@dataclass(kw_only=True)
class ReferenceCheck(Record):
    """The full-order reference checked against direct solves of the full system (C reference_check_*)."""
    error: float = _value()
    rtol: float = _value()
    factorizations: int = _value(doc="numerical factorizations the direct solves made (0 when every point iterated)")
    iterative_points: int = _value(doc="angles and midpoints whose truth was iterated from the reference itself")
    iterative_steps: int = _value(doc="their steps, summed (one block K+ application each, but the first: the moments' K+ G)")
    iterative_steps_max: int = _value()
    fallbacks: int = _value(doc="points whose iteration did not contract, solved directly instead")
    per_angle: dict = _by_label(ReferencePoint)


@dataclass(kw_only=True)
class Verdict(Record):
    """Whether the chosen model meets the accuracy target: always on the model the reducer chose. Its keys are at
    the top of summary.json."""
    accuracy_measure: str = _value(doc="elastic | total: the response the errors are of")
    error_definition: str = _value(doc="the one error measure, in words")
    pointwise_definition: str = _value(doc="the pointwise error (information, never the verdict)")
    chosen_method: str = _value(doc="single-angle | multi-angle")
    target_met: bool = _value(doc="error <= accuracy at every angle of interest and midpoint; None: not measured")
    error_max: float = _value(doc="the chosen model's worst error over angles and midpoints")
    error_estimated: bool = _value(doc="true when the reference was the a-posteriori estimator")
    verdict_kind: str = _value(doc="measured (against the full order) | estimated (against the richest candidate, "
                                   "uncertified: verify.full_order false) | certified (estimated, the full order's "
                                   "mode count equal to the richest candidate's at every configuration)")
    certificate: dict = _value(doc="the mode count of -kf_verify auto's estimate (None: not tried): below_hz, "
                                   "certified, and per configuration (angles of interest, then midpoints) "
                                   "full_counts and rich_counts, the flexible modes below below_hz; count_source "
                                   "helper (counted beside the reduction) or in-process")
    floored_pairs: dict = _value(doc="per angle of interest (None: not verified), the [output, input] pairs whose "
                                     "error is measured against a floor, not their own peak: largest_pair (peak "
                                     "below 1e-4 of the largest pair's), own_total (elastic peak below 1e-6 of "
                                     "their own total peak)")
    moments_matched: int = _value()
    multi_moments_matched: int = _value()
    reference_check: ReferenceCheck = _record(ReferenceCheck)


@dataclass(kw_only=True)
class ChosenModel(Record):
    """The model the reducer chose: its family, size, expansion and errors at the angles of interest."""
    method: str = _value()
    moments: int = _value()
    dofs_per_body: dict = _value({})
    dofs: int = _value()
    system_dofs: dict = _value({}, doc="{label: reassembled dofs}")
    expansion_angles_deg: list = _value()
    kept_clusters: object = _value(doc="int, 'per body', or None (every cluster, or not known)")
    kept_modes: list = _value(doc="1-based Krylov modes kept (single-angle), None for multi-angle")
    frf_error: dict = _value({}, doc="{label: e} the verdict's measure")
    frf_pointwise_error: dict = _value({}, doc="{label: e} information")
    worst_error: float = _value()
    worst_where: str = _value(doc="an angle label or a midpoint's label")
    worst_kind: str = _value(doc="angle | midpoint")
    expansion_points_hz: list = _value([])
    expansion_point_factorizations: int = _value()
    compressed_from_dofs: int = _value(doc="-kf_compress: reduced dofs before the compression (None: not run)")
    compressed_to_dofs: int = _value(doc="-kf_compress: reduced dofs after it (equal: no direction could go); a tied "
                                         "model's: its body dofs less its ties")
    compressed_tied: bool = _value(doc="-kf_compress: true when the model kept is the one tied across its bodies (one "
                                       "SVD of the whole response), false body by body, None: not run")
    static_exact: bool = _value(True, doc="L^0 kept as the search made it (false: compressed with -kf_static_exact "
                                          "false, L^0 approximated: see static_moment_error)")
    static_moment_error: dict = _value({}, doc="{label: ||L^0_full - L^0_red|| / ||L^0_full||}, measured")


@dataclass(kw_only=True)
class Midpoint(Record):
    """A configuration between two angles of interest where the chosen model's error is measured too."""
    angles_deg: list = _value([])
    label: str = _value()
    frf_error: float = _value()


@dataclass(kw_only=True)
class Candidate(Record):
    """One model the search evaluated (C search_table)."""
    family: str = _value(doc="single-angle | multi-angle")
    moments: int = _value()
    kept_clusters: object = _value(doc="int, 'per body', or None (all)")
    expansion_angles: int = _value()
    reduced_dofs: int = _value(doc="sum over bodies")
    max_system_dofs: int = _value()
    error: float = _value()
    variant: str = _value(doc="split | tied | tied, no static correction (-kf_shared_directions) | compressed body by "
                              "body | compressed, tied across the bodies (-kf_compress: the chosen model compressed, "
                              "rows after the search's), or None (not known)")


@dataclass(kw_only=True)
class ExpansionPointCandidate(Record):
    """One candidate of the in-band expansion-point search (C shift_search)."""
    moments: int = _value()
    points: int = _value()
    reduced_dofs: int = _value()
    system_dofs: int = _value()
    error: float = _value()
    factorizations_spent: int = _value()


@dataclass(kw_only=True)
class ExpansionPointSearch(Record):
    """The in-band expansion-point search (-kf_max_factorizations)."""
    factorizations_spent: int = _value()
    rows: list = _records(ExpansionPointCandidate)


@dataclass(kw_only=True)
class HankelBound(Record):
    """The Hankel singular values of the full system at one configuration: the lower bound on any model's error."""
    order: int = _value(doc="first-order states the target needs")
    singular_values: list = _value([])
    scale: float = _value()
    chosen_states: int = _value()
    bound_at_chosen: float = _value()


@dataclass(kw_only=True)
class MultiAngle(Record):
    """The multi-angle model, when one was built (every part optional)."""
    system_dofs: dict = _value()
    dofs_per_body: dict = _value()
    moment_ratios: dict = _value()
    frf_error: dict = _value()
    frf_pointwise_error: dict = _value()
    frf_max_rel_error: dict = _value(doc="= frf_error, under the name scripts of version 1 read")
    reduction_angles_deg: list = _value()
    moment_error: dict = _value()
    max_moment_ratio_deviation: dict = _value()
    max_moment_error: dict = _value()


@dataclass(kw_only=True)
class ModelCheck(Record):
    """kryflex check's findings on the scene (the reduce command adds them)."""
    facts: dict = _value({})
    findings: list = _value([])


# =============================================================================================== the summary

@dataclass(frozen=True)
class Configuration:
    """One angle of interest's results gathered from the summary's blocks (a view: not a key of summary.json)."""
    label: str
    angles_deg: list
    full_frequencies_hz: list
    reduced_frequencies_hz: list
    krylov: KrylovModes
    frf: FrequencyResponse
    frf_error: float            # the chosen model's error here (the verdict's measure)
    system_dofs: int            # the chosen model's reassembled dofs here


@dataclass(kw_only=True)
class Summary(Record):
    """The results of one reduction (summary.json): the scene's names, the settings, the full and reduced systems at
    the angles of interest, the verdict on the chosen model, the search and the solver's performance."""
    kryflex_version: str = _value(doc="the kryflex that wrote it")
    summary_version: int = _value(SUMMARY_VERSION, doc="1: no such key; 2: the typed summary")
    scene: str = _value(doc="the scene's name")
    scene_file: str = _value()
    inputs: list = _value([], doc="input names")
    outputs: list = _value([], doc="output names")
    joints: list = _value(doc="revolute joint names")
    angles_deg: list = _value(doc="[[deg per revolute joint] per angle of interest] ([[]]: no revolute joint)")
    angle_labels: list = _value([], doc="one label per angle of interest: file names and table headers")
    band_hz: list = _value()
    damping: float = _value()
    damping_model: dict = _value()
    damping_matrices: list = _value()
    output_quantities: list = _value()
    accuracy: float = _value(doc="the accuracy target")
    frf_floor_db: float = _value()
    settings: Settings = _record(Settings)
    full: FullOrder = _record(FullOrder)
    krylov: dict = _by_label(KrylovModes, doc="{label: KrylovModes}")
    reduction_label: str = _value(doc="the label of alpha_G, the single-angle model's expansion angle")
    reduction_rule: str = _value(doc="why this alpha_G")
    kept_modes: list = _value([], doc="1-based Krylov modes kept at alpha_G")
    static_correction_modes: int = _value()
    static_correction_frequency_hz: list = _value()
    reduced: ReducedOrder = _record(ReducedOrder)
    frf: dict = _by_label(FrequencyResponse, doc="{label: FrequencyResponse}")
    dominant_modes: dict = _value(doc="{label: 0-based indices into full.frequencies_hz[label]}")
    dominant_freq_error: dict = _value()
    timings_s: dict = _value(doc="{stage: seconds}")
    performance: Performance = _record(Performance)
    notes: list = _value([])
    verdict: Verdict = _flat(Verdict)
    chosen: ChosenModel = _record(ChosenModel)
    expansion_point_search: ExpansionPointSearch = _record(ExpansionPointSearch)
    midpoints: list = _records(Midpoint)
    search: list = _records(Candidate, doc="every model the search evaluated")
    search_chosen: int = _value(doc="the index in search of the chosen model, None when not there")
    hankel: dict = _by_label(HankelBound)
    multi_angle: MultiAngle = _record(MultiAngle)
    model_check: ModelCheck = _record(ModelCheck)
    paper: dict = _value(doc="the paper's tables beside kryflex's (scenes with paper: lee; kryflex/paper.py)")

    @classmethod
    def from_json(cls, data):
        """The summary of a dict as json.load gives it, of any summary version up to SUMMARY_VERSION."""
        if not isinstance(data, dict):
            raise SummaryError("a summary is a JSON object, got a %s" % type(data).__name__)
        version = data.get("summary_version", 1)
        if not isinstance(version, int) or not 1 <= version <= SUMMARY_VERSION:
            raise SummaryError("summary_version %r: this kryflex reads versions 1 to %d; read it with the kryflex that "
                               "wrote it (kryflex_version %s) or a newer one"
                               % (version, SUMMARY_VERSION, data.get("kryflex_version", "?")))
        summary = cls._decode(data, "summary")
        summary.summary_version = version
        return summary

    def to_json(self):
        """The dict summary.json holds, at the current version (a version-1 summary's keys and values, plus
        summary_version)."""
        out = super().to_json()
        out["summary_version"] = SUMMARY_VERSION
        return out

    @classmethod
    def load(cls, path):
        """The summary in a summary.json file (or in the summary.json of a results folder)."""
        import os
        if os.path.isdir(path):
            path = os.path.join(path, "summary.json")
        try:
            with open(path, encoding="utf-8") as f:
                data = json.load(f)
        except FileNotFoundError:
            raise SummaryError("%s: no such file: give the summary.json 'kryflex reduce' wrote, or its folder"
                               % path) from None
        except ValueError as e:
            raise SummaryError("%s: not JSON (%s): a summary.json written by 'kryflex reduce' expected" % (path, e)) \
                from None
        try:
            return cls.from_json(data)
        except SummaryError as e:
            raise SummaryError("%s: %s" % (path, e)) from None

    def dumps(self):
        """summary.json's text: objects indented one space per level, a list of numbers (or of lists of them) on one
        line (JSON's C encoder; the pure-Python one that indents every number took 0.8 s of a 57k-dof reduction's
        summary)."""
        return _json_text(self.to_json()) + "\n"

    # ------------------------------------------------------------------ views

    @property
    def labels(self):
        return list(self.angle_labels)

    @property
    def chosen_candidate(self):
        """The search's row of the chosen model, None when the search did not evaluate it."""
        k = self.search_chosen
        return self.search[k] if k is not None and 0 <= k < len(self.search) else None

    def configuration(self, label):
        """One angle of interest's results (a Configuration), by its label."""
        if label not in self.angle_labels:
            raise KeyError("angle label %r: the summary's labels are %s" % (label, ", ".join(self.angle_labels)))
        k = self.angle_labels.index(label)
        chosen = self.chosen or ChosenModel()
        frf = self.frf.get(label)
        error = chosen.frf_error.get(label) if chosen.frf_error else (frf.frf_error if frf else None)
        return Configuration(
            label=label, angles_deg=self.angles_deg[k] if self.angles_deg else None,
            full_frequencies_hz=(self.full.frequencies_hz if self.full else {}).get(label),
            reduced_frequencies_hz=(self.reduced.frequencies_hz if self.reduced else {}).get(label),
            krylov=self.krylov.get(label), frf=frf, frf_error=error,
            system_dofs=(chosen.system_dofs or {}).get(label))

    @property
    def configurations(self):
        return [self.configuration(label) for label in self.angle_labels]

    # ------------------------------------------------------------------ the dict of version 1, for old scripts

    def _json_value(self, key):
        for f in self.json_fields():
            codec = f.metadata["codec"]
            if isinstance(codec, _Flat):
                sub = getattr(self, f.name)
                if key in codec.cls.json_keys():
                    return sub._json_value_of(key)
            elif f.name == key:
                if f.name in self.absent and self._is_default(f, getattr(self, key)):
                    break
                return SUMMARY_VERSION if key == "summary_version" else codec.encode(getattr(self, key))
        if key in self.extra:
            return self.extra[key]
        raise KeyError(key)

    def __getitem__(self, key):
        """summary["key"]: the key's JSON value, as the summary dict of version 1 gave it (deprecated: use the
        attributes, or to_json() for the whole dict)."""
        warnings.warn("Reduction.summary is a kryflex.results.Summary: read summary.%s (typed) or "
                      "summary.to_json()[%r] instead of summary[%r]" % (key, key, key), DeprecationWarning,
                      stacklevel=2)
        return self._json_value(key)

    def get(self, key, default=None):
        """summary.get("key", default) as on the dict of version 1 (deprecated, as summary["key"])."""
        warnings.warn("Reduction.summary is a kryflex.results.Summary: read summary.%s (typed) instead of "
                      "summary.get(%r)" % (key, key), DeprecationWarning, stacklevel=2)
        try:
            return self._json_value(key)
        except KeyError:
            return default

    def __contains__(self, key):
        try:
            self._json_value(key)
        except KeyError:
            return False
        return True

