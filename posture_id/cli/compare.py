"""``posture-id compare``: DEC and the independent-channel model fitted to one recording,
and which of the two its sway supports (docs/model.md §8; docs/ic.md)."""

from __future__ import annotations

import argparse
from pathlib import Path

from posture_id.bodies.body import DEFAULT_URDF, load_body
from posture_id.cli.arguments import (
    check_out_and_plot,
    is_cohort,
    non_negative_int,
    positive_int,
    write_result,
)
from posture_id.cli.exit_status import answered
from posture_id.cli.markers import recording_body
from posture_id.cli.progress import TerminalProgress
from posture_id.cli.stimulus import (
    add_recording_arguments,
    columns_from_args,
    prepared_trial,
    stimulus_from_args,
)
from posture_id.errors import PostureIdError

__all__ = ["add_parser"]


def add_parser(sub) -> None:
    p = sub.add_parser("compare", help="fit DEC and the independent-channel (IC) model to a "
                                       "recording; say which its sway supports")
    p.add_argument("recording", help="recording CSV (time_s,tilt_deg,<seg>_deg...); a folder "
                                    "or a glob pattern compares a cohort into the --out folder")
    p.add_argument("--body", type=Path, help="URDF (default: the TIP)")
    p.add_argument("--out", type=Path, help="comparison JSON (\"preferred\": dec, ic or "
                                           "undecided, with both models' parameters); for a "
                                           "cohort, a folder: one JSON per recording and "
                                           "summary.csv")
    p.add_argument("--plot", type=Path, help="the locked COM sway at every compared harmonic "
                                            "with both models over it (PNG)")
    p.add_argument("--fit-ki", action="store_true", help="the IC model's Ki identified too")
    p.add_argument("--fit-passive", action="store_true",
                   help="the IC model's passive stiffness and damping identified too")
    p.add_argument("--starts", type=positive_int, default=6,
                   help="IC fit starts (default %(default)d)")
    p.add_argument("--seed", type=non_negative_int, default=0, help="seed (default 0)")
    p.add_argument("--second", type=Path, metavar="RECORDING",
                   help="the same subject at the second amplitude of a two-amplitude "
                        "protocol (--protocol FILE gives each part its stimulus; without "
                        "it each recording's tilt says): DEC with one set of parameters for "
                        "both, IC with a W per amplitude")
    p.add_argument("--no-held-out", action="store_true",
                   help="skip the held-out cycle (two fits fewer; the BIC alone decides)")
    add_recording_arguments(p)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    if is_cohort(args.recording):
        return run_cohort(args)
    args.recording = Path(args.recording)
    check_out_and_plot(args, (args.recording, args.body, args.tilt, args.second))
    from posture_id.comparison.models import compare_amplitudes, compare_models

    if args.second is None:
        body = recording_body(args, DEFAULT_URDF)
        trials = [prepared_trial(args, body)]
    else:
        body, trials = _amplitude_trials(args)
    with TerminalProgress(prefix="posture-id compare", quiet=True) as progress:
        result = (compare_models(trials[0], body, _ic_options(args), progress,
                                 not args.no_held_out) if args.second is None
                  else compare_amplitudes(trials, body, _ic_options(args), progress))
    write_result(result, args.out, args.plot)
    return answered(result.doubtful)


def run_cohort(args: argparse.Namespace) -> int:
    """Every recording of a folder or pattern, into the --out folder."""
    from posture_id.cli.output_folder import cohort_folder
    from posture_id.comparison.cohort import compare_cohort
    from posture_id.identify.cohort import find_recordings, stimulus_record

    if args.plot:
        raise PostureIdError("--plot is for one recording; a cohort writes JSON per recording "
                             "and summary.csv")
    if args.second is not None:
        raise PostureIdError("--second goes with one recording (the same subject's second "
                             "amplitude), not with a folder or pattern")
    if args.out is None:
        raise PostureIdError(f"{args.recording}: a cohort's comparisons need a folder: --out "
                             "FOLDER")
    recordings = find_recordings(args.recording)
    with cohort_folder(args, recordings):
        body = load_body(args.body or DEFAULT_URDF)

        def read(path: Path):
            args.recording = path
            return prepared_trial(args, body)

        options = _ic_options(args)
        recorded = {"stimulus": stimulus_record(stimulus_from_args(args, default=None)),
                    "columns": columns_from_args(args), "body_sha256": body.sha256}
        with TerminalProgress("recordings", prefix="posture-id compare") as progress:
            result = compare_cohort(recordings, args.out, body, read, options,
                                    not args.no_held_out, progress, recorded)
    print(result.summary())
    return answered(bool(result.failed or result.doubtful))


def _amplitude_trials(args: argparse.Namespace) -> tuple:
    """``--second``: the body and the two parts of a two-amplitude protocol (compared at
    once), each prepared with its part's stimulus."""
    if args.part is not None:
        raise PostureIdError("--part: with --second each recording is its own part (the "
                             "first 1, the second 2)")
    if args.second.resolve() == args.recording.resolve():
        raise PostureIdError(f"--second {args.second}: the recording itself; give the same "
                             "subject's recording at the protocol's other amplitude")
    body = load_body(args.body or DEFAULT_URDF)
    trials = []
    for part, path in enumerate((args.recording, args.second), 1):
        args.recording, args.part = path, (part if args.protocol else None)
        trials.append(prepared_trial(args, body))
    _two_amplitudes(*(t.recording for t in trials))
    return body, trials


def _ic_options(args: argparse.Namespace):
    """The IC fit's options from the flags."""
    from posture_id.fitting.frequency import IcFitOptions

    return IcFitOptions(fit_ki=args.fit_ki, fit_passive=args.fit_passive,
                        starts=args.starts, seed=args.seed)


#: The larger tilt's RMS over the smaller's below which two recordings are one amplitude.
SAME_AMPLITUDE_RATIO = 1.1


def _two_amplitudes(first, second) -> None:
    """Refuse a --second that is the first recording again (the same samples) or was made
    at the same amplitude: re-weighting shows between two amplitudes only."""
    import numpy as np

    if first.theta.shape == second.theta.shape and np.array_equal(first.theta, second.theta) \
            and np.array_equal(first.tilt, second.tilt):
        raise PostureIdError(f"--second {second.name}: the same samples as {first.name} (a "
                             "copy?); give the same subject's recording at the other amplitude")
    rms = [float(np.degrees(np.std(r.tilt))) for r in (first, second)]
    if max(rms) < SAME_AMPLITUDE_RATIO * min(rms):
        raise PostureIdError(
            f"--second {second.name}: its tilt has the amplitude of {first.name}'s "
            f"({rms[1]:.3g}° and {rms[0]:.3g}° RMS): a two-amplitude comparison needs the "
            "protocol's two amplitudes (sensory re-weighting shows between them)")
