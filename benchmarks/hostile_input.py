"""Hostile input for the newer commands: protocol files, a lab's columns, cohorts,
design, stimulus, frf, the universal tools and evaluate, and (``tests/hostile_cases_newest.py``) C3D
trials, the IC model, compare and norms, each tried as a new user tries them, and each
outcome sorted by :func:`hostile_harness.run_case` (clear, handled, unclear, traceback,
silent, data loss, hang: :mod:`hostile_harness`).

Run:  .venv/bin/python benchmarks/hostile_input.py [--out docs/results/hostile_input]
                                                   [--only SUBSTRING] [--before ROWS_JSON]

Writes ``report.md`` (the counts per surface and every case's line) and ``rows.json``; a
journal there makes an interrupted run resumable, and records a case that never finished
(killed while inside code the time limit cannot interrupt) as a hang.
The cases and their material are ``tests/hostile_cases.py``'s; ``tests/test_hostile_newer.py``
runs every case and requires *clear* or *handled*.
The cases run in this process, each in a fresh folder (the current directory while it
runs); the shared material (recordings, a protocol, small data sets) is made once.
"""


from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

from hostile_cases import all_cases, make_material, run_case  # noqa: E402
from hostile_harness import OUTCOMES, Outcome, before_after  # noqa: E402

# ------------------------------------------------------------------------- journal
#: One JSON line per case started and per case finished: a run again goes on from there,
#: and a case started but never finished (the process killed while it ran, e.g. inside C
#: code the time limit cannot interrupt) is recorded as a hang.
JOURNAL = "hostile_input.journal"


def _journal_rows(journal: Path) -> dict[str, Outcome]:
    if not journal.exists():
        return {}
    rows, started = {}, []
    for line in journal.read_text(encoding="utf-8").splitlines():
        entry = json.loads(line)
        if "started" in entry:
            started.append(entry["started"])
        else:
            rows[entry["name"]] = Outcome(entry["name"], entry["surface"], entry["outcome"],
                                          entry["status"], entry["line"], entry["seconds"])
    for name in started:
        if name not in rows:
            surface = next(c.surface for c in all_cases() if c.name == name)
            rows[name] = Outcome(name, surface, "hang", None,
                                 "never finished: the process was stopped while it ran", 0.0)
    return rows


# ------------------------------------------------------------------------- report
def _report(rows: list[Outcome], seconds: float, command: str) -> str:
    surfaces = sorted({r.surface for r in rows})
    lines = ["# Hostile input: the newer commands", "",
             f"Made by `{command}` ({len(rows)} cases, {seconds:.0f} s).", "",
             "| surface | cases | " + " | ".join(OUTCOMES) + " |",
             "|---|---|" + "---|" * len(OUTCOMES)]
    for surface in [*surfaces, "all"]:
        mine = [r for r in rows if surface in ("all", r.surface)]
        counts = [sum(r.outcome == o for r in mine) for o in OUTCOMES]
        label = f"**{surface}**" if surface == "all" else surface
        lines.append(f"| {label} | {len(mine)} | " + " | ".join(map(str, counts)) + " |")
    lines += ["", "| case | surface | outcome | exit | the line |", "|---|---|---|---|---|"]
    for r in rows:
        text = r.line.replace("|", "\\|")
        lines.append(f"| {r.name} | {r.surface} | {r.outcome} | {r.status} | {text} |")
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--out", type=Path, default=ROOT / "docs/results/hostile_input")
    parser.add_argument("--only", help="run the cases whose name holds this")
    parser.add_argument("--before", type=Path,
                        help="rows.json of the same cases run on an earlier tree: the "
                             "report adds the counts before and after, per surface")
    args = parser.parse_args(argv)
    from posture_id.fileio import atomic_write_text, json_text

    before = (None if args.before is None
              else json.loads(args.before.read_text(encoding="utf-8")))  # read before the run
    cases = [c for c in all_cases() if args.only is None or args.only in c.name]
    args.out.mkdir(parents=True, exist_ok=True)
    journal = args.out / JOURNAL
    start = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="hostile-") as tmp:
        material = make_material(Path(tmp) / "material")
        done = _journal_rows(journal)
        rows = []
        for k, case in enumerate(cases, 1):
            if case.name in done:
                row = done[case.name]
            else:
                with journal.open("a", encoding="utf-8") as out:
                    out.write(json.dumps({"started": case.name}) + "\n")
                row = run_case(case, material, Path(tmp) / "case")
                with journal.open("a", encoding="utf-8") as out:
                    out.write(json.dumps(row.to_dict()) + "\n")
            rows.append(row)
            print(f"[{k}/{len(cases)}] {row.outcome:9s} {case.name}: {row.line[:150]}",
                  file=sys.stderr, flush=True)
    seconds = time.perf_counter() - start
    journal.unlink()
    command = ".venv/bin/python benchmarks/hostile_input.py" + (
        f" --before {args.before}" if args.before is not None else "")
    if args.only is None:
        report = _report(rows, seconds, command)
        if before is not None:
            report += (f"\n## Before and after\n\nThe cases also in `{args.before}` (the "
                       "same cases run on an earlier tree); each cell: "
                       + " / ".join(OUTCOMES) + ".\n\n" + before_after(before, rows))
        atomic_write_text(args.out / "report.md", report)
        atomic_write_text(args.out / "rows.json", json_text([r.to_dict() for r in rows]))
        print(f"wrote {args.out / 'report.md'}", file=sys.stderr)
    counts = {o: sum(r.outcome == o for r in rows) for o in OUTCOMES}
    print(json.dumps(counts))
    return 0


if __name__ == "__main__":
    sys.exit(main())
