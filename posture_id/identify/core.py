"""One entry point for identifying a recording: the CNN, least squares, or both.

    >>> from posture_id import load_body, Recording
    >>> from posture_id.identify import identify, Method
    >>> body = load_body()
    >>> rec = Recording.from_csv("rec.csv", body.segment_names)
    >>> result = identify(rec, body, Method.HYBRID)   # the CNN's answer refined
    >>> print(result.summary()); result.plot("result.png")

- :attr:`Method.CNN`: the trained network alone (milliseconds; only for the stimulus it
  was trained on);
- :attr:`Method.FIT`: least squares from the body's defaults (any tilt; seconds, and it
  can stall in a local minimum);
- :attr:`Method.HYBRID`: least squares started from the CNN's answer: its classes kept
  when it is sure of them and the fit then explains the sway as well as the recording's
  own noise allows, otherwise relaxed so that the fit can overturn a class
  (:func:`_refine`; docs/identify.md).

Every result is checked by simulating the identified model on the recording's tilt: the
body-sway errors E_id and E_rel (docs/model.md §7) and each segment's residual.
"""

from __future__ import annotations

import enum
import math
import time
from dataclasses import dataclass, replace
from pathlib import Path
from statistics import NormalDist

import numpy as np

from posture_id.bodies.body import Body, load_body
from posture_id.dec.parameters import TARGET_FIELDS
from posture_id.errors import PostureIdError
from posture_id.fitting.options import FitOptions, FixedClasses, RelaxedClasses
from posture_id.frf.locked import LockedOptions, LockedProjection
from posture_id.identify.alternatives import better_explanations
from posture_id.identify.method import DEFAULT_METHOD, Method
from posture_id.identify.mistakes import Check, find_mistakes
from posture_id.identify.networks import Network, network_for
from posture_id.identify.noise_check import (
    NOISE_RATIO_LIMIT,
    Basis,
    NoiseCheck,
    noise_check,
    unweighted_projection,
)
from posture_id.identify.result import NOTHING_BALANCES, IdentificationResult, SegmentFit
from posture_id.identify.verdict import (
    UNSURE_CLASS,
    TrustVerdict,
    class_doubts,
    is_people_like,
    suggestion,
    unpinned_parameters,
)
from posture_id.learning.config import LearningError
from posture_id.learning.identifier import DEFAULT_LEVEL
from posture_id.progress import Progress
from posture_id.provenance import provenance, recording_identity
from posture_id.recording import Recording
from posture_id.simulation.batch import simulate
from posture_id.simulation.metrics import sway_errors
from posture_id.simulation.options import MAX_SWAY_LIMIT_DEG, SimulationOptions
from posture_id.simulation.stimulus import TiltProfile
from posture_id.trials import PreparedTrial, prepare_trial

__all__ = ["Method", "identify", "Identifier", "DEFAULT_METHOD", "Refinement", "auto_refinement",
           "network_prior"]

def identify(recording: Recording, body: Body | None = None, method: Method = DEFAULT_METHOD,
             model: str | Path | Network | None = None,
             fit_options: FitOptions | None = None, progress: Progress | None = None,
             stimulus: TiltProfile | None = None,
             level: float = DEFAULT_LEVEL) -> IdentificationResult:
    """Identify every module's Kp, Ki, Kd, Δ and class from one recording: a one-off
    :class:`Identifier` (build one to identify many recordings).

    Args:
        recording: The tilt and segment angles (the body's segments); its ``name`` names
            it in messages.
        body: The body recorded; None: the default TIP.
        method: How to identify (:data:`DEFAULT_METHOD`: ``auto``).
        model: A model folder (a universal model or a per-body specialist) or a loaded
            network; None: the bundled universal model (:func:`~.networks.network_for`).
        fit_options: The least-squares options; None: the defaults.
        progress: Told the fit's stages; None: silent.
        stimulus: The tilt as the lab ran it (checked against the recording's tilt
            column); None: recognised from the tilt column.
        level: The intervals' nominal coverage (docs/uncertainty.md): the CNN's are
            conformal; least squares' are its Gauss-Newton standard errors times the scale
            calibrated for the hybrid, or ±z·SE, unchecked, for a fit from the defaults or
            a model without that calibration.

    Returns:
        Every module's parameters with their intervals, the verdict and the notices.
    """
    identifier = Identifier(body or load_body(), method, model, fit_options, level)
    return identifier.identify(recording, stimulus, progress)


class Identifier:
    """Built once for a body, a method and a model; identifies many recordings.

        >>> identifier = Identifier(load_body("subject.urdf"), Method.HYBRID)
        >>> results = [identifier.identify(Recording.from_csv(p)) for p in paths]

    Args:
        body: The body its recordings are of.
        method: How to identify (:data:`DEFAULT_METHOD`: ``auto``).
        model: A model folder (a universal model or a per-body specialist) or a loaded
            network; None: the bundled universal model (:func:`~.networks.network_for`).
        fit_options: The least-squares options; None: the defaults.
        level: The intervals' nominal coverage (as :func:`identify`'s).

    Attributes:
        cnn: The loaded network (:func:`~.networks.network_for`); None for
            :attr:`Method.FIT`, or for ``auto`` when the bundled network cannot serve
            the body.
        network_refusal: Why the bundled network cannot identify the body (``auto`` then
            fits), or None.
    """

    def __init__(self, body: Body, method: Method = DEFAULT_METHOD,
                 model: str | Path | Network | None = None,
                 fit_options: FitOptions | None = None,
                 level: float = DEFAULT_LEVEL) -> None:
        self.body = body
        self.method = Method(method)
        self.fit_options = fit_options or FitOptions()
        self.level = level
        #: why the bundled network cannot identify this body (``auto`` then fits), or None
        self.network_refusal: str | None = None
        self.cnn = None
        if self.method is not Method.FIT:
            try:
                self.cnn = network_for(model, body)
            except LearningError as error:
                if self.method is not Method.AUTO or model is not None:
                    raise
                self.network_refusal = str(error)

    def prepare(self, recording: Recording, stimulus: TiltProfile | None = None
                ) -> PreparedTrial:
        """The entrance: the recording checked against the body, its stimulus found or
        checked, at the model's rate."""
        recording.check_segments(self.body.segment_names)
        return prepare_trial(recording, stimulus, self.fit_options.simulation.sample_rate_hz)

    def identify(self, recording: Recording, stimulus: TiltProfile | None = None,
                 progress: Progress | None = None) -> IdentificationResult:
        """Identify one recording (see :func:`identify`)."""
        start = time.perf_counter()
        trial = self.prepare(recording, stimulus)
        return self.identify_trial(trial, progress, start)

    def hybrid_fit(self, trial: PreparedTrial, progress: Progress | None = None):
        """The hybrid's answer alone, without its verdict: the network's answer on a trial
        prepared by :meth:`prepare`, refined by least squares with this identifier's fit
        options (:class:`~posture_id.fitting.result.FitResult`)."""
        if self.cnn is None:
            raise PostureIdError(f"{self.body.name}: no network serves this body (the "
                                 "hybrid starts from one)")
        fit, _ = _refine(trial, self.body, self.cnn.identify(trial, self.level),
                         self.fit_options, progress, [])
        return fit

    def identify_trial(self, trial: PreparedTrial, progress: Progress | None = None,
                       start: float | None = None) -> IdentificationResult:
        """Identify a trial already prepared by :meth:`prepare`."""
        start = time.perf_counter() if start is None else start
        if self.method is Method.AUTO:
            return self._auto(trial, progress, start)
        return self._identify(trial, Step(self.method, self.fit_options), progress, start)

    def _identify(self, trial: PreparedTrial, step: Step, progress: Progress | None,
                  start: float, answer=None) -> IdentificationResult:
        """One identification of ``trial`` by ``step``'s method and fit options; ``answer``:
        the network's answer on this very trial when it was already made (not made
        again)."""
        method, body, options = step.method, self.body, step.fit_options
        network = None if method is Method.FIT else self.cnn
        notices: list[str] = []
        cnn = fit = None
        relaxed_refit = False
        spent = 0.0
        if network is not None:
            began = time.perf_counter()
            cnn = answer if answer is not None else network.identify(trial, self.level)
            spent = time.perf_counter() - began
            notices += cnn.notices
        began = time.perf_counter()
        if method is Method.FIT:
            # CasADi loads only when least squares runs: the CNN alone starts sooner
            from posture_id.fitting.least_squares import fit_recording

            fit = fit_recording(trial, body, None, options, progress)
        elif method is Method.HYBRID:
            fit, relaxed_refit = _refine(trial, body, cnn, options, progress, notices)
        if fit is not None:
            spent += time.perf_counter() - began
            notices += fit.notices
            parameters, normalised = fit.parameters, fit.normalised
            # the hybrid's scales are calibrated for the network's own body only
            calibration = (network.calibration if method is Method.HYBRID
                           and network.trained_on_this_body else None)
            scales = None if calibration is None else calibration.least_squares
            trial = fit.trial  # with a fitted stimulus offset: the shifted trial
        else:
            parameters, normalised = cnn.parameters, cnn.normalised
            notices += trial.notices
        locked = unweighted_projection(trial)
        checked = _resimulate(body, trial, parameters, options.simulation, locked)
        body_share = checked.pop("locked_share")  # the verdict's, not a result field
        noise = checked.pop("noise")
        # the network's intervals, widened for a people-like recording's own noise: the
        # network's answer's, and the floor of a fit from its prior
        network_intervals = (None if cnn is None
                             else _widened(network, cnn, cnn.intervals, body_share, noise))
        if fit is None:
            intervals = network_intervals
        else:
            intervals = fit.intervals_at(self.level, scales, **_network_floor(
                options, scales, network_intervals))
            if scales is not None and scales.beyond(intervals.noise_deg):
                notices.append(f"{trial.name}: its sensor noise (about "
                               f"{intervals.noise_deg:.3f}°) is above the "
                               f"{scales.noise_deg[-1]:.3f}° the hybrid's intervals were "
                               "calibrated for: they are likely too narrow")
        verdict = _verdict(method, options, trial, noise, body_share, cnn, fit, locked,
                           network is not None and network.reads_people_like,
                           body, intervals, parameters, checked["resimulated"])
        verdict = self._alternatives(trial, verdict, cnn, locked, step)
        return IdentificationResult(
            method=method, parameters=parameters, normalised=np.asarray(normalised),
            class_probability=None if cnn is None else np.asarray(cnn.class_probability),
            wall_time_s=time.perf_counter() - start, identification_time_s=spent,
            joints=body.joint_names, cnn=cnn, fit=fit, intervals=intervals,
            notices=tuple(dict.fromkeys(notices)),
            provenance=provenance(options if fit is not None else None, body,
                                  **recording_identity(trial.name, trial.recording.source),
                                  method=method.value),
            verdict=verdict, relaxed_refit=relaxed_refit,
            stimulus_offset_s=trial.time_offset_s, **checked,
        )


    def _alternatives(self, trial: PreparedTrial, verdict: TrustVerdict, cnn,
                      locked: LockedProjection | None, step: Step) -> TrustVerdict:
        """The verdict with the mistakes an alternative reading reveals
        (:mod:`~posture_id.identify.alternatives`: columns exchanged, another body's
        size), looked for when the answer leaves more than the noise and a network can
        read the alternatives. ``locked``: the trial's unweighted locked projection (the
        same for every alternative: they keep its tilt)."""
        noise = verdict.noise
        if (cnn is None or noise is None or noise.basis is not Basis.LOCKED
                or not NOISE_RATIO_LIMIT < noise.ratio < math.inf):
            return verdict  # nothing to read, or an answer within the noise
        def ratio_of(other: PreparedTrial, body: Body) -> float:
            return self._network_check(other, body, locked).ratio

        base = noise.ratio if step.method is Method.CNN else ratio_of(trial, self.body)
        found = better_explanations(trial, self.body, base, noise.relative, ratio_of,
                                    sizes=self.cnn.reads_any_body)
        if any(m.check is Check.ANOTHER_BODY for m in found) and not verdict.fitted \
                and self._fits_within_noise(trial, cnn, step.fit_options):
            found = tuple(m for m in found if m.check is not Check.ANOTHER_BODY)
        if not found:
            return verdict
        return replace(verdict, mistakes=verdict.mistakes + tuple(m.sentence for m in found),
                       suggestion="")

    def _fits_within_noise(self, trial: PreparedTrial, cnn, fit_options: FitOptions) -> bool:
        """Least squares from the network's answer ``cnn`` on the stimulus-locked sway (the
        locked hybrid's fit) explains ``trial`` on this identifier's body within its noise.
        The size check's confirmation: on clean sway the network's own error can read a
        body a fifth off better by chance, where least squares on the given body reaches
        the noise (docs/identify.md, "Mistakes"); a body that cannot have made the
        recording leaves least squares above it. Only the fit and its check: nothing of
        the hybrid's verdict is needed here."""
        options = replace(fit_options, locked=LockedOptions())
        try:
            fit, _ = _refine(trial, self.body, cnn, options, None, [])
        except PostureIdError:  # no fit: nothing confirms the given body, the reading stands
            return False
        return self.judge(fit.trial, self.body, fit.parameters).consistent

    def _network_check(self, trial: PreparedTrial, body: Body,
                       locked: LockedProjection | None = None) -> NoiseCheck:
        """The network's answer on ``trial`` read with ``body``, re-simulated and judged
        against the recording (:meth:`judge`; its ``ratio``: the stimulus-locked residual
        in units of the recording's noise, inf where it falls). ``locked``: the trial's unweighted
        locked projection (default: made here)."""
        network = self.cnn if body is self.body else self.cnn.for_body(body)
        return self.judge(trial, body, network.identify(trial, self.level).parameters,
                            locked)

    def judge(self, trial: PreparedTrial, body: Body, parameters,
              locked: LockedProjection | None = None) -> NoiseCheck:
        """``parameters`` on ``body`` re-simulated on ``trial``'s stimulus and judged
        against the recording (:func:`noise_check`, on the body COM sway as an answer's
        verdict is). ``locked``: the trial's unweighted locked projection (default: made
        here)."""
        if locked is None:
            locked = unweighted_projection(trial)
        _, theta, sway = _resimulated_sway(body, trial, parameters,
                                           self.fit_options.simulation)
        return noise_check(trial, theta, body_sway=sway, projection=locked)

    def _auto(self, trial: PreparedTrial, progress: Progress | None,
              start: float) -> IdentificationResult:
        """:attr:`Method.AUTO`: the network's answer, refined by least squares when
        :func:`auto_refinement` says so (the hybrid on the raw or the locked sway; on
        people-like sway whose answer falls or leaves more than the noise, the locked fit
        from the network's answer with its calibrated spread as the prior); least squares
        from the body's defaults when the network cannot read the recording (a tilt that is
        not periodic, or less than one whole cycle of it) or identify the body (more than 3
        segments). A stimulus that was named or rebuilt rather than recorded is first
        moved in time to where the sway says it was (:meth:`_onset`). Every recording gets
        an answer: when a refinement falls and the network's answer did not, the network's
        is kept; when both fall, least squares from the body's defaults on the locked sway
        with docs/model.md §5's prior; when that falls too, the one that stays up longest is
        returned, doubtful (``posture-id identify`` exits 1 then, its answer written)."""
        unread = self.network_refusal or _unreadable_by_network(trial)
        if unread is not None:
            fitted = self._identify(trial, Step(Method.FIT, self.fit_options), progress, start)
            return replace(fitted, notices=(
                f"{trial.name}: {unread}: identified by least squares from the body's "
                "defaults (--method auto)", *fitted.notices))
        answer = self._identify(trial, Step(Method.CNN, self.fit_options), progress, start)
        answer, trial, moved = self._onset(answer, trial, progress, start)
        result = self._refined(answer, trial, progress, start, polish=moved is not None)
        if moved is None:
            return result
        if abs(result.stimulus_offset_s - trial.time_offset_s) >= 0.0005:
            moved += (f"; least squares on the locked sway puts it at "
                      f"{result.stimulus_offset_s:+.3f} s")
        return replace(result, notices=(moved, *result.notices))

    def _refined(self, answer: IdentificationResult, trial: PreparedTrial,
                 progress: Progress | None, start: float,
                 polish: bool = False) -> IdentificationResult:
        """``auto``'s refinement of the network's ``answer`` (:meth:`_auto`); with
        ``polish`` (the stimulus was moved in time to where the sway says it ran), refined
        on the stimulus-locked sway in any case, its offset fitted too within
        :data:`TIMING_POLISH_S` (the network's timing is good to about a tenth of a
        second; least squares on the locked sway pins it further)."""
        verdict = answer.verdict
        how = auto_refinement(verdict)
        if polish and how in (Refinement.KEEP, Refinement.RAW):
            how = Refinement.LOCKED_PRIOR if verdict.people_like else Refinement.LOCKED
        if how is Refinement.KEEP:
            return answer
        options, on = self.fit_options, "the sway"
        if how is Refinement.LOCKED_PRIOR:
            on = "the stimulus-locked sway, with the network's spread as the prior"
            options = replace(options, locked=LockedOptions(),
                              **network_prior(answer, self.level))
        elif how is Refinement.LOCKED:
            on = "the stimulus-locked sway"
            if options.locked is None:
                options = replace(options, locked=LockedOptions())
        if polish:
            on += f", its timing fitted within ±{TIMING_POLISH_S:g} s"
            options = replace(options, locked=replace(options.locked,
                                                      max_offset_s=TIMING_POLISH_S))
        # the hybrid starts from the network's answer already made on this trial
        refined = self._identify(trial, Step(Method.HYBRID, options), progress, start,
                                 answer.cnn)
        why = "; ".join(verdict.reasons) or "; ".join(verdict.imprecision)
        why = f" ({why})" if why else ""
        said = (f"{trial.name}: the network's answer was {verdict.level}{why}: refined by "
                f"least squares on {on} (--method auto)")
        if refined.fell and not answer.fell:
            return replace(answer, notices=(
                said + "; the refined model falls in re-simulation, so the network's answer "
                "is kept", *answer.notices))
        if refined.fell:
            # both fall: least squares from the body's defaults on the locked sway, the
            # prior of docs/model.md §5 holding what the sway leaves open (where the
            # network's answer is no start at all)
            fitted = self._identify(trial, Step(Method.FIT, replace(
                self.fit_options, locked=LockedOptions(), prior_sd=0.5, prior_centre=None)),
                progress, start)
            said += ("; the refined model falls in re-simulation too: fitted again from the "
                     "body's defaults on the stimulus-locked sway with docs/model.md §5's prior "
                     "(--method fit --locked --prior-sd 0.5)")
            if not fitted.fell:
                return replace(fitted, notices=(said, *fitted.notices))
            later = max((answer, refined, fitted), key=lambda r: r.fell_at_s or 0.0)
            later = replace(later, verdict=replace(later.verdict, suggestion=""))  # all tried
            return replace(later, notices=(
                said + f"; {NOTHING_BALANCES}: the one that stays up longest is given, "
                "doubtful", *later.notices))
        return replace(refined, notices=(said, *refined.notices))

    def _onset(self, answer: IdentificationResult, trial: PreparedTrial,
               progress: Progress | None, start: float
               ) -> tuple[IdentificationResult, PreparedTrial, str | None]:
        """The stimulus's timing, where the network's answer leaves more than the noise or
        the sway is people-like (whose noise hides a mistimed stimulus): the answer, the
        trial it is for, and the notice of a move (None without one).

        Candidates (:meth:`_timing_candidates`): about the offset at which the recording's
        own locked FRF is smoothest, the network's locked residual on a grid of shifts,
        its deepest local minima each identified by the network and its offset settled.
        The network's residual finds them but cannot choose: on people-like sway its own
        error moves it as much as the timing does. Where a candidate's answer leaves less
        than the answer at the given timing, least squares on the stimulus-locked sway
        decides (:meth:`_timing_profile`, one prior for every timing): the timing moves
        only where its fit's χ² is lower than the given timing's by at least
        :data:`SHIFT_CHI2`. Searched within a
        quarter cycle, tilt column or named stimulus alike: half a cycle on, a PRTS (and a
        sinusoid) is its own negative, which is a question of the tilt's sign (the
        verdict's mistakes name it: the body then sways against the tilt), never one of
        its timing. A mistake in the recording (a negated tilt column, an angle step, a
        change of control) is not explained by a shift and is not moved."""
        verdict = answer.verdict
        if answer.fell or verdict.noise is None:
            return answer, trial, None
        period = trial.stimulus.period_s
        if not (verdict.beyond_noise or verdict.people_like) or period is None:
            return answer, trial, None
        weighted = LockedProjection.for_periodic_trial(trial)
        if weighted is None:
            return answer, trial, None
        cycles = weighted.cycles
        reach = period / 4  # half a cycle on, a PRTS or a sinusoid is its own negative
        ratio = verdict.noise.ratio
        # a candidate competes only on as many cycles as the given timing analyses: a
        # shift that moves the stimulus's start before the recording's, or its end past
        # it, loses a cycle, and a χ² over less sway wins for that alone (compared on the
        # same fewer cycles, a wrong timing of people-like sway still won: one cycle
        # cannot tell the subject's own sway from the response)
        judged = [j for j in self._timing_candidates(trial, weighted, reach, progress, start)
                  if j[0] < ratio and _analysed_cycles(j[1]) == cycles]
        if not judged:
            return answer, trial, None
        given = self._timing_profile([(trial, answer)], progress, polish=False)
        profile = [p for p in self._timing_profile(
            [(shifted, moved) for _, shifted, moved in judged], progress)
            if _analysed_cycles(p[1]) == cycles]
        if not (given and profile):
            return answer, trial, None  # a fit failed: nothing to compare
        given = given[0][0]
        best_cost, fitted, moved = min(profile, key=lambda p: p[0])
        offset = fitted.time_offset_s - trial.time_offset_s
        gain = 2.0 * (given - best_cost)
        if abs(offset) < 0.02 or gain < SHIFT_CHI2:
            return answer, trial, None
        moved = self._identify(fitted, Step(Method.CNN, self.fit_options), progress, start)
        best = moved.verdict.noise.ratio
        evidence = (f"least squares on the locked sway: χ² lower by {gain:.0f}; the network's "
                    f"answer {best:.2f}× the noise, {ratio:.2f}× at the given timing")
        if trial.tilt_recorded:
            said = (f"{trial.name}: the sway says the stimulus ran {offset:+.2f} s from where "
                    f"its tilt column has it ({evidence}): identified there (--method auto; "
                    "check the tilt column's timing, or search it with --max-offset-s)")
        else:
            said = (f"{trial.name}: the stimulus was named, not recorded: the sway says it "
                    f"ran {offset:+.2f} s from where it was named ({evidence}); identified "
                    "there (--method auto; name the onset with --onset-s, or search it with "
                    "--max-offset-s)")
        return moved, fitted, said

    def _timing_candidates(self, trial: PreparedTrial, weighted: LockedProjection,
                           reach: float, progress: Progress | None, start: float) -> list:
        """(ratio, shifted trial, the network's answer there) of :meth:`_onset`'s
        candidate timings within ±``reach`` s, best first: about the offset at which the
        recording's empirical locked FRF is smoothest
        (:meth:`~posture_id.frf.locked.LockedProjection.smoothest_offset`), the network's
        residual on a grid of shifts (every :data:`ONSET_GRID_S` within
        ±:data:`ONSET_WINDOW_S` of it), its :data:`ONSET_CANDIDATES` deepest local minima
        each identified by the network and settled (:meth:`_settle_offset`). ``weighted``:
        the trial's locked projection."""
        rec = trial.recording
        centre = weighted.smoothest_offset(np.degrees(rec.theta), np.degrees(rec.tilt), reach)
        low, high = max(centre - ONSET_WINDOW_S, -reach), min(centre + ONSET_WINDOW_S, reach)
        scanned = []
        for offset in np.arange(low, high + 1e-9, ONSET_GRID_S):
            shifted = trial.shifted_whole(float(offset)) if abs(offset) >= 0.02 else None
            if shifted is None:
                continue
            try:
                scanned.append((self._network_check(shifted, self.body).ratio, shifted))
            except PostureIdError:  # the shifted tilt cannot be read there
                continue
        minima = [scanned[k] for k in range(len(scanned))
                  if (k == 0 or scanned[k][0] <= scanned[k - 1][0])
                  and (k == len(scanned) - 1 or scanned[k][0] <= scanned[k + 1][0])]
        judged = []
        for _, shifted in sorted(minima, key=lambda m: m[0])[:ONSET_CANDIDATES]:
            try:
                moved = self._identify(shifted, Step(Method.CNN, self.fit_options), progress,
                                       start)
                moved, shifted = self._settle_offset(moved, shifted, progress, start)
            except PostureIdError:
                continue
            if not moved.fell:
                judged.append((moved.verdict.noise.ratio, shifted, moved))
        return sorted(judged, key=lambda j: j[0])

    def _timing_profile(self, starts: list, progress: Progress | None,
                        polish: bool = True) -> list:
        """(cost, the fitted trial, the start's answer) of least squares on the
        stimulus-locked sway at each (trial, network answer) of ``starts``, from that
        answer, its classes kept, with docs/model.md §5's prior about the body's defaults
        (:data:`TIMING_PRIOR_SD`: one prior for every timing, so that the costs compare,
        χ² = 2·cost with the prior's terms; without it a wrong timing's fit runs to
        parameters no person has and can beat the right one); with ``polish`` the offset
        fitted too within :data:`TIMING_POLISH_S` (a candidate a few tens of milliseconds
        off the right timing must not lose to a wrong one for that). A start whose fit
        fails is left out."""
        from posture_id.fitting.least_squares import fit_recording

        options = replace(self.fit_options, classes=FixedClasses(),
                          prior_sd=TIMING_PRIOR_SD, prior_centre=None, locked=LockedOptions(
                              max_offset_s=TIMING_POLISH_S if polish else 0.0))
        out = []
        for shifted, answer in starts:
            try:
                fit = fit_recording(shifted, self.body, answer.parameters, options, progress)
            except PostureIdError:
                continue
            out.append((fit.cost, fit.trial, answer))
        return out

    def _settle_offset(self, answer: IdentificationResult, trial: PreparedTrial,
                       progress: Progress | None, start: float
                       ) -> tuple[IdentificationResult, PreparedTrial]:
        """The network's ``answer`` on a shifted ``trial``, its offset refined: the best
        offset of its own locked sway against the recorded one (the first shift was
        measured with the answer on the unshifted trial), the network again there, while
        the offset moves by at least 20 ms and the residual shrinks (at most
        :data:`OFFSET_ROUNDS` times)."""
        for _ in range(OFFSET_ROUNDS):
            projection = unweighted_projection(trial)
            if projection is None or answer.fell:
                break
            step = projection.best_offset(np.degrees(answer.resimulated),
                                          np.degrees(trial.recording.theta), 0.5,
                                          step_s=0.005)
            again = None if abs(step) < 0.02 else trial.shifted_whole(step)
            if again is None:
                break
            moved = self._identify(again, Step(Method.CNN, self.fit_options), progress,
                                   start)
            if moved.fell or moved.verdict.noise.ratio >= answer.verdict.noise.ratio:
                break
            answer, trial = moved, again
        return answer, trial


#: Rounds of :meth:`Identifier._settle_offset`.
OFFSET_ROUNDS = 3
#: s, the step of :meth:`Identifier._onset`'s grid of shifts (the network's residual
#: dips narrowly about the right timing: a fraction of a 0.25 s PRTS state).
ONSET_GRID_S = 0.1
#: s, how far either side of the smoothest-FRF offset that grid reaches (that offset is
#: off by the body's group delay: ``smoothest_error_s`` in benchmarks/prts_timing.py).
ONSET_WINDOW_S = 2.0
#: The grid's local minima :meth:`Identifier._onset` identifies and settles.
ONSET_CANDIDATES = 3
#: The least drop of the locked least-squares χ² (its cost ×2, in units of the noise)
#: for which ``auto`` moves a stimulus in time: on 80-state PRTS recordings of people-like
#: sway the right timing beats the next local minimum by more than this in most, and a
#: shift of a rightly timed one by less (benchmarks/prts_timing.py).
SHIFT_CHI2 = 10.0
#: s, the offset ``auto``'s least squares still fits about a stimulus it moved in time.
TIMING_POLISH_S = 0.5
#: The prior SD (normalised parameters, about the body's defaults: docs/model.md §5) of
#: the fits that decide the timing.
TIMING_PRIOR_SD = 0.5


@dataclass(frozen=True)
class Step:
    """One identification ``auto`` (or any method) runs: its method and fit options."""

    method: Method
    fit_options: FitOptions


class Refinement(enum.Enum):
    """What ``auto`` does with the network's answer (:func:`auto_refinement`)."""

    #: keep it
    KEEP = "keep"
    #: least squares from it on every sample of the sway (the hybrid)
    RAW = "raw"
    #: least squares from it on the stimulus-locked sway (the hybrid with ``--locked``)
    LOCKED = "locked"
    #: the same with the network's calibrated spread as a prior centred on its answer
    LOCKED_PRIOR = "locked_prior"


def auto_refinement(verdict: TrustVerdict) -> Refinement:
    """``auto``'s rule for the network's answer (measured in docs/universal.md, "The
    default method"): keep an answer that is close to the recording (within
    :data:`~posture_id.identify.noise_check.CLOSE_ENOUGH` of it), on no bound and inside
    the network's scope. On people-like sway keep it too unless it falls or leaves more
    than the recording's noise: least squares fits the subject's own sway too, and the
    network was trained on such sway; then refine it on the stimulus-locked sway with the
    network's calibrated spread as the prior (:attr:`Refinement.LOCKED_PRIOR`). Otherwise
    refine it from its own values: on the stimulus-locked sway when the recording cannot
    check it (:attr:`~posture_id.identify.noise_check.NoiseCheck.unchecked`: the answer
    explains the recording as well as its noise allows, and that noise alone leaves more
    than 10 % of the locked sway; on motor-noisy sway, least squares on every sample fits
    the subject's own sway and ends further from the truth, `benchmarks/auto_rule.py`),
    except on a recording of one cycle, whose locked share cannot be measured (people-like
    or not, the network's answer is kept there: `benchmarks/auto_rule.py --cycles 1`), on
    every sample otherwise. A mistake found in the recording is no reason to refine: no
    fit can be right about it."""
    if verdict.mistakes or not (verdict.not_close or verdict.bounds_that_matter
                                or verdict.outside):
        return Refinement.KEEP
    share = verdict.locked_share
    if verdict.people_like:
        return Refinement.LOCKED_PRIOR if verdict.beyond_noise else Refinement.KEEP
    if verdict.noise is not None and verdict.noise.unchecked:
        # one cycle: no locked share to tell people-like sway from part-locked, and least
        # squares, raw or locked, ended further from the truth than the network on such
        # motor-noisy recordings (docs/results/auto_rule_one_cycle.md)
        return Refinement.KEEP if share is None else Refinement.LOCKED
    return Refinement.RAW


def network_prior(answer: IdentificationResult, level: float) -> dict:
    """The prior a refinement of the network's ``answer`` takes: ``prior_centre`` its
    normalised gains and delays, ``prior_sd`` its calibrated spread (the half-width of
    its intervals at ``level`` over the normal quantile, at least :data:`MIN_PRIOR_SD`);
    docs/model.md §5's 0.5 about the defaults when it has no intervals. FitOptions keywords."""
    intervals = answer.intervals
    if intervals is None:
        return {"prior_sd": 0.5}
    z = NormalDist().inv_cdf((1 + intervals.level) / 2)
    sd = np.maximum((intervals.upper - intervals.lower) / 2 / z, MIN_PRIOR_SD)  # (N, 4)
    centre = np.asarray(answer.normalised, dtype=float)[:, :4]
    return {"prior_sd": tuple(float(v) for v in sd.T.ravel()),
            "prior_centre": tuple(float(v) for v in centre.T.ravel())}


def _network_floor(options: FitOptions, scales, network_intervals) -> dict:
    """``intervals_at`` keywords for a fit whose prior is the network's answer
    (:func:`network_prior`) and whose standard errors have no calibrated scale: its
    intervals are no narrower than the network's calibrated ones. Two cycles of
    people-like sway pin the fit less than its Gauss-Newton errors say (they assume the
    residual is white; on people-like sway it is the noise's, coloured), and a prior
    narrows a posterior only as far as the data inform it: the network's calibrated spread
    is the checked statement of what the recording pins (``docs/identify.md``).
    ``network_intervals``: the network's, widened for a people-like recording's own noise
    (:func:`_widened`), or None."""
    if options.prior_centre is None or scales is not None or network_intervals is None:
        return {}
    return {"at_least": (network_intervals.upper - network_intervals.lower) / 2,
            "at_least_from": "the network's calibrated intervals"}


#: The least SD of the network's prior on a normalised parameter (its intervals can be
#: narrow where the network has seen much of the same).
MIN_PRIOR_SD = 0.05


def _analysed_cycles(trial: PreparedTrial) -> int | None:
    """The stimulus cycles the trial's locked analysis spans (None: none)."""
    projection = LockedProjection.for_periodic_trial(trial)
    return None if projection is None else projection.cycles


def _unreadable_by_network(trial: PreparedTrial) -> str | None:
    """Why the network cannot read ``trial`` (it reads the stimulus-locked response over
    whole cycles of a periodic tilt), or None when it can."""
    if trial.stimulus.period_s is None:
        return (f"its tilt is not periodic over the {trial.recording.duration_s:.1f} s "
                "recorded, and the network reads the response to a periodic one")
    return trial.whole_cycle_shortfall()


def _refine(trial: PreparedTrial, body: Body, cnn, options: FitOptions,
            progress: Progress | None, notices: list[str]):
    """The hybrid's least squares from the CNN's answer: (the fit, whether it was fitted
    again with the classes relaxed).

    Classes the CNN is sure of (P(C = +1) outside :data:`UNSURE_CLASS` for every module)
    are kept and only the continuous parameters refined: the short route. It is accepted
    when its residual is consistent with the recording's own noise
    (:func:`~posture_id.identify.noise_check.noise_check`: stimulus-locked for a periodic
    stimulus, so that sway of the subject's own does not count against it; raw
    otherwise), whether the fit compares raw or locked sway. When the CNN is unsure of a
    class, or the short route leaves more than the noise allows (a confidently wrong
    class leaves a large locked residual), the fit runs again from the CNN's parameters
    with its classes relaxed half-way (c = ±0.5), so that it can overturn a class; the
    better of the two fits is kept.
    """
    from posture_id.fitting.least_squares import fit_recording

    low, high = UNSURE_CLASS
    unsure = [j for j, p in zip(body.joint_names, cnn.class_probability, strict=True)
              if low < p < high]
    fit = fit_short = None
    if unsure:
        notices.append(f"the CNN is unsure of the class of {', '.join(unsure)}: "
                       "least squares decides it")
    else:
        fit = fit_recording(trial, body, cnn.parameters,
                            replace(options, classes=FixedClasses()), progress)
        check = noise_check(fit.trial, fit.fitted)
        if not check.consistent:
            notices.append(f"with the CNN's classes the fit leaves a {check.sentence()}: "
                           "fitted again with the classes relaxed")
            fit_short, fit = fit, None
    if fit is None:
        relaxed = options.classes if isinstance(options.classes, RelaxedClasses) \
            else RelaxedClasses()
        fit = fit_recording(trial, body, cnn.parameters,
                            replace(options, classes=relaxed), progress)
        if fit_short is not None and fit_short.cost < fit.cost:
            fit = fit_short
    changed = [j for j in body.joint_names
               if fit.parameters[j].controls != cnn.parameters[j].controls]
    if changed:
        notices.append(f"least squares overturned the CNN's class of {', '.join(changed)}")
    return fit, fit_short is not None or bool(unsure)


def _resimulated_sway(body: Body, trial: PreparedTrial, parameters,
                      simulation: SimulationOptions) -> tuple:
    """(the simulation of the identified model on the trial's stimulus, with the sway
    limit widened to :data:`MAX_SWAY_LIMIT_DEG`; its (S, N) segment angles over the
    recording's S samples, rad; (the recorded, the simulated) (S,) body COM sway, rad)."""
    wide = replace(simulation, sway_limit_deg=MAX_SWAY_LIMIT_DEG)
    sim = simulate(body, parameters, trial.stimulus, wide)
    n = len(trial.recording.time)
    return sim, sim.theta[:n], (body.com_angles(trial.recording.theta)[:, 0],
                                sim.alpha[:n, 0])


def _resimulate(body: Body, trial: PreparedTrial, parameters,
                simulation: SimulationOptions, locked: LockedProjection | None) -> dict:
    """Simulate the identified model on the trial's stimulus (with any fitted offset);
    E_id, E_rel, segment fits and its check against the recording's noise (``noise``:
    :func:`noise_check` on the body COM sway); with ``locked`` (the trial's unweighted
    locked projection) the locked statistics too."""
    rec = trial.recording
    sim, theta, (sway_recorded, sway_simulated) = _resimulated_sway(body, trial, parameters,
                                                                    simulation)
    e_id, e_rel = map(float, sway_errors(sway_recorded, sway_simulated))
    fell = math.isinf(e_rel)
    share = explained = body_share = None
    if locked is not None:
        share = locked.locked_share(rec.theta)
        explained = locked.explained(rec.theta, theta)
        body_share = float(locked.locked_share(np.degrees(sway_recorded)[:, None])[0])
    segments = []
    for j, name in enumerate(rec.segments):
        residual = rec.theta[:, j] - theta[:, j]
        statistics = {} if locked is None else {
            # a single cycle cannot tell noise from response: no share (None)
            "locked_share": float(share[j]) if np.isfinite(share[j]) else None,
            "locked_variance_explained": float(explained[j])}
        if fell:
            segments.append(SegmentFit(name, math.inf, -math.inf, **statistics))
            continue
        segments.append(SegmentFit(
            name, math.degrees(float(np.sqrt(np.mean(residual**2)))),
            float(1.0 - np.var(residual) / np.var(rec.theta[:, j])), **statistics))
    noise = noise_check(trial, theta, body_sway=(sway_recorded, sway_simulated),
                        projection=locked)
    return {"e_id_deg": e_id, "e_rel": e_rel, "segments": tuple(segments), "time": rec.time,
            "recorded": rec.theta, "resimulated": theta, "sway_recorded": sway_recorded,
            "sway_resimulated": sway_simulated, "fell_at_s": sim.abort_time,
            "locked_share": None if body_share is None or not math.isfinite(body_share)
            else body_share, "noise": noise}


def _widened(network, cnn, intervals, share: float | None, noise: NoiseCheck):
    """The network's ``intervals`` widened for a people-like recording (locked ``share``
    below :data:`PEOPLE_LIKE_SHARE`) by the network's recording widening
    (:mod:`posture_id.uncertainty.widening`) at the share of its locked sway its own noise
    leaves (``noise.noise_relative``); as they are otherwise."""
    widening = getattr(network, "widening", None)
    relative = noise.noise_relative
    if (widening is None or intervals is None or not is_people_like(share)
            or not math.isfinite(relative)):
        return intervals
    factor = widening.factor(relative)
    if np.all(factor <= 1.0):
        return intervals
    defaults = np.array([[getattr(network.defaults[j], f) for f in TARGET_FIELDS]
                         for j in intervals.joints])
    return intervals.widened(
        np.asarray(cnn.normalised, dtype=float)[:, :4], factor, defaults,
        "widened ×" + "/".join(f"{v:.2f}" for v in factor) + " (Kp/Ki/Kd/delay) for the "
        f"noise this people-like recording shows ({100 * relative:.0f} % of its locked "
        "sway; docs/uncertainty.md)")


def _verdict(method: Method, options: FitOptions, trial: PreparedTrial, noise: NoiseCheck,
             share: float | None, cnn, fit, locked: LockedProjection | None,
             reads_people_like: bool, body: Body, intervals, parameters,
             resimulated: np.ndarray) -> TrustVerdict:
    """The trust verdict (:mod:`posture_id.identify.verdict`) of one identification;
    ``noise``: its check against the recording's noise; ``share``: the recorded body
    sway's locked share; ``reads_people_like``: the network was trained on people-like
    sway (the universal model); ``intervals`` (or None) and ``parameters``: the answer's;
    ``resimulated``: its sway re-simulated (S, N) rad."""
    locked_fit = options.locked is not None
    people_like = is_people_like(share)
    outside = list(cnn.outside) if method is Method.CNN and cnn is not None else []
    if people_like and method is Method.CNN and not reads_people_like:
        outside.append(f"only {100 * share:.0f} % of the body sway is stimulus-locked; the "
                       "network was trained on sway that is the stimulus's response and "
                       "sensor noise")
    elif people_like and not locked_fit and method is not Method.CNN:
        outside.append(f"only {100 * share:.0f} % of the body sway is stimulus-locked: "
                       "least squares on the raw sway fits the subject's own sway too")
    on_bounds = () if fit is None else fit.on_bounds
    mistakes = find_mistakes(trial, body, resimulated, locked)
    estimate = np.array([[getattr(parameters[j], f) for f in TARGET_FIELDS]
                         for j in body.joint_names])
    unpinned = unpinned_parameters(intervals, estimate)
    classes_doubted = ""
    if method is Method.CNN and cnn is not None:  # classes the network is unsure of
        unsure, classes_doubted = class_doubts(body.joint_names, cnn.class_probability)
        unpinned += unsure
    sentences = tuple(m.sentence for m in mistakes)
    typicality = None if cnn is None else cnn.typicality
    if typicality is not None and typicality.atypical:  # not a recording the model made
        sentences += (typicality.sentence(),)
    verdict = TrustVerdict(noise, on_bounds, tuple(outside), share, mistakes=sentences,
                           unpinned=unpinned, classes_doubted=classes_doubted,
                           fitted=fit is not None)
    if not verdict.doubtful or verdict.mistakes:  # a mistake: the recording to mend first
        return verdict
    if verdict.reasons == (classes_doubted,):  # its sentence says what decides them
        return verdict
    advice = suggestion(method, locked_fit, share, on_bounds, noise,
                        options.prior_sd is not None, reads_people_like,
                        _unreadable_by_network(trial) is None, trial.stimulus.period_s,
                        locked_fit and options.locked.max_offset_s > 0)
    if not trial.tilt_recorded and verdict.beyond_noise:
        # a named stimulus that no timing fits: the stimulus itself is the first suspect
        advice = (f"{NAMED_STIMULUS_CHECK}" + (f"; else {advice}" if advice else ""))
    return replace(verdict, suggestion=advice)


#: The suggestion for an answer beyond the noise on a stimulus named, not recorded.
NAMED_STIMULUS_CHECK = ("checking the stimulus named against the lab's protocol (--states, "
                        "--state-s, --start-state, --sign, --onset-s: the sway follows no "
                        "timing of this one within the noise)")
