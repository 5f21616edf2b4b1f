"""Two groups of identified subjects, parameter by parameter
(``posture-id norm compare --group A/*.json --group B/*.json`` on ``identify`` results).

For each module's Kp, Ki, Kd and delay: each subject's value with its interval (the
calibrated interval of its answer, its half-width taken as z·SE at the interval's level),
each group's inverse-variance weighted mean (a subject the recording pinned weighs more
than one it left loose), their difference with a bootstrap confidence interval (subjects
resampled in each group, their own uncertainty drawn anew from their intervals), and a
permutation test of the difference of the weighted means (labels shuffled).
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.stats import norm as normal

from posture_id.errors import PostureIdError
from posture_id.fileio import Result

__all__ = ["IdentifiedGroup", "ParameterComparison", "read_identified", "compare_parameters"]

FIELDS = ("kp", "ki", "kd", "delay_s")


@dataclass(frozen=True)
class IdentifiedGroup:
    """values, sds: {"<joint> <field>": (N,)}; names: (N,)."""

    values: dict
    sds: dict
    names: tuple[str, ...]


def read_identified(paths: list[Path]) -> IdentifiedGroup:
    """The identified parameters and their intervals of ``identify`` result JSONs."""
    values: dict[str, list] = {}
    sds: dict[str, list] = {}
    for path in paths:
        try:
            data = json.loads(Path(path).read_text(encoding="utf-8"))
        except (OSError, ValueError) as exc:
            raise PostureIdError(f"{path}: not a result JSON ({exc})") from None
        intervals = (data.get("intervals") or {}) if isinstance(data, dict) else {}
        if "parameters" not in data or "modules" not in intervals:
            raise PostureIdError(f"{path}: an identify result with intervals is needed "
                                 "(posture-id identify ... --out FILE.json)")
        z = float(normal.ppf(0.5 + float(intervals.get("level", 0.9)) / 2))
        for joint, module in data["parameters"].items():
            for field in FIELDS:
                key = f"{joint} {field}"
                box = intervals["modules"].get(joint, {}).get(field, {})
                sd = (box.get("upper_si", np.nan) - box.get("lower_si", np.nan)) / (2 * z)
                values.setdefault(key, []).append(float(module[field]))
                sds.setdefault(key, []).append(float(sd))
    lengths = {len(v) for v in values.values()}
    if len(lengths) != 1:
        raise PostureIdError("the results are of bodies with other joints: compare one "
                             "body's cohort at a time")
    return IdentifiedGroup({k: np.array(v) for k, v in values.items()},
                           {k: np.array(v) for k, v in sds.items()},
                           tuple(Path(p).stem for p in paths))


def _weighted_mean(v: np.ndarray, sd: np.ndarray) -> float:
    w = np.where(np.isfinite(sd) & (sd > 0), 1 / np.maximum(sd, 1e-12) ** 2, 0.0)
    return float(np.sum(w * v) / np.sum(w)) if np.sum(w) > 0 else float(np.mean(v))


@dataclass(frozen=True)
class ParameterComparison(Result):
    """rows: per parameter, {"parameter", "mean_a", "mean_b", "difference", "low",
    "high", "p_value"}."""

    names: tuple[str, str]
    sizes: tuple[int, int]
    rows: tuple[dict, ...]
    level: float = 0.95

    def to_dict(self) -> dict:
        from posture_id.provenance import provenance

        return {"groups": list(self.names), "sizes": list(self.sizes), "level": self.level,
                "parameters": list(self.rows), "provenance": provenance()}

    def summary(self) -> str:
        a, b = self.names
        lines = [f"{a} ({self.sizes[0]}) against {b} ({self.sizes[1]}), weighted by each "
                 "subject's interval:",
                 f"{'parameter':<16}{'mean ' + a:>14}{'mean ' + b:>14}{'difference':>12}  "
                 f"{100 * self.level:.0f} % interval       p"]
        for r in self.rows:
            lines.append(f"{r['parameter']:<16}{r['mean_a']:>14.4g}{r['mean_b']:>14.4g}"
                         f"{r['difference']:>12.4g}  [{r['low']:.4g}, {r['high']:.4g}]  "
                         f"{r['p_value']:.4f}")
        return "\n".join(lines)

    def plot(self, path=None, ax=None):
        from posture_id.plotting import plot_parameter_differences

        return plot_parameter_differences(self, path=path, ax=ax)


def compare_parameters(a: IdentifiedGroup, b: IdentifiedGroup,
                       names: tuple[str, str] = ("A", "B"), permutations: int = 2000,
                       bootstrap: int = 1000, level: float = 0.95,
                       seed: int = 0) -> ParameterComparison:
    """Group ``a`` against ``b``, parameter by parameter (the module doc)."""
    if set(a.values) != set(b.values):
        raise PostureIdError("the two groups' results are of bodies with other joints")
    if len(a.names) < 2 or len(b.names) < 2:
        raise PostureIdError("comparing groups needs at least 2 results each")
    rng = np.random.default_rng(seed)
    rows = []
    for key in a.values:
        va, sa, vb, sb = a.values[key], a.sds[key], b.values[key], b.sds[key]
        observed = _weighted_mean(va, sa) - _weighted_mean(vb, sb)
        v, s = np.concatenate([va, vb]), np.concatenate([sa, sb])
        n = len(va)
        exceed = 0
        for _ in range(permutations):
            order = rng.permutation(len(v))
            first, second = order[:n], order[n:]
            diff = _weighted_mean(v[first], s[first]) - _weighted_mean(v[second], s[second])
            exceed += abs(diff) >= abs(observed)
        diffs = []
        for _ in range(bootstrap):
            ia, ib = rng.integers(0, len(va), len(va)), rng.integers(0, len(vb), len(vb))
            da = va[ia] + rng.standard_normal(len(ia)) * np.nan_to_num(sa[ia])
            db = vb[ib] + rng.standard_normal(len(ib)) * np.nan_to_num(sb[ib])
            diffs.append(_weighted_mean(da, sa[ia]) - _weighted_mean(db, sb[ib]))
        low, high = np.quantile(diffs, [(1 - level) / 2, (1 + level) / 2])
        rows.append({"parameter": key, "mean_a": _weighted_mean(va, sa),
                     "mean_b": _weighted_mean(vb, sb), "difference": observed,
                     "low": float(low), "high": float(high),
                     "p_value": (1 + exceed) / (1 + permutations)})
    return ParameterComparison(tuple(names), (len(a.names), len(b.names)), tuple(rows), level)
