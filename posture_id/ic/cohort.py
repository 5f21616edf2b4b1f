"""``posture-id compare DIR_OR_GLOB --out FOLDER``: DEC against IC on every recording of a
cohort: ``<recording>.json`` each (the comparison) and ``summary.csv`` (one row per
recording: the preferred model, ΔBIC, whether each model is within the noise, the IC
parameters and each DEC module's Kp, Kd and delay). Each JSON records the options it was
made with (``"cohort_options"``: the fit's flags, the held-out cycle, the stimulus, the
columns, the body): a recording already compared with the same options is not compared
again (a killed run goes on), one compared with other options is compared again and the
summary says which options changed; one that cannot be read gets its reason in the
summary while the others go on."""

from __future__ import annotations

import csv
import io
import json
from dataclasses import dataclass, field
from pathlib import Path

from posture_id.errors import PostureIdError
from posture_id.fileio import Result, atomic_write_text, json_text
from posture_id.ic.compare import compare_models
from posture_id.ic.fit import IcFitOptions
from posture_id.progress import Progress, report

__all__ = ["CompareCohort", "compare_cohort", "SUMMARY_FIELDS"]

SUMMARY_FIELDS = ("recording", "status", "preferred", "delta_bic_ic_minus_dec",
                  "dec_within_noise", "ic_within_noise", "ic_kp", "ic_kd", "ic_delay_s",
                  "ic_w", "ic_torque_feedback_gain", "ic_torque_feedback_time_s")


@dataclass(frozen=True)
class CompareCohort(Result):
    """out: the folder. rows: ``summary.csv``'s rows (dicts). changed: per recording
    compared again, the options that differed from its earlier comparison's."""

    out: Path
    rows: tuple[dict, ...]
    changed: dict[str, tuple[str, ...]] = field(default_factory=dict)

    @property
    def failed(self) -> dict[str, str]:
        return {r["recording"]: r["status"] for r in self.rows
                if r["status"] not in ("done", "skipped", "redone")}

    @property
    def doubtful(self) -> tuple[str, ...]:
        """Recordings that neither model explains within the noise."""
        return tuple(r["recording"] for r in self.rows if r.get("dec_within_noise") is False
                     and r.get("ic_within_noise") is False)

    def to_dict(self) -> dict:
        return {"out": str(self.out), "rows": list(self.rows)}

    def summary(self) -> str:
        counts = {m: sum(r.get("preferred") == m for r in self.rows)
                  for m in ("dec", "ic", "undecided")}
        return (f"{self.out}: {len(self.rows)} recordings: DEC preferred {counts['dec']}, IC "
                f"{counts['ic']}, undecided {counts['undecided']}, failed {len(self.failed)}"
                + "".join(f"\n  {k}: compared again, its options changed: {', '.join(v)}"
                          for k, v in self.changed.items())
                + "".join(f"\n  {k}: {v}" for k, v in self.failed.items())
                + (f"\n  neither model within the noise: {', '.join(self.doubtful)}"
                   if self.doubtful else ""))

    def plot(self, path=None, ax=None):
        """ΔBIC (IC − DEC) per recording: below −10 IC, above +10 DEC, between undecided."""
        from posture_id.plotting import plot_delta_bic

        done = [r for r in self.rows if r.get("delta_bic_ic_minus_dec") is not None]
        return plot_delta_bic([r["recording"] for r in done],
                              [r["delta_bic_ic_minus_dec"] for r in done],
                              [r["preferred"] for r in done], path=path, ax=ax)


def _row(name: str, data: dict, status: str) -> dict:
    ic = data["ic"]["parameters"]
    row = {"recording": name, "status": status, "preferred": data["preferred"],
           "delta_bic_ic_minus_dec": data["delta_bic_ic_minus_dec"],
           "dec_within_noise": data["within_noise"]["dec"],
           "ic_within_noise": data["within_noise"]["ic"]}
    row.update({f"ic_{k}": ic[k] for k in ("kp", "kd", "delay_s", "w",
                                            "torque_feedback_gain", "torque_feedback_time_s")})
    for joint, m in data["dec"]["parameters"].items():
        row.update({f"dec_{joint}_kp": m["kp"], f"dec_{joint}_kd": m["kd"],
                    f"dec_{joint}_delay_s": m["delay_s"], f"dec_{joint}_controls": m["controls"]})
    return row


def compare_cohort(recordings: list[Path], out: Path, body, read, options: IcFitOptions,
                   held_out: bool = True, progress: Progress | None = None,
                   recorded: dict | None = None) -> CompareCohort:
    """Compare every recording into ``out``; ``read(path) -> PreparedTrial``.
    ``recorded``: JSON-ready options besides ``options`` and ``held_out`` that the results
    depend on (the stimulus, the columns, the body), kept in each JSON."""
    from posture_id.identify.cohort import option_differences

    wanted = json.loads(json_text({"--fit-ki": options.fit_ki,
                                   "--fit-passive": options.fit_passive,
                                   "--starts": options.starts, "--seed": options.seed,
                                   "--no-held-out": not held_out, **(recorded or {})}))
    out.mkdir(parents=True, exist_ok=True)
    rows, changed = [], {}
    report(progress, 0, len(recordings), "recording")
    for k, path in enumerate(recordings, 1):
        target = out / f"{path.stem}.json"
        try:
            earlier = json.loads(target.read_text(encoding="utf-8")) if target.exists() \
                else None
        except ValueError:
            earlier = None
        if earlier is not None and "preferred" in earlier and \
                earlier.get("cohort_options") == wanted:
            rows.append(_row(path.name, earlier, "skipped"))
        else:
            if earlier is not None and "preferred" in earlier:
                changed[path.name] = option_differences(earlier.get("cohort_options") or {},
                                                        wanted)
            try:
                result = compare_models(read(path), body, options, held_out=held_out)
            except PostureIdError as exc:
                rows.append({"recording": path.name, "status": str(exc)})
            else:
                data = {**result.to_dict(), "cohort_options": wanted}
                atomic_write_text(target, json_text(data))
                rows.append(_row(path.name, data, "redone" if path.name in changed
                                 else "done"))
        report(progress, k, len(recordings), "recording")
    fields = list(SUMMARY_FIELDS) + sorted({k for r in rows for k in r} - set(SUMMARY_FIELDS))
    text = io.StringIO()
    writer = csv.DictWriter(text, fields, lineterminator="\n")
    writer.writeheader()
    writer.writerows(rows)
    atomic_write_text(out / "summary.csv", text.getvalue())
    return CompareCohort(out, tuple(rows), changed)
