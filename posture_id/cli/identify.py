"""``posture-id identify``: DEC parameters of a recording (CNN, least squares or both)."""

from __future__ import annotations

import argparse
from functools import cache
from pathlib import Path

from posture_id.bodies.body import DEFAULT_URDF, load_body
from posture_id.cli.arguments import (
    check_out_and_plot,
    interval_level,
    is_cohort,
    say,
    write_result,
)
from posture_id.cli.exit_status import answered
from posture_id.cli.fit import add_search_arguments, search_flags_given, search_keywords
from posture_id.cli.markers import recording_body
from posture_id.cli.norm import norm_bands
from posture_id.cli.output_folder import cohort_folder
from posture_id.cli.progress import TerminalProgress
from posture_id.cli.stimulus import (
    add_recording_arguments,
    columns_from_args,
    prepared_trial,
    recording_and_stimulus,
    stimulus_from_args,
)
from posture_id.errors import PostureIdError
from posture_id.fitting.options import FitOptions
from posture_id.motion_capture.mapping import MarkerMapping

__all__ = ["add_parser"]

METHODS = ("cnn", "fit", "hybrid", "auto")
#: identify.core.DEFAULT_METHOD, named here without importing torch (a test keeps them equal)
DEFAULT_METHOD_NAME = "auto"


def add_parser(sub) -> None:
    p = sub.add_parser(
        "identify", help="identify DEC (or IC) parameters of a recording or a cohort")
    p.add_argument("recording",
                   help="recording CSV (time_s,tilt_deg,<seg>_deg...); a folder or a glob "
                        "pattern identifies a cohort into the --out folder")
    p.add_argument("--body", type=Path, help="URDF (default: the TIP)")
    p.add_argument("--model", choices=("dec", "ic"), default="dec",
                   help="the model identified: dec (default) or ic, the independent-channel "
                        "model fitted to the stimulus-locked body COM sway (as fit --model "
                        "ic; compare sets the two side by side)")
    p.add_argument("--network", type=Path, metavar="DIR",
                   help="the network's folder: a universal model or a per-body specialist "
                        "(default: the bundled universal model)")
    p.add_argument("--method", choices=METHODS, default=DEFAULT_METHOD_NAME,
                   help="cnn: the network alone, milliseconds; fit: least squares "
                        "from the defaults; hybrid: least squares from the CNN's answer; "
                        "auto: the network, then the hybrid where its answer is doubtful "
                        "and the sway is not people-like (on the stimulus-locked sway when "
                        "the recording is too noisy to check an answer; on one cycle, such "
                        "an answer is kept); on people-like sway where it falls or leaves "
                        "more than the noise, the locked fit with the network's spread as "
                        "the prior; a stimulus named but not recorded is moved to where "
                        "the sway says it ran (default %(default)s)")
    p.add_argument("--out", type=Path,
                   help="result JSON (its \"parameters\" object is a parameter file); for a "
                        "cohort, a folder: one JSON per recording and summary.csv (needed "
                        "there). Without it one recording's result is printed only")
    p.add_argument("--scheduler", help="cohort: Dask distributed scheduler (tcp://host:port)")
    p.add_argument("--bodies", type=Path,
                   help="cohort: a folder of the subjects' own bodies, <recording name>.urdf "
                        "each (posture-id body --height-m H --mass-kg M makes one); a subject "
                        "without one gets --body")
    p.add_argument("--plot", type=Path,
                   help="recorded versus re-simulated sway (PNG), and each parameter's "
                        "interval beside it (NAME.intervals.png)")
    p.add_argument("--level", type=interval_level, default=0.9,
                   help="the intervals' nominal coverage (default %(default)g)")
    p.add_argument("--band-preset", choices=("peterka11",),
                   help="cohort: also write each recording's FRF at these points, the labs' "
                        "way (<recording>.frf.json: a normative set in one more command, "
                        "posture-id norm build)")
    p.add_argument("--norm", type=Path,
                   help="cohort: test each recording against this norm (its points): "
                        "summary.csv gains human_likeness, inside_prediction_band and "
                        "distance_percentile")
    add_recording_arguments(p, "tilt CSV (time_s,tilt_deg) the recordings were made with")
    add_search_arguments(p)
    p.set_defaults(func=run)


def _no_search_for_the_network_alone(args: argparse.Namespace) -> None:
    """Refuse least-squares flags with ``--method cnn``, which runs no least squares."""
    given = search_flags_given(args) if args.method == "cnn" else []
    if given:
        raise PostureIdError(f"{', '.join(given)} set the least-squares search, and --method "
                             "cnn runs none: use --method hybrid, fit or auto (the default)")


def run(args: argparse.Namespace) -> int:
    _no_search_for_the_network_alone(args)
    if args.network is not None and args.method == "fit":
        raise PostureIdError("--network names the network, and --method fit runs none (least "
                             "squares from the defaults): use --method cnn, hybrid or auto, "
                             "or leave out --network")
    if is_cohort(args.recording):
        return run_cohort(args)
    args.recording = Path(args.recording)
    if args.scheduler or args.bodies or args.band_preset or args.norm:
        raise PostureIdError("--scheduler, --bodies, --band-preset and --norm go with a folder "
                             "or pattern of recordings (one recording: posture-id frf, "
                             "posture-id norm test)")
    if args.model == "ic":
        return _identify_ic(args)
    fit_options = FitOptions(**search_keywords(args))
    check_out_and_plot(args, (args.recording, args.body, args.network, args.tilt))
    # torch and CasADi load here, not when the parser is built: other commands start fast
    from posture_id.identify import Identifier, Method
    body = recording_body(args, DEFAULT_URDF)
    identifier = Identifier(body, Method(args.method), args.network, fit_options, args.level)
    recording, stimulus = recording_and_stimulus(args, body)
    with TerminalProgress(prefix="posture-id identify", quiet=True) as progress:
        result = identifier.identify(recording, stimulus, progress)
    if args.out is None:
        say("no --out: the result is printed, not written (--out FILE.json keeps it)")
    write_result(result, args.out, args.plot)
    if result.fell:  # an answer, written, but it does not balance the body
        say(result.fell_line())
    return answered(result.fell or (result.verdict is not None and result.verdict.doubtful))


def _identify_ic(args: argparse.Namespace) -> int:
    """``--model ic``: the IC fit of one recording (fit --model ic's)."""
    from posture_id.cli.fit import ic_answer
    from posture_id.fitting.frequency import IcFitOptions
    from posture_id.frf.locked import LockedOptions

    given = [flag for flag, on in (("--method", args.method != DEFAULT_METHOD_NAME),
                                   ("--network", args.network is not None),
                                   ("--level", args.level != 0.9)) if on]
    given += [f for f in search_flags_given(args) if f not in ("--fit-passive",
                                                               "--max-frequency-hz")]
    if given:
        raise PostureIdError(f"{', '.join(given)}: DEC's identification only; --model ic fits "
                             "the stimulus-locked body COM sway (docs/ic.md)")
    check_out_and_plot(args, (args.recording, args.body, args.tilt))
    options = IcFitOptions(fit_passive=args.fit_passive,
                           locked=LockedOptions(max_frequency_hz=args.max_frequency_hz))
    return ic_answer(args, options)


def run_cohort(args: argparse.Namespace) -> int:
    from posture_id.identify import Identifier, Method
    from posture_id.identify.cohort import (
        find_recordings,
        identify_cohort,
        subjects_without_a_body,
    )

    if args.plot:
        raise PostureIdError("--plot is for one recording; a cohort writes JSON per recording")
    if args.out is None:
        raise PostureIdError(f"{args.recording}: a cohort's results need a folder: --out "
                             "FOLDER (one JSON per recording and summary.csv)")
    if args.model == "ic":
        raise PostureIdError(f"{args.recording}: a cohort's IC fits come with DEC's beside "
                             "them: posture-id compare DIR --out FOLDER")
    fit_options = FitOptions(**search_keywords(args))
    recordings = find_recordings(args.recording)
    norm = _cohort_norm(args)
    if args.scheduler:
        from posture_id.executors import check_scheduler_address

        check_scheduler_address(args.scheduler)
    if args.bodies is not None:
        without = subjects_without_a_body(recordings, args.bodies)
        if without:
            names = ", ".join(p.name for p in without[:3]) + (" …" if len(without) > 3 else "")
            say(f"{len(without)} of {len(recordings)} recordings have no body in "
                f"{args.bodies} ({names}): they get {args.body or 'the default TIP'}")
    suffixes = (".json", ".frf.json") if args.band_preset or args.norm else (".json",)
    with cohort_folder(args, recordings, suffixes):
        body = load_body(args.body or DEFAULT_URDF)
        stimulus = stimulus_from_args(args, default=None)
        identifier = Identifier(body, Method(args.method), args.network, fit_options,
                                args.level)
        with TerminalProgress("recordings", prefix="posture-id identify") as progress:
            result = identify_cohort(recordings, args.out, identifier, args.scheduler,
                                     progress, stimulus, args.network, columns_from_args(args),
                                     args.bodies, trial_bodies=args.body is None)
        no_frf = (_cohort_frfs(args, recordings, body, norm)
                  if args.band_preset or norm is not None else {})
    say(result.summary())
    return answered(bool(result.failed or result.doubtful or no_frf))


def _cohort_norm(args: argparse.Namespace):
    """The --norm, read before any work (its points must be a lab's)."""
    if args.norm is None:
        return None
    from posture_id.norms.norm import Norm

    norm = Norm.from_json(args.norm)
    norm_bands(args, norm)  # its points: its own, a preset's, or --band-preset's; else refused
    per_trial = args.bodies is not None or (
        args.body is None and isinstance(columns_from_args(args), MarkerMapping))
    if not per_trial:  # every recording is read for one body: its channels are known
        from posture_id.norms.norm import tested_channels

        body = load_body(args.body or DEFAULT_URDF)
        given = (*body.segment_names, "body COM")
        try:
            tested_channels(norm, given, where=str(args.norm))
        except PostureIdError:
            raise PostureIdError(
                f"{args.norm}: the norm's channels {', '.join(norm.channels)} are not all "
                f"the recordings' ({', '.join(given)} for {Path(body.urdf_path).name}): "
                "test against a norm of the same segments, or of the body COM alone "
                "(norm build --channel 'body COM')") from None
    return norm


def _cohort_frfs(args: argparse.Namespace, recordings: list[Path], body, norm
                 ) -> dict[str, str]:
    """Each recording's FRF at the lab's points, and the norm's columns in summary.csv;
    returns the recordings that got none, with why (each said)."""
    from posture_id.frf.bands import BAND_PRESETS
    from posture_id.norms.cohort import cohort_frfs
    from posture_id.trials.subjects import subject_urdf

    bands = norm_bands(args, norm) if norm is not None else BAND_PRESETS[args.band_preset]

    load = cache(load_body)  # one load per URDF, however many recordings share it

    layout = columns_from_args(args)
    trial_bodies = layout if args.body is None and isinstance(layout, MarkerMapping) else None

    def body_of(path: Path):
        return load(subject_urdf(path, args.bodies, Path(body.urdf_path), trial_bodies))

    def read(path: Path):
        args.recording = path
        return prepared_trial(args, body_of(path), rate_hz=None, checked=False)

    failed = cohort_frfs(recordings, args.out, read, body_of, bands, norm)
    for name, why in failed.items():
        say(f"{name}: no FRF ({why})")
    return failed
