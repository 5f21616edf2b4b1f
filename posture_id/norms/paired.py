"""Two conditions of the same subjects (``posture-id norm compare --paired``): eyes open
against eyes closed, before against after, each subject measured in both.

The i-th member of group A and the i-th of group B are one subject. Per channel and per
frequency the within-subject difference of the complex FRF, d_i = H_A,i − H_B,i
(i = 1 … n), is tested for a mean of zero by a **sign-flip permutation test**: under the
null hypothesis the two conditions are exchangeable within each subject, so each d_i is
as likely to be −d_i, whatever the subject's own FRF and noise level. The statistic at
one frequency f of one channel m is

    Q_fm = |Σ_i d_i|² / Σ_i |d_i|²  =  n·|mean d|² / mean |d_i|²,

the share of the differences' energy that lies in their mean (0 ≤ Q ≤ n; n only when
every subject's difference is the same complex number). Σ|d_i|² does not change when
signs flip, so Q orders the sign patterns exactly as the Hotelling-like ratio
R = |mean d|² / mean |d_i − mean d|² = Q / (n − Q) does (one p-value for both), and over
the 2ⁿ sign patterns Q has mean exactly 1 at every frequency, whatever the FRF's size
there (E[s_i·s_j] = δ_ij): Q is standardised, and the **whole FRF** is tested with
T = Σ_fm Q_fm under the same sign flips (one sign pattern flips a subject's difference at
every frequency and channel at once, keeping the dependence between frequencies; the test
of T is exact as the per-frequency ones are).

**Exactness.** With 2ⁿ ≤ ``permutations`` every sign pattern is enumerated and
p = #{patterns with T_s ≥ T} / 2ⁿ exactly (the identity pattern among them). A pattern and
its negation give the same statistic, so the smallest p is 2/2ⁿ (every subject's
difference the same up to a positive factor). Otherwise ``permutations`` patterns are
drawn (each subject's sign ±1 with probability ½) and p = (1 + #{T_s ≥ T}) / (1 + N).
Besides the per-frequency p-values (uncorrected), ``p_adjusted`` gives each frequency's
p-value adjusted for the F·M frequencies and channels by the single-step max-T method
(the share of patterns whose largest Q exceeds this frequency's; Westfall and Young 1993),
from the same patterns.

**Effect sizes** (t-based, Student's t with n − 1 degrees of freedom, at ``level``): per
frequency the mean gain ratio B/A, the geometric mean exp(mean log(|H_B,i|/|H_A,i|)) as
a percentage, its interval exp(mean ± t·SD/√n) of the log ratios; and the mean phase
difference B − A, φ_i = ∠(H_B,i / H_A,i) in degrees, centred at the φ_i's circular mean
before averaging (so differences near ±180° do not cancel), with mean ± t·SD/√n. Both
are differences of B from A; the tested d is A − B.

:func:`compare_paired_parameters` tests identified parameters (``identify`` results) the
same way: one real difference per subject and parameter, the same statistic (for real
numbers Q orders the sign patterns as the one-sample t statistic's square does), the same
sign patterns for every parameter. **[decision]** Each subject counts once (no weights
from the subjects' own intervals): in a within-subject design the spread of the change
between subjects is what the test must face, and a subject whose recording pinned its
parameters tightly would otherwise carry the result alone.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.stats import t as student

from posture_id.errors import PostureIdError
from posture_id.fileio import Result, jsonable
from posture_id.norms.norm import FrfSet
from posture_id.norms.parameters import IdentifiedGroup

__all__ = ["SignFlipTest", "sign_flip_test", "PairedComparison", "compare_paired",
           "PairedParameterComparison", "compare_paired_parameters", "SIGNIFICANCE"]

#: The level at which a summary names the frequencies (or parameters) that differ.
SIGNIFICANCE = 0.05
#: Ties: a pattern's statistic counts as reaching the observed one within this (Q ≤ n).
_TIE = 1e-9
#: The most numbers (sign patterns × tested columns) one block of patterns holds.
_BLOCK = 1 << 20


@dataclass(frozen=True)
class SignFlipTest:
    """A sign-flip permutation test of n subjects' differences (the module doc).

    Attributes:
        statistic: (K,) Q of each tested column (a frequency of a channel, a parameter).
        p_values: (K,) each column's p-value (uncorrected).
        p_adjusted: (K,) each column's max-T adjusted p-value (over the K columns).
        global_statistic: T = Σ Q. global_p: its p-value.
        patterns: the sign patterns used (2ⁿ when exact). exact: every pattern enumerated.
    """

    statistic: np.ndarray
    p_values: np.ndarray
    p_adjusted: np.ndarray
    global_statistic: float
    global_p: float
    patterns: int
    exact: bool


def _sign_blocks(n: int, permutations: int, columns: int, seed: int):
    """(exact, count, iterator of (B, n) ±1 sign matrices): every one of the 2ⁿ patterns
    when 2ⁿ ≤ ``permutations`` (in blocks), else ``permutations`` random ones."""
    exact = n < 62 and (1 << n) <= permutations
    count = (1 << n) if exact else permutations
    block = max(1, _BLOCK // max(columns, n, 1))
    bits = np.arange(n, dtype=np.int64)

    def blocks():
        rng = np.random.default_rng(seed)
        for start in range(0, count, block):
            size = min(block, count - start)
            if exact:
                codes = np.arange(start, start + size, dtype=np.int64)
                yield 1.0 - 2.0 * ((codes[:, None] >> bits) & 1)
            else:
                yield 1.0 - 2.0 * rng.integers(0, 2, size=(size, n))

    return exact, count, blocks()


def sign_flip_test(differences: np.ndarray, permutations: int = 2000,
                   seed: int = 0) -> SignFlipTest:
    """The sign-flip permutation test of ``differences`` (the module doc): each column's
    Q = |Σ_i d_i|² / Σ_i |d_i|² and the sum T = Σ Q, each subject's row flipped in sign by
    one pattern for every column at once.

    Args:
        differences: (n, K) real or complex, one row per subject (n ≥ 2), one column per
            tested quantity (frequency × channel, or parameter); (n,) for one column.
        permutations: N; all 2ⁿ patterns are enumerated when 2ⁿ ≤ N, else N are drawn.
        seed: seeds the drawn patterns (unused when exact).
    Returns:
        :class:`SignFlipTest`. A column whose differences are all zero has Q = 0, p = 1.
    Raises:
        PostureIdError: fewer than 2 subjects, permutations < 1, values not finite.
    """
    d = np.asarray(differences)
    if d.ndim == 1:
        d = d[:, None]
    if d.ndim != 2 or len(d) < 2:
        raise PostureIdError(f"a sign-flip test needs at least 2 subjects' differences, got "
                             f"{len(d) if d.ndim else 0}")
    if permutations < 1:
        raise PostureIdError(f"permutations must be ≥ 1, got {permutations}")
    if not np.all(np.isfinite(d)):
        raise PostureIdError("the within-subject differences hold values that are not finite")
    n, k = d.shape
    energy = np.sum(np.abs(d) ** 2, axis=0)  # (K,): the same for every pattern
    scale = np.where(energy > 0, energy, np.inf)

    def q_of(sums: np.ndarray) -> np.ndarray:
        return np.abs(sums) ** 2 / scale

    observed = q_of(d.sum(axis=0))
    total = float(observed.sum())
    exact, count, blocks = _sign_blocks(n, permutations, k, seed)
    reach = np.zeros(k)
    reach_max = np.zeros(k)
    reach_total = 0
    for signs in blocks:
        q = q_of(signs @ d)  # (B, K)
        reach += np.sum(q >= observed - _TIE, axis=0)
        reach_max += np.sum(q.max(axis=1)[:, None] >= observed - _TIE, axis=0)
        reach_total += int(np.sum(q.sum(axis=1) >= total - _TIE * k))

    def p(hits):
        return hits / count if exact else (1 + hits) / (1 + count)

    return SignFlipTest(observed, p(reach), p(reach_max), total, float(p(reach_total)),
                        count, exact)


def _t_interval(x: np.ndarray, level: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(mean, low, high) over axis 0 of ``x`` (n, ...): mean ± t_{n−1}·SD/√n."""
    n = len(x)
    with np.errstate(invalid="ignore"):
        mean = x.mean(axis=0)
        half = student.ppf(0.5 + level / 2, n - 1) * x.std(axis=0, ddof=1) / np.sqrt(n)
    return mean, mean - half, mean + half


def _check_level(level: float) -> None:
    if not 0 < level < 1:
        raise PostureIdError(f"level must be within 0–1 (a share, not a percentage), got "
                             f"{level}")


def _check_pairs(count_a: int, count_b: int, names: tuple[str, str], what: str) -> None:
    if count_a != count_b:
        raise PostureIdError(f"a paired comparison takes one {what} of each subject in each "
                             f"group: {names[0]} has {count_a}, {names[1]} has {count_b}")
    if count_a < 2:
        raise PostureIdError(f"a paired comparison needs at least 2 subjects (pairs), got "
                             f"{count_a}")


@dataclass(frozen=True)
class PairedComparison(Result):
    """Condition A against condition B within the same subjects, per frequency.

    Attributes:
        names: the two conditions' names (A, B). pairs: ((A member, B member), ...) names,
        one per subject (n). frequencies_hz: (F,) Hz. channels: (M,).
        p_value: the whole FRF's (every frequency and channel). statistic: its T = Σ Q.
        statistics, p_values, p_adjusted: (F, M) each frequency's Q, p-value and max-T
        adjusted p-value.
        gain_ratio_percent, gain_ratio_low, gain_ratio_high: (F, M) the geometric mean of
        |H_B|/|H_A| (%) with its ``level`` interval.
        phase_difference_deg, phase_low, phase_high: (F, M) mean ∠(H_B/H_A) (degrees) with
        its interval.
        patterns: sign patterns used; exact: all 2ⁿ enumerated. level: the intervals'.
    """

    names: tuple[str, str]
    pairs: tuple[tuple[str, str], ...]
    frequencies_hz: np.ndarray = field(repr=False)
    channels: tuple[str, ...]
    p_value: float
    statistic: float
    statistics: np.ndarray = field(repr=False)
    p_values: np.ndarray = field(repr=False)
    p_adjusted: np.ndarray = field(repr=False)
    gain_ratio_percent: np.ndarray = field(repr=False)
    gain_ratio_low: np.ndarray = field(repr=False)
    gain_ratio_high: np.ndarray = field(repr=False)
    phase_difference_deg: np.ndarray = field(repr=False)
    phase_low: np.ndarray = field(repr=False)
    phase_high: np.ndarray = field(repr=False)
    patterns: int
    exact: bool
    level: float = 0.95
    seed: int = 0

    @property
    def size(self) -> int:
        """n, the subjects (pairs)."""
        return len(self.pairs)

    @property
    def p_value_max(self) -> float:
        """The whole FRF's p-value by the largest Q instead of their sum (the smallest
        max-T adjusted p-value): more powerful than the sum for a change at one frequency,
        less for one spread over many."""
        return float(np.min(self.p_adjusted))

    def differing(self, adjusted: bool = False, alpha: float = SIGNIFICANCE
                  ) -> dict[str, list[float]]:
        """Per channel, the frequencies (Hz) whose p-value (max-T adjusted with
        ``adjusted``) is below ``alpha``."""
        p = self.p_adjusted if adjusted else self.p_values
        return {c: [float(f) for f, pk in zip(self.frequencies_hz, p[:, m], strict=True)
                    if pk < alpha] for m, c in enumerate(self.channels)}

    def to_dict(self) -> dict:
        """JSON-ready (strict: a ratio that cannot be formed, a gain of 0, is null)."""
        from posture_id.provenance import provenance

        per_frequency = {
            c: [{"frequency_hz": float(f), "statistic": self.statistics[k, m],
                 "p_value": self.p_values[k, m], "p_adjusted": self.p_adjusted[k, m],
                 "gain_ratio_percent": self.gain_ratio_percent[k, m],
                 "gain_ratio_interval_percent": [self.gain_ratio_low[k, m],
                                                 self.gain_ratio_high[k, m]],
                 "phase_difference_deg": self.phase_difference_deg[k, m],
                 "phase_difference_interval_deg": [self.phase_low[k, m],
                                                   self.phase_high[k, m]]}
                for k, f in enumerate(self.frequencies_hz)]
            for m, c in enumerate(self.channels)}
        return jsonable({
            "paired": True, "groups": list(self.names), "pairs": self.size,
            "subjects": [list(p) for p in self.pairs],
            "test": "sign-flip permutation test of d = H_A − H_B; Q = |Σd|²/Σ|d|² per "
                    "frequency, the whole FRF by ΣQ",
            "p_value": self.p_value, "statistic": self.statistic,
            "p_value_max": self.p_value_max, "patterns": self.patterns,
            "exact": self.exact, "level": self.level, "seed": self.seed,
            "frequencies_hz": self.frequencies_hz, "channels": list(self.channels),
            "differ_at_5_percent_hz": self.differing(),
            "differ_at_5_percent_adjusted_hz": self.differing(adjusted=True),
            "per_frequency": per_frequency, "provenance": provenance()})

    def summary(self) -> str:
        a, b = self.names
        how = (f"exact: all {self.patterns} sign patterns" if self.exact
               else f"{self.patterns} random sign patterns")
        lines = [f"{a} against {b}, {self.size} subjects in both (paired): whole FRF p = "
                 f"{self.p_value:.4f} (sign-flip test of the summed Q, {how}; by the "
                 f"largest Q p = {self.p_value_max:.4f})"]
        level = f"{100 * self.level:.0f} %"
        gain, phase = f"gain {b}/{a} (%)", f"phase {b} − {a} (°)"
        width = max(len(gain), len(phase), 24)
        for m, channel in enumerate(self.channels):
            lines.append(f"  {channel} (mean [{level} interval]; * p < 0.05):")
            lines.append(f"    {'f (Hz)':>7}  {gain:<{width}}  {phase:<{width}}  "
                         f"{'p':>7}   p (max-T)")
            for k, f in enumerate(self.frequencies_hz):
                mark = "*" if self.p_values[k, m] < SIGNIFICANCE else " "
                g = (f"{self.gain_ratio_percent[k, m]:.1f} [{self.gain_ratio_low[k, m]:.1f}, "
                     f"{self.gain_ratio_high[k, m]:.1f}]")
                ph = (f"{self.phase_difference_deg[k, m]:.1f} [{self.phase_low[k, m]:.1f}, "
                      f"{self.phase_high[k, m]:.1f}]")
                lines.append(f"    {f:7.3g}  {g:<{width}}  {ph:<{width}}  "
                             f"{self.p_values[k, m]:7.4f}{mark}  {self.p_adjusted[k, m]:.4f}")
        for channel in self.channels:
            plain = self.differing()[channel]
            adjusted = self.differing(adjusted=True)[channel]
            lines.append(f"  {channel}: differ at 5 % at "
                         + (", ".join(f"{f:g} Hz" for f in plain) or "no frequency")
                         + " (uncorrected); adjusted for the "
                         f"{self.p_values.size} frequencies × channels (max-T): "
                         + (", ".join(f"{f:g} Hz" for f in adjusted) or "none"))
        return "\n".join(lines)

    def plot(self, path=None, ax=None):
        """The mean gain ratio and phase difference per frequency with their intervals, the
        frequencies that differ at 5 % marked (:func:`~posture_id.plotting.
        plot_paired_difference`)."""
        from posture_id.plotting import plot_paired_difference

        return plot_paired_difference(self, path=path, ax=ax)


def compare_paired(a: FrfSet, b: FrfSet, names: tuple[str, str] = ("A", "B"),
                   permutations: int = 2000, level: float = 0.95,
                   seed: int = 0) -> PairedComparison:
    """Condition ``a`` against condition ``b`` within subjects (the module doc).

    Args:
        a: condition A's FRFs (:class:`FrfSet`, n subjects, F frequencies, M channels).
        b: condition B's, the i-th member the same subject as ``a``'s i-th, at the same
            frequencies and channels.
        names: the two conditions' names, A's first.
        permutations: N; all 2ⁿ sign patterns are enumerated when 2ⁿ ≤ N, else N drawn.
        level: the intervals' coverage (0–1, default 0.95).
        seed: seeds the drawn sign patterns.
    Returns:
        :class:`PairedComparison`: the whole FRF's p-value, and per frequency and channel
        (F, M) the p-value, the mean gain ratio B/A (%) and phase difference B − A (°) with
        their intervals.
    Raises:
        PostureIdError: groups of unequal sizes (naming both counts), fewer than 2 pairs,
            other frequencies or channels, a level outside 0–1.
    """
    names = (str(names[0]), str(names[1]))
    _check_pairs(len(a), len(b), names, "FRF")
    _check_level(level)
    if a.frequencies_hz.shape != b.frequencies_hz.shape or not np.allclose(
            a.frequencies_hz, b.frequencies_hz, atol=1e-6):
        raise PostureIdError(f"the two conditions' FRFs are at different frequencies: "
                             f"{names[0]} at {np.round(a.frequencies_hz, 3).tolist()} Hz, "
                             f"{names[1]} at {np.round(b.frequencies_hz, 3).tolist()} Hz")
    if tuple(a.channels) != tuple(b.channels):
        raise PostureIdError(f"the conditions' channels differ: {names[0]} has "
                             f"{', '.join(a.channels)}, {names[1]} {', '.join(b.channels)}")
    ha, hb = np.asarray(a.response, complex), np.asarray(b.response, complex)  # (n, F, M)
    n, f, m = ha.shape
    test = sign_flip_test((ha - hb).reshape(n, f * m), permutations, seed)
    with np.errstate(divide="ignore", invalid="ignore"):
        log_ratio = np.log(np.abs(hb)) - np.log(np.abs(ha))
        phase = np.angle(hb / ha)  # rad, (−π, π]
    gain, gain_low, gain_high = (100 * np.exp(x) for x in _t_interval(log_ratio, level))
    centre = np.angle(np.nansum(np.exp(1j * phase), axis=0))
    centred = np.angle(np.exp(1j * (phase - centre)))
    phase_mean, phase_low, phase_high = (np.degrees(centre + x)
                                         for x in _t_interval(centred, level))

    def shaped(x: np.ndarray) -> np.ndarray:
        return np.asarray(x, float).reshape(f, m)

    return PairedComparison(
        names, tuple(zip(a.names, b.names, strict=True)),
        np.asarray(a.frequencies_hz, float), tuple(a.channels), test.global_p,
        test.global_statistic, shaped(test.statistic), shaped(test.p_values),
        shaped(test.p_adjusted), gain, gain_low, gain_high, phase_mean, phase_low,
        phase_high, test.patterns, test.exact, level, seed)


@dataclass(frozen=True)
class PairedParameterComparison(Result):
    """Identified parameters of two conditions within the same subjects.

    Attributes:
        names: the conditions (A, B). pairs: ((A result, B result), ...), one per subject.
        rows: per parameter {"parameter", "mean_a", "mean_b", "difference" (mean of
        A − B), "low", "high" (its ``level`` interval), "statistic" (Q), "p_value",
        "p_adjusted" (max-T over the parameters)}; SI units of the parameter.
        p_value: every parameter at once (T = Σ Q under the same sign patterns).
        patterns: sign patterns used; exact: all 2ⁿ enumerated.
    """

    names: tuple[str, str]
    pairs: tuple[tuple[str, str], ...]
    rows: tuple[dict, ...]
    p_value: float
    patterns: int
    exact: bool
    level: float = 0.95

    @property
    def sizes(self) -> tuple[int, int]:
        """(n, n): the subjects in each condition (as :class:`ParameterComparison`)."""
        return (len(self.pairs), len(self.pairs))

    def to_dict(self) -> dict:
        from posture_id.provenance import provenance

        return jsonable({"paired": True, "groups": list(self.names),
                         "pairs": len(self.pairs), "subjects": [list(p) for p in self.pairs],
                         "test": "sign-flip permutation test of each parameter's "
                                 "within-subject difference A − B",
                         "p_value": self.p_value, "patterns": self.patterns,
                         "exact": self.exact, "level": self.level,
                         "parameters": list(self.rows), "provenance": provenance()})

    def summary(self) -> str:
        a, b = self.names
        how = (f"exact: all {self.patterns} sign patterns" if self.exact
               else f"{self.patterns} random sign patterns")
        lines = [f"{a} against {b}, {len(self.pairs)} subjects in both (paired): every "
                 f"parameter at once p = {self.p_value:.4f} (sign-flip test, {how})",
                 f"{'parameter':<16}{'mean ' + a:>14}{'mean ' + b:>14}{a + ' − ' + b:>12}  "
                 f"{100 * self.level:.0f} % interval       p  p (max-T)"]
        for r in self.rows:
            mark = "*" if r["p_value"] < SIGNIFICANCE else " "
            lines.append(f"{r['parameter']:<16}{r['mean_a']:>14.4g}{r['mean_b']:>14.4g}"
                         f"{r['difference']:>12.4g}  [{r['low']:.4g}, {r['high']:.4g}]  "
                         f"{r['p_value']:.4f}{mark} {r['p_adjusted']:.4f}")
        differ = [r["parameter"] for r in self.rows if r["p_value"] < SIGNIFICANCE]
        lines.append("differ at 5 % (uncorrected): " + (", ".join(differ) or "none"))
        return "\n".join(lines)

    def plot(self, path=None, ax=None):
        """Each parameter's mean difference with its interval, relative to B's mean."""
        from posture_id.plotting import plot_parameter_differences

        return plot_parameter_differences(self, path=path, ax=ax)


def compare_paired_parameters(a: IdentifiedGroup, b: IdentifiedGroup,
                              names: tuple[str, str] = ("A", "B"), permutations: int = 2000,
                              level: float = 0.95, seed: int = 0
                              ) -> PairedParameterComparison:
    """Condition ``a`` against ``b`` within subjects, parameter by parameter (the module
    doc): each parameter's differences A − B tested by :func:`sign_flip_test`, every
    parameter under the same sign patterns.

    Args:
        a: condition A's identified subjects (:func:`~posture_id.norms.parameters.
            read_identified`), n of them. b: condition B's, the i-th the same subject.
        names: the conditions' names. permutations: N (2ⁿ ≤ N: exact). level: the mean
        difference's interval (t-based). seed: seeds the drawn sign patterns.
    Returns:
        :class:`PairedParameterComparison`.
    Raises:
        PostureIdError: unequal sizes (naming both counts), fewer than 2 pairs, results of
            bodies with other joints, a level outside 0–1.
    """
    names = (str(names[0]), str(names[1]))
    _check_pairs(len(a.names), len(b.names), names, "result")
    _check_level(level)
    if set(a.values) != set(b.values):
        raise PostureIdError(f"the two conditions' results are of bodies with other joints "
                             f"({names[0]}: {', '.join(a.values)}; {names[1]}: "
                             f"{', '.join(b.values)})")
    keys = list(a.values)
    va = np.stack([a.values[k] for k in keys], axis=1)  # (n, P)
    vb = np.stack([b.values[k] for k in keys], axis=1)
    test = sign_flip_test(va - vb, permutations, seed)
    mean, low, high = _t_interval(va - vb, level)
    rows = tuple({"parameter": key, "mean_a": float(va[:, j].mean()),
                  "mean_b": float(vb[:, j].mean()), "difference": float(mean[j]),
                  "low": float(low[j]), "high": float(high[j]),
                  "statistic": float(test.statistic[j]), "p_value": float(test.p_values[j]),
                  "p_adjusted": float(test.p_adjusted[j])} for j, key in enumerate(keys))
    return PairedParameterComparison(names, tuple(zip(a.names, b.names, strict=True)), rows,
                                     test.global_p, test.patterns, test.exact, level)
