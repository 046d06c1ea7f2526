"""Facts derived from a summary that several report sections and figures share."""
from ..io.scene_schema import NO_JOINT_LABEL
from .formatting import MAX_MOMENT_ENTRIES_SHOWN
from .schema import _get


class _Context:
    """Derived facts used by several sections (labels, headers, displayed I/O entries)."""

    def __init__(self, summary):
        self.s = summary
        self.labels = list(summary["angle_labels"])
        self.label_g = summary["reduction_label"]
        self.outputs = list(summary["outputs"])
        self.inputs = list(summary["inputs"])
        self.rigid = _get(summary, ("full", "rigid_modes"))
        self.entries = [(o, i) for o in range(len(self.outputs)) for i in range(len(self.inputs))]
        self.dominant_entry = self._dominant_entry()
        self.shown_entries = self.entries if len(self.entries) <= MAX_MOMENT_ENTRIES_SHOWN else [self.dominant_entry]
        self.model_name = (summary.get("chosen_method") or _get(summary, ("settings", "method"))
                           or "single-angle") + " model"
        self.chosen = summary.get("chosen") or {}

    def chosen_error(self, label, name="frf_error"):
        """The chosen model's error at an angle of interest: name "frf_error" (relative H-inf per pair, the verdict's
        measure) or "frf_pointwise_error" (information). Summaries without a "chosen" block (written before issue
        11) give the single-angle model's per-angle value, the only one they hold."""
        per = self.chosen.get(name)
        if per is not None:
            return per.get(label)
        frf = (self.s.get("frf") or {}).get(label) or {}
        return frf.get(name, frf.get("max_rel_error") if name == "frf_error" else None)

    def _dominant_entry(self):
        """The (output, input) entry with the largest static gain |L^0| summed over configurations."""
        weight = {e: 0.0 for e in self.entries}
        for label in self.labels:
            moments = self.s["full"]["moments"][label]
            if moments:
                for (o, i) in self.entries:
                    weight[(o, i)] += abs(moments[0][o][i])
        return max(self.entries, key=lambda e: weight[e])

    def no_joint(self, label):
        """True for the one configuration of a scene without revolute joints: the structure, which has no angle."""
        angles = self.s.get("angles_deg")
        if angles is not None and label in self.labels:
            values = angles[self.labels.index(label)]
            return isinstance(values, (list, tuple)) and len(values) == 0
        return label == NO_JOINT_LABEL

    def angle(self, label):
        """'α = 15°' from angles_deg when available (several joints: 'α = (0°, 30°)'), else from the label; 'the
        structure' without revolute joints."""
        if self.no_joint(label):
            return "the structure"
        angles = self.s.get("angles_deg")
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
        return f"{self.outputs[o]} ← {self.inputs[i]}"

    def mode_number(self, flex_index):
        """Paper-style mode number of the flex_index-th (0-based) flexible mode: rigid modes come first."""
        return flex_index + 1 + (self.rigid or 0)
