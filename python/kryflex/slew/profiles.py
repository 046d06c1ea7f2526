"""Angle histories of a slew and the motor torque that drives them.

Every profile is alpha(t) = alpha0 + amplitude * s(t) on every revolute joint together (amplitude per joint), with
s smooth (zero jerk at the ends, so the torque starts from zero and the start at rest is consistent), and the drive
torque u(t) = s''(t) / max|s''| (unit peak: the models are linear, so the relative errors do not depend on the torque
scale; u is the torque J alpha'' that gives the slew to a rigid mechanism of inertia J, up to that scale).

  slew    rest to rest in duration T, cycloidal: s = t/T - sin(2 pi t/T) / (2 pi); peak rate 2 A / T
  spinup  rest to the constant rate A / T in T (s' a cycloidal ramp), then spinning on at that rate (alpha keeps
          growing: the ties turn through every angle)

The held profiles keep every angle at alpha0 (the only configuration of a structure without revolute joints) and
drive the inputs with a force history of peak `force` instead (the response of the structure at rest to a load):

  step    u = force * s(t): the cycloidal ramp from 0 to force in the rise time T, then held
  pulse   u = force * (1 - cos(2 pi t/T)) / 2 on [0, T], then 0 (a Hann pulse of length T)

Both start from zero with zero slope, so the start at rest is consistent.
"""
import numpy as np

SLEWS = ("slew", "spinup")
HELD = ("step", "pulse")
PROFILES = SLEWS + HELD


class Profile:
    """kind: slew, spinup, step or pulse; duration T (s); amplitude (radians, one per revolute joint; not used by the
    held profiles); alpha0 (radians); force: the peak of a held profile's input history."""

    def __init__(self, kind, duration, amplitude, alpha0, force=1.0):
        if kind not in PROFILES:
            raise ValueError("unknown slew profile %r: use one of %s" % (kind, ", ".join(PROFILES)))
        if not duration > 0:
            raise ValueError("the slew duration must be positive, got %g s" % duration)
        self.kind, self.T, self.force = kind, float(duration), float(force)
        self.held = kind in HELD
        self.amplitude = np.atleast_1d(np.asarray(amplitude, float))
        if self.held:
            self.amplitude = 0.0 * self.amplitude
        self.alpha0 = np.atleast_1d(np.asarray(alpha0, float))

    def s(self, t):
        t = np.asarray(t, float)
        T, w = self.T, 2 * np.pi / self.T
        if self.kind in ("slew", "step"):
            tc = np.clip(t, 0, T)
            return tc / T - np.sin(w * tc) / (2 * np.pi)
        # spinup: s' = (t/T - sin(w t) / (2 pi)) / T on [0, T] (a cycloidal ramp to the rate 1/T), then 1/T
        tc = np.clip(t, 0, T)
        return (tc ** 2 / (2 * T) + (np.cos(w * tc) - 1) / (2 * np.pi * w)) / T + np.maximum(t - T, 0) / T

    def s2(self, t):
        """s'' (1/s^2)."""
        t = np.asarray(t, float)
        T, w = self.T, 2 * np.pi / self.T
        inside = (t >= 0) & (t <= T)
        if self.kind == "slew":
            return np.where(inside, w * np.sin(w * t) / T, 0.0)
        return np.where(inside, (1 - np.cos(w * t)) / T ** 2, 0.0)

    def angles(self, t):
        """alpha(t): (len(t), revolute joints), radians."""
        return self.alpha0[None, :] + np.asarray(self.s(t))[..., None] * self.amplitude[None, :]

    def torque(self, t):
        """u(t) = s''(t) / max|s''|: unit peak; a held profile's force history (see the module doc)."""
        if self.kind == "step":
            return self.force * self.s(t)
        if self.kind == "pulse":
            t = np.asarray(t, float)
            inside = (t >= 0) & (t <= self.T)
            return np.where(inside, self.force * 0.5 * (1 - np.cos(2 * np.pi * t / self.T)), 0.0)
        peak = 2 * np.pi / self.T ** 2 if self.kind == "slew" else 2 / self.T ** 2
        return self.s2(t) / peak

    @property
    def peak_rate(self):
        """The peak angular rate of the largest joint amplitude (rad/s); 0 for a held profile."""
        if self.held:
            return 0.0
        a = float(np.max(np.abs(self.amplitude))) if self.amplitude.size else 0.0
        return (2 * a / self.T) if self.kind == "slew" else a / self.T
