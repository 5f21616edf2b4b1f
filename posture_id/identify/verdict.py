"""Should this answer be trusted? One verdict on every identification.

Three questions, each answered from the recording and the result alone (no truth):

1. **Does the identified model explain the recording as well as its noise allows?**
   (:func:`~posture_id.identify.noise_check.noise_check`: the re-simulation's residual
   against the noise estimated from the recording, stimulus-locked for a periodic
   stimulus, raw otherwise; or, if not, is it close anyway: at most
   :data:`~posture_id.identify.noise_check.CLOSE_ENOUGH` of the recorded sway.)
2. **Did least squares stop on a bound of its search?** (:attr:`FitResult.on_bounds
   <posture_id.fitting.result.FitResult.on_bounds>`, named; Kp, Kd or a passive term on a
   bound makes the answer doubtful, Ki or a delay is named as what the recording leaves
   open: :data:`DOUBTFUL_ON_BOUND`.)
3. **Is the recording inside what the method was trained or calibrated on?** The CNN:
   its body, its noise calibration, and sway that is mostly the stimulus's response (the
   bundled networks are trained on sensor noise alone, so a recording whose body sway is
   less than :data:`PEOPLE_LIKE_SHARE` stimulus-locked lies outside them). Least squares
   on the raw sway: the same share (below it the raw fit is fitting the subject's own
   sway).

and a fourth, from the recording alone:

4. **Could this body, under one controller, have made this recording at all?**
   (:mod:`posture_id.identify.mistakes`: a tilt of the wrong sign, a step in the angles,
   control that changes within the recording, a body whose time scale is not the
   subject's, inputs unlike anything the network was trained on.)

Three levels (:class:`TrustLevel`), because "wrong" and "imprecise" are different news:

- ``doubtful``: evidence that the answer is wrong: a residual beyond the recording's noise
  (and more than :data:`~posture_id.identify.noise_check.CLOSE_ENOUGH` of its locked
  sway; for least squares' answer, more than :data:`FITTED_NOISE_LIMIT` times the noise
  however close: a fit of the right model reaches the noise), Kp or Kd on a search
  bound, a recording outside what the method was trained on, a mistake found in the
  recording, or classes the network itself gives less than
  :data:`CLASSES_RIGHT_AT_LEAST` of being right together (the product over modules of
  its probability of the class it chose: a coin flip of a class is not imprecision, it
  is an even chance of a wrong answer). The verdict names the method or flags that suit
  the recording (:func:`suggestion`).
- ``imprecise``: nothing says the answer is wrong, but the recording cannot pin it: its
  noise alone leaves more than ``CLOSE_ENOUGH`` of the locked sway (no answer can be
  checked to 10 %), or a module's Kp, Kd or delay has an interval wider than ±10 % of its
  value (:data:`PINNED_FIELDS`, :data:`PINNED_TO`). The calibrated intervals give the
  precision; the verdict names what is not pinned.
- ``good``: the model explains the recording as well as its noise allows and the
  recording pins those parameters.

The rule and its measurement: docs/identify.md, "Trust".
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from posture_id.dec.parameters import TARGET_FIELDS
from posture_id.identify.method import Method
from posture_id.identify.noise_check import CLOSE_ENOUGH, NoiseCheck
from posture_id.models.protocol import TrustLevel
from posture_id.uncertainty.intervals import LABELS

__all__ = ["TrustVerdict", "TrustLevel", "PEOPLE_LIKE_SHARE", "PINNED_FIELDS", "PINNED_TO",
           "CLASSES_RIGHT_AT_LEAST", "UNSURE_CLASS", "NAMED_CLASS", "FITTED_NOISE_LIMIT",
           "suggestion", "unpinned_parameters", "class_doubts", "is_people_like"]

#: Body sway whose noise-corrected stimulus-locked share is below this is people-like:
#: the subject's own sway dominates (docs/real_recordings.md: 10–40 % in people).
PEOPLE_LIKE_SHARE = 0.6


def is_people_like(locked_share: float | None) -> bool:
    """Whether body sway of this stimulus-locked share (None: unknown) is people-like."""
    return locked_share is not None and locked_share < PEOPLE_LIKE_SHARE

#: A parameter on a search bound makes the answer doubtful when it is one of these: the
#: sway determines them well, so a bound there cut the answer short. Ki and the delay are
#: the parameters a recording determines least (docs/uncertainty.md); on a bound they are
#: named, as what the recording leaves open, without doubting the rest.
DOUBTFUL_ON_BOUND = ("kp", "kd", "kpas", "bpas")

#: The parameters a ``good`` answer pins: the gains and the delay the sway determines
#: (Ki, the parameter posture sway determines least, is named by the intervals' own words
#: and does not lower the level: docs/uncertainty.md).
PINNED_FIELDS = ("kp", "kd", "delay_s")
#: Pinned: the interval's half-width is at most this share of the value.
PINNED_TO = 0.10

#: The network is said to be unsure of a class when P(C = +1) is inside this band: the
#: hybrid then lets least squares decide it (``identify.core._refine``).
UNSURE_CLASS = (0.05, 0.95)
#: A class whose P(C = +1) is inside this band is named as what the recording does not pin
#: (the answer imprecise, naming the module's class): a chance of 1 in 50 or more that the
#: class is wrong. The network's probabilities are calibrated on noise it never saw too
#: (docs/uncertainty.md, "Class probabilities on noise never seen"); at (0.05, 0.95) the
#: verdict named or doubted 18 of the 23 wrong classes of the leave-one-family-out answers,
#: at (0.02, 0.98) 20 (benchmarks/class_calibration.py; docs/identify.md, "Trust").
NAMED_CLASS = (0.02, 0.98)
#: Below this probability that every class the network chose is right (the product of
#: max(P, 1 − P) over the modules), the answer is doubtful: more than one chance in five
#: that a controlled variable is wrong (docs/identify.md, "Trust", measured there).
CLASSES_RIGHT_AT_LEAST = 0.8
#: An answer of least squares (the fit, or ``auto``'s and the hybrid's refinement) that
#: leaves more than this many times the recording's noise is doubtful even when it is
#: within :data:`~posture_id.identify.noise_check.CLOSE_ENOUGH` of the sway: least squares
#: with the right model reaches the noise (the hybrid's right answers at 0.01° and 0.05°
#: of sensor noise: at most 1.26× it, docs/results/hybrid_rule), where the network's
#: answer on clean sway stays several times above it (its 3–6 % errors), so the network's
#: answer keeps the closeness allowance and least squares' does not
#: (docs/identify.md, "Trust").
FITTED_NOISE_LIMIT = 3.0


#: A residual (in units of the recording's noise) above which least squares' doubtful
#: answer is sent to the stimulus's timing rather than to a longer recording.
TIMING_RATIO = 2.0


#: What suits people-like sway (docs/real_recordings.md, docs/results/real_like.md).
LOCKED_FLAGS = "--method fit --locked --prior-sd 0.5"


@dataclass(frozen=True)
class TrustVerdict:
    """Whether an identification should be trusted, and why not.

    Attributes:
        noise: the residual against the recording's own noise, or None.
        on_bounds: parameters that least squares left on a bound of its search.
        outside: ways the recording lies outside what the method was trained or
            calibrated on (sentences).
        locked_share: the body sway's stimulus-locked share (noise-corrected), or None.
        suggestion: what to run instead when doubtful ("" otherwise).
        mistakes: what in the recording this body under one controller cannot have made
            (sentences, :mod:`posture_id.identify.mistakes`).
        unpinned: parameters whose interval is wider than ±:data:`PINNED_TO` of their
            value ("the hip's Kd"), of :data:`PINNED_FIELDS`, and classes the network is
            unsure of ("the hip's class (P(com) 0.62)").
        classes_doubted: why the network's classes are more likely wrong than
            :data:`CLASSES_RIGHT_AT_LEAST` allows (one sentence, :func:`class_doubts`),
            or "".
        fitted: the answer is least squares' (:data:`FITTED_NOISE_LIMIT`).
    """

    noise: NoiseCheck | None
    on_bounds: tuple[str, ...] = ()
    outside: tuple[str, ...] = ()
    locked_share: float | None = None
    suggestion: str = ""
    mistakes: tuple[str, ...] = ()
    unpinned: tuple[str, ...] = ()
    classes_doubted: str = ""
    fitted: bool = False

    @property
    def beyond_noise(self) -> bool:
        """The residual is larger than the recording's noise allows and more than
        :data:`CLOSE_ENOUGH` of the recorded sway (a model that falls included), or, for
        least squares' answer, more than :data:`FITTED_NOISE_LIMIT` times the noise."""
        noise = self.noise
        return noise is not None and not noise.consistent and (
            not noise.acceptable or self.fit_beyond_noise)

    @property
    def fit_beyond_noise(self) -> bool:
        """Least squares' answer leaves more than :data:`FITTED_NOISE_LIMIT` times the
        recording's noise (close to the sway or not)."""
        return self.fitted and self.noise is not None and self.noise.ratio > FITTED_NOISE_LIMIT

    @property
    def people_like(self) -> bool:
        """The body sway is people-like (:func:`is_people_like`)."""
        return is_people_like(self.locked_share)

    @property
    def not_close(self) -> bool:
        """The residual is more than :data:`CLOSE_ENOUGH` of the recorded sway, whether or
        not the recording's noise explains it (``auto``'s trigger for a refinement)."""
        return self.noise is not None and not self.noise.acceptable

    @property
    def reasons(self) -> tuple[str, ...]:
        """Why the answer is doubtful (empty when it is not)."""
        out = []
        if self.beyond_noise and self.noise.acceptable:  # close, but least squares' answer
            out.append(f"least squares leaves a {self.noise.sentence()}: more than "
                       f"{FITTED_NOISE_LIMIT:g}× the noise, where a fit of the right model "
                       "reaches it (is the body the subject's, the columns in order, or is the "
                       "fit in a local minimum?)")
        elif self.beyond_noise:
            out.append(f"the model leaves a {self.noise.sentence()}")
        if self.bounds_that_matter:
            out.append("on a search bound: " + ", ".join(self.bounds_that_matter))
        if self.classes_doubted:
            out.append(self.classes_doubted)
        return (*out, *self.outside, *self.mistakes)

    @property
    def imprecision(self) -> tuple[str, ...]:
        """Why the answer is imprecise (empty when it is not, or when it is doubtful)."""
        if self.reasons:
            return ()
        out = []
        noise = self.noise
        if noise is not None and not noise.acceptable:
            note = noise.weighting_note()
            out.append(
                f"its noise alone leaves about {100 * noise.noise_relative:.0f} % of the "
                f"recorded {noise.basis} sway, too much to check an answer to "
                f"{100 * CLOSE_ENOUGH:g} % (the model's residual: {noise.ratio:.2f}× the "
                f"noise, {100 * noise.relative:.1f} % of the sway"
                + (f"; {note}" if note else "") + ")"
                if math.isfinite(noise.noise_relative) else
                f"the model leaves a {noise.sentence()}")
        if self.unpinned:
            out.append(f"the recording does not pin {_listed(self.unpinned)} (to "
                       f"±{100 * PINNED_TO:g} %)")
        return tuple(out)

    @property
    def level(self) -> TrustLevel:
        if self.reasons:
            return TrustLevel.DOUBTFUL
        return TrustLevel.IMPRECISE if self.imprecision else TrustLevel.GOOD

    @property
    def bounds_that_matter(self) -> tuple[str, ...]:
        """The bound hits that make the answer doubtful (:data:`DOUBTFUL_ON_BOUND`)."""
        return tuple(b for b in self.on_bounds if b.split()[1] in DOUBTFUL_ON_BOUND)

    @property
    def doubtful(self) -> bool:
        """True only for :attr:`TrustLevel.DOUBTFUL`."""
        return bool(self.reasons)

    def open_bounds(self) -> str:
        """The clause naming what least squares left on a bound that does not make the
        answer doubtful (Ki, a delay), or "": the value is the search's edge, not the
        subject's (a lumped delay of 0 s is no one's delay)."""
        others = [b for b in self.on_bounds if b not in self.bounds_that_matter]
        if not others:
            return ""
        zero_delay = any(b.split()[1] == "delay_s" and "lower" in b for b in others)
        return ("on a search bound, which the recording leaves open: " + ", ".join(others)
                + (" (a delay of 0 s is the search's edge, not the subject's delay)"
                   if zero_delay else ""))

    def line(self) -> str:
        """The one line a user reads."""
        bounds = self.open_bounds()
        if self.level is TrustLevel.IMPRECISE:
            return ("trust: imprecise: " + "; ".join(
                (*self.imprecision, *([bounds] if bounds else ())))
                + ": nothing says the answer is wrong; its intervals give the precision")
        if not self.doubtful:
            noise = self.noise
            if noise is None:
                what = ""
            elif noise.consistent:
                what = (f": the model explains the recording as well as its noise allows "
                        f"({noise.basis} residual {noise.ratio:.2f}× the noise)")
            else:
                what = (f": the model is close ({noise.basis} residual "
                        f"{100 * noise.relative:.1f} % of the recorded body sway), though "
                        f"not within the noise ({noise.ratio:.2f}× it)")
            if bounds:
                what += f"; {bounds}"
            return f"trust: good{what}"
        line = "trust: DOUBTFUL: " + "; ".join((*self.reasons, *([bounds] if bounds else ())))
        return line + (f"; try {self.suggestion}" if self.suggestion else "")

    def benchmark_fields(self) -> dict:
        """The flat fields a benchmark row keeps of the verdict (JSON-ready): doubtful,
        trust_reasons, noise_ratio, relative_residual, noise_relative."""
        noise = self.noise

        def number(x: float | None) -> float | None:
            return None if x is None or not math.isfinite(x) else float(x)

        return {"doubtful": self.doubtful, "trust_level": self.level.value,
                "trust_reasons": list(self.reasons),
                "noise_ratio": None if noise is None else number(noise.ratio),
                "relative_residual": None if noise is None else number(noise.relative),
                "noise_relative": None if noise is None else number(noise.noise_relative)}

    def to_dict(self) -> dict:
        return {"level": self.level.value, "doubtful": self.doubtful,
                "reasons": list(self.reasons), "imprecise": list(self.imprecision),
                "suggestion": self.suggestion or None, "mistakes": list(self.mistakes),
                "unpinned": list(self.unpinned),
                "classes_doubted": self.classes_doubted or None,
                "noise_check": None if self.noise is None else self.noise.to_dict(),
                "on_bounds": list(self.on_bounds), "outside": list(self.outside),
                "locked_share": self.locked_share, "fitted": self.fitted}


def suggestion(method: Method, locked: bool, locked_share: float | None,
               on_bounds: tuple[str, ...], noise: NoiseCheck | None,
               prior: bool = False, network_reads_people_like: bool = False,
               whole_cycles: bool = True, period_s: float | None = None,
               offset_searched: bool = False) -> str:
    """What suits a recording whose answer is doubtful, by the documented rule:

    - people-like sway (locked share below :data:`PEOPLE_LIKE_SHARE`) identified without
      ``--locked``, other than by a network trained on it (the universal model):
      :data:`LOCKED_FLAGS`;
    - least squares on a recording whose noise alone leaves more than
      :data:`~posture_id.identify.noise_check.CLOSE_ENOUGH` of the locked sway: a longer
      recording (nothing fitted to it can be checked);
    - the CNN alone: ``--method hybrid`` (least squares from its answer), with
      ``--locked`` when its answer explains such a noisy recording as well as its noise
      allows (``auto``'s rule); on a recording of one cycle, whose locked share cannot be
      measured, such an answer gets the longer recording (least squares did worse than
      the network there on motor-noisy sway: ``auto`` keeps it), and ``--method hybrid``
      for sway without motor noise;
    - least squares on a bound: for a locked fit without a prior, ``--prior-sd 0.5`` (a
      noisy recording leaves some parameters free to run to a bound; the prior holds
      them); otherwise a wider ``--gain-range`` / ``--delay-range`` (and the locked fit
      with the prior for a noisy recording);
    - least squares from the defaults left more than the noise: ``--method hybrid`` (a
      start from the CNN's answer, away from the local minimum);
    - the hybrid or a locked fit left more than the noise: ``--locked --max-offset-s 1
      --prior-sd 0.5`` (a stimulus that is not where the lab's clock says, and the prior).

    And least squares that leaves more than :data:`TIMING_RATIO` times the
    noise on a periodic tilt (``period_s``) without having searched the stimulus's timing
    (``offset_searched``): ``--locked --max-offset-s`` a quarter cycle (a longer recording
    averages noise away, not a residual that large: a tilt column, or a named onset, off
    the sway's clock leaves one; beside a bound's suggestion when one is on a bound).

    Without ``whole_cycles`` (a tilt that is not periodic, or less than one whole cycle of
    it) neither the network, nor the hybrid, nor the locked fit can read the recording:
    what would need them suggests a recording they can read instead.
    """
    if not whole_cycles and method is Method.FIT:
        if any(b.split()[1] in DOUBTFUL_ON_BOUND for b in on_bounds):
            return "a wider --gain-range MIN MAX / --delay-range MIN MAX"
        if noise is not None and not noise.acceptable:
            return ("a recording of at least one whole cycle of a periodic tilt (a PRTS): "
                    "the network, the hybrid and the locked fit read only those")
        return ""
    people_like = is_people_like(locked_share)
    if people_like and not locked and not (method is Method.CNN and network_reads_people_like):
        return LOCKED_FLAGS
    timing = (period_s is not None and method is not Method.CNN and not offset_searched
              and noise is not None and not noise.acceptable and noise.ratio > TIMING_RATIO)
    timing_flags = "" if not timing else (f"--locked --max-offset-s {period_s / 4:.3g}"
                                          + ("" if prior else " --prior-sd 0.5"))
    timing_why = "" if not timing else (f"the stimulus's timing: {noise.ratio:.1f}× the "
                                        "noise is more than a longer recording would "
                                        "average away")
    # the network's answer on one cycle (no locked share: the network reads whole cycles
    # of a periodic tilt): least squares did worse there on motor-noisy sway
    if (noise is not None and not noise.acceptable and noise.noise_relative > CLOSE_ENOUGH
            and not timing
            and (method is not Method.CNN or (locked_share is None and noise.unchecked))):
        return ("a longer recording (more stimulus cycles to average): its noise alone "
                f"leaves {100 * noise.noise_relative:.0f} % of the locked sway, so no answer "
                f"can be checked to {100 * CLOSE_ENOUGH:g} %"
                + ("; for sway without motor noise (a robot's), --method hybrid"
                   if method is Method.CNN else ""))
    if method is Method.CNN:
        unchecked = noise is not None and noise.unchecked
        return "--method hybrid" + (" --locked --prior-sd 0.5" if people_like
                                    else " --locked" if unchecked else "")
    if any(b.split()[1] in DOUBTFUL_ON_BOUND for b in on_bounds):
        timed = "" if not timing else (f"; or, if the stimulus's timing is off "
                                       f"({noise.ratio:.1f}× the noise), {timing_flags}")
        if locked and not prior:
            return "--prior-sd 0.5 (or a wider --gain-range / --delay-range)" + timed
        return ("a wider --gain-range MIN MAX / --delay-range MIN MAX"
                + ("" if locked else ", or --locked --prior-sd 0.5 for a noisy recording")
                + timed)
    if timing:
        return f"{timing_flags} ({timing_why})"
    if noise is not None and not noise.acceptable:
        if method is Method.FIT and not locked:
            return "--method hybrid"
        return "--locked --max-offset-s 1" + ("" if prior else " --prior-sd 0.5")
    return ""


def class_doubts(joints: tuple[str, ...], probability_com) -> tuple[tuple[str, ...], str]:
    """What the network's class probabilities ``probability_com`` (N,) P(C = +1, COM) of
    ``joints`` say of its answer: the classes it is unsure of (:data:`NAMED_CLASS`),
    named as unpinned ("the hip's class (P(com) 0.62)"), and, when the chance that every
    chosen class is right is below :data:`CLASSES_RIGHT_AT_LEAST`, the sentence that
    makes the answer doubtful ("" otherwise)."""
    p = np.asarray(probability_com, dtype=float)
    low, high = NAMED_CLASS
    unsure = tuple(f"the {j}'s class (P(com) {q:.2f})" for j, q in zip(joints, p, strict=True)
                   if low < q < high)
    right = float(np.prod(np.maximum(p, 1 - p)))
    if right >= CLASSES_RIGHT_AT_LEAST:
        return unsure, ""
    return unsure, (f"the network cannot tell {_listed(unsure)}: by its own probabilities "
                    f"its classes are all right only {100 * right:.0f} % of the time "
                    f"(a recording that decides them: more cycles or a larger tilt)")


def _listed(names: tuple[str, ...]) -> str:
    return names[0] if len(names) == 1 else ", ".join(names[:-1]) + " and " + names[-1]


def unpinned_parameters(intervals, estimate_si: np.ndarray) -> tuple[str, ...]:
    """The :data:`PINNED_FIELDS` whose interval's half-width is more than
    :data:`PINNED_TO` of the value ("the hip's Kd"), from a
    :class:`~posture_id.uncertainty.intervals.ParameterIntervals` (None: none) and the
    answer's values ``estimate_si`` (N, 4), SI units."""
    if intervals is None:
        return ()
    half = (intervals.upper_si - intervals.lower_si) / 2
    with np.errstate(invalid="ignore"):
        wide = ~(half <= PINNED_TO * np.abs(np.asarray(estimate_si, dtype=float)))
    out = []
    for i, joint in enumerate(intervals.joints):
        names = [LABELS[f] for k, f in enumerate(TARGET_FIELDS)
                 if f in PINNED_FIELDS and wide[i, k]]
        if names:
            out.append(f"the {joint}'s {' and '.join(names)}")
    return tuple(out)
