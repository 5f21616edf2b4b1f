"""``posture-id compare DIR_OR_GLOB --out FOLDER``: DEC against IC (two models) on every
recording of a cohort, by the cohort runner (:mod:`posture_id.cohorts`):
``<recording>.json`` each (the comparison) and ``summary.csv`` (one row per recording:
the preferred model, ΔBIC, whether each model is within the noise, the IC
parameters and each DEC module's Kp, Kd and delay). Each JSON records the options it was
made with (``"cohort_options"``: the fit's flags, the held-out cycle, the stimulus, the
columns, the body): a recording already compared with the same options is not compared
again (a killed run goes on), one compared with other options is compared again and the
summary says which options changed; one that cannot be read gets its reason in the
summary while the others go on."""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

from posture_id.cohorts import (
    CohortRow,
    CohortTask,
    Journal,
    changed_and_failed,
    write_summary,
)
from posture_id.comparison.models import DEFAULT_MODELS, UNDECIDED, compare_models
from posture_id.fileio import Result, json_text
from posture_id.fitting.frequency import IcFitOptions
from posture_id.progress import Progress

__all__ = ["CompareCohort", "compare_cohort", "SUMMARY_FIELDS"]

SUMMARY_FIELDS = ("recording", "status", "preferred", "delta_bic_ic_minus_dec",
                  "dec_within_noise", "ic_within_noise", "ic_kp", "ic_kd", "ic_delay_s",
                  "ic_w", "ic_torque_feedback_gain", "ic_torque_feedback_time_s")


@dataclass(frozen=True)
class CompareCohort(Result):
    """out: the folder. rows: ``summary.csv``'s rows (:class:`~posture_id.cohorts.CohortRow`).
    changed: per recording compared again, the options that differed from its earlier
    comparison's. models: the two models compared."""

    out: Path
    rows: tuple[CohortRow, ...]
    changed: dict[str, tuple[str, ...]] = field(default_factory=dict)
    models: tuple = DEFAULT_MODELS

    @property
    def failed(self) -> dict[str, str]:
        return {r.recording: r.status for r in self.rows if not r.finished}

    @property
    def doubtful(self) -> tuple[str, ...]:
        """Recordings that neither model explains within the noise."""
        return tuple(r.recording for r in self.rows
                     if r.finished and not any(r.get(f"{m.name}_within_noise")
                                               for m in self.models))

    def to_dict(self) -> dict:
        return {"out": str(self.out), "rows": [r.as_dict() for r in self.rows]}

    def summary(self) -> str:
        names = [m.name for m in self.models] + [UNDECIDED]
        counts = {m: sum(r.get("preferred") == m for r in self.rows) for m in names}
        first, second = self.models
        return (f"{self.out}: {len(self.rows)} recordings: {first.label} preferred "
                f"{counts[first.name]}, {second.label} {counts[second.name]}, undecided "
                f"{counts[UNDECIDED]}, failed {len(self.failed)}"
                + changed_and_failed(self.changed, self.failed, "compared")
                + (f"\n  neither model within the noise: {', '.join(self.doubtful)}"
                   if self.doubtful else ""))

    def plot(self, path=None, ax=None):
        """ΔBIC (IC − DEC) per recording: below −10 IC, above +10 DEC, between undecided."""
        from posture_id.plotting import plot_delta_bic

        first, second = self.models
        key = f"delta_bic_{second.name}_minus_{first.name}"
        done = [r for r in self.rows if r.get(key) is not None]
        return plot_delta_bic([r.recording for r in done], [r[key] for r in done],
                              [r["preferred"] for r in done], path=path, ax=ax)


def _row(data: dict) -> dict:
    """A comparison's columns of summary.csv: the verdict, ΔBIC, whether each model is
    within the noise, and each model's parameters (a DEC module's Kp, Kd, delay, class)."""
    delta = next(k for k in data if k.startswith("delta_bic_"))
    within = data["within_noise"]
    row = {"preferred": data["preferred"], delta: data[delta],
           **{f"{m}_within_noise": v for m, v in within.items()}}
    for model in within:
        params = data[model]["parameters"]
        if params.get("model") is not None:  # one set of named parameters
            row.update({f"{model}_{k}": v for k, v in params.items()
                        if k not in ("model", "ki", "kpas", "bpas")})
        else:  # a module per joint
            for joint, m in params.items():
                row.update({f"{model}_{joint}_kp": m["kp"], f"{model}_{joint}_kd": m["kd"],
                            f"{model}_{joint}_delay_s": m["delay_s"],
                            f"{model}_{joint}_controls": m["controls"]})
    return row


def compare_cohort(recordings: list[Path], out: Path, body, read, options: IcFitOptions,
                   held_out: bool = True, progress: Progress | None = None,
                   recorded: dict | None = None, models: tuple = DEFAULT_MODELS
                   ) -> CompareCohort:
    """Compare every recording into ``out``; ``read(path) -> PreparedTrial``.
    ``recorded``: JSON-ready options besides ``options`` and ``held_out`` that the results
    depend on (the stimulus, the columns, the body), kept in each JSON."""
    wanted = json.loads(json_text({"--fit-ki": options.fit_ki,
                                   "--fit-passive": options.fit_passive,
                                   "--starts": options.starts, "--seed": options.seed,
                                   "--no-held-out": not held_out, **(recorded or {})}))
    journal = Journal(out, CohortTask("preferred", lambda path: wanted, _row))

    def work(path: Path) -> dict:
        return compare_models(read(path), body, options, held_out=held_out,
                              models=models).to_dict()

    journal.run(recordings, work, progress)
    rows = journal.rows(recordings)
    fields = list(SUMMARY_FIELDS) + sorted({k for r in rows for k in r.as_dict()}
                                           - set(SUMMARY_FIELDS))
    write_summary(journal.out / "summary.csv", rows, fields)
    return CompareCohort(journal.out, tuple(rows), journal.redone, tuple(models))
