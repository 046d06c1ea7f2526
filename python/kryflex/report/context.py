"""Facts derived from a summary that several report sections and figures share."""
from ..io.scene_schema import NO_JOINT_LABEL
from .formatting import MAX_MOMENT_ENTRIES_SHOWN, pair_name
from ..results import ChosenModel, Summary, SummaryError
from .schema import ReportError


def as_summary(summary):
    """A Summary from a Summary or its JSON dict (ReportError naming the key when the dict cannot be read)."""
    if isinstance(summary, Summary):
        return summary
    try:
        return Summary.from_json(summary)
    except SummaryError as e:
        raise ReportError(str(e)) from None


class _Context:
    """Derived facts used by several sections (labels, headers, displayed I/O entries). summary: a
    kryflex.results.Summary (typed: self.summary) or its JSON dict; self.s is the JSON dict, for the tables that
    walk its nested per-label blocks."""

    def __init__(self, summary):
        summary = as_summary(summary)
        self.summary = summary
        self.s = summary.to_json()
        self.labels = list(summary.angle_labels)
        self.label_g = summary.reduction_label
        self.outputs = list(summary.outputs)
        self.inputs = list(summary.inputs)
        self.rigid = summary.full.rigid_modes if summary.full is not None else None
        self.entries = [(o, i) for o in range(len(self.outputs)) for i in range(len(self.inputs))]
        self.dominant_entry = self._dominant_entry()
        self.shown_entries = self.entries if len(self.entries) <= MAX_MOMENT_ENTRIES_SHOWN else [self.dominant_entry]
        settings = summary.settings
        self.model_name = (summary.verdict.chosen_method or (settings.method if settings is not None else None)
                           or "single-angle") + " model"
        # a summary without a chosen-model block (written before it had one): every key of the block absent
        self.chosen = summary.chosen or ChosenModel(absent=frozenset(ChosenModel.json_keys()))

    def chosen_error(self, label, name="frf_error"):
        """The chosen model's error at an angle of interest: name "frf_error" (relative H-inf per pair, the verdict's
        measure) or "frf_pointwise_error" (information). Summaries without a chosen-model block give the
        single-angle model's per-angle value, the only one they hold."""
        if name not in self.chosen.absent:
            return getattr(self.chosen, name).get(label)
        frf = self.summary.frf.get(label)
        if frf is None:
            return None
        value = getattr(frf, name)
        return frf.max_rel_error if value is None and name == "frf_error" else value

    def _dominant_entry(self):
        """The (output, input) entry with the largest static gain |L^0| summed over configurations."""
        weight = {e: 0.0 for e in self.entries}
        for label in self.labels:
            moments = self.summary.full.moments[label]
            if moments:
                for (o, i) in self.entries:
                    weight[(o, i)] += abs(moments[0][o][i])
        return max(self.entries, key=lambda e: weight[e])

    def no_joint(self, label):
        """True for the one configuration of a scene without revolute joints: the structure, which has no angle."""
        angles = self.summary.angles_deg
        if angles is not None and label in self.labels:
            values = angles[self.labels.index(label)]
            return isinstance(values, (list, tuple)) and len(values) == 0
        return label == NO_JOINT_LABEL

    def angle(self, label):
        """'α = 15°' from angles_deg when available (several joints: 'α = (0°, 30°)'), else from the label; 'the
        structure' without revolute joints."""
        if self.no_joint(label):
            return "the structure"
        angles = self.summary.angles_deg
        if angles is not None:
            values = angles[self.labels.index(label)]
            values = values if isinstance(values, (list, tuple)) else [values]
            if len(values) == 1:
                return f"α = {values[0]:g}°"
            return "α = (" + ", ".join(f"{v:g}°" for v in values) + ")"
        return f"α = {label}°"

    @property
    def single(self):
        """True for a scene without revolute joints: its one configuration is the structure, there is no α_G."""
        return self.no_joint(self.label_g)

    def g_mark(self, label):
        """' (α_G)' after the reduction configuration's angle, '' for any other and for a structure without joints."""
        return " (α_G)" if label == self.label_g and not self.single else ""

    def at_g(self):
        """'at α_G (α = 30°)', or 'of the structure' without revolute joints."""
        return "of the structure" if self.single else f"at α_G ({self.angle(self.label_g)})"

    def short_angle(self, label):
        if self.no_joint(label):
            return "the structure"
        text = self.angle(label)[4:]
        return text + " (α_G)" if label == self.label_g else text

    def entry_name(self, entry):
        o, i = entry
        return pair_name(self.outputs[o], self.inputs[i])

    def mode_number(self, flex_index):
        """Paper-style mode number of the flex_index-th (0-based) flexible mode: rigid modes come first."""
        return flex_index + 1 + (self.rigid or 0)
