"""Command line: ``posture-id body ...`` and ``posture-id simulate ...``.

Every user error is printed as one line ``posture-id: error: ...`` (exit status 2).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from posture_id.errors import PostureIdError

__all__ = ["main"]


def _body_table(body) -> str:
    """Human-readable summary of a body and its default parameters."""
    params = body.default_parameters()
    lines = [
        f"body '{body.name}' from {body.urdf_path}: {body.n_segments} segments, "
        f"{body.total_mass:.3f} kg, g = {body.gravity:g} m/s²",
        "",
        f"{'segment':<10}{'joint':<10}{'mass kg':>9}{'length m':>10}{'COM m':>8}"
        f"{'I kg·m²':>10}",
    ]
    for s in body.segments:
        lines.append(
            f"{s.name:<10}{s.joint:<10}{s.mass:>9.3f}{s.length:>10.4f}"
            f"{(s.com[0] ** 2 + s.com[1] ** 2) ** 0.5:>8.4f}{s.inertia:>10.4f}"
        )
    lines += [
        "",
        f"{'module':<10}{'m·g·h':>10}{'Kp':>10}{'Ki':>9}{'Kd':>9}{'Δ s':>7}"
        f"{'Kpas':>9}{'Bpas':>9}  controls",
    ]
    for joint, mgh in zip(body.joint_names, body.mgh, strict=True):
        m = params[joint]
        lines.append(
            f"{joint:<10}{mgh:>10.3f}{m.kp:>10.3f}{m.ki:>9.4f}{m.kd:>9.3f}{m.delay_s:>7.3f}"
            f"{m.kpas:>9.3f}{m.bpas:>9.3f}  {m.controls}"
        )
    return "\n".join(lines)


def _cmd_body(args: argparse.Namespace) -> int:
    from posture_id.anthropometry import default_tip_segments, straight_links, winter_segments
    from posture_id.body import DEFAULT_URDF, load_body
    from posture_id.urdf_writer import write_chain_urdf

    writing = [args.height is not None or args.mass is not None, args.default_tip,
               args.from_robot is not None, args.lump is not None]
    if sum(writing) > 1:
        raise PostureIdError(
            "choose one of --height/--mass, --default-tip, --from-robot and --lump"
        )
    if any(writing) and args.out is None:
        raise PostureIdError("--out is required to write a body URDF")
    if args.from_robot is not None or args.lump is not None:
        from posture_id.lumping import lump_robot, preset_body

        if args.from_robot is not None:
            lumped = preset_body(args.from_robot, args.segments)
        else:
            for flag in ("ankle_joints", "hip_joints"):
                if getattr(args, flag) is None:
                    raise PostureIdError(f"--lump needs --{flag.replace('_', '-')} LEFT RIGHT")
            srdf = (args.srdf, args.posture) if args.srdf is not None else None
            if (args.srdf is None) != (args.posture is None):
                raise PostureIdError("--srdf and --posture go together")
            lumped = lump_robot(
                args.lump, ankle=tuple(args.ankle_joints), hip=tuple(args.hip_joints),
                knee=tuple(args.knee_joints) if args.knee_joints else None, srdf=srdf,
                segments=args.segments,
            )
        urdf = lumped.write(args.out)
        print(f"wrote {urdf} ({lumped.source})", file=sys.stderr)
    elif any(writing):
        if args.default_tip:
            segments, name = default_tip_segments(), "tip_default"
        else:
            if args.height is None or args.mass is None:
                raise PostureIdError("--height and --mass go together")
            segments = winter_segments(args.height, args.mass, args.segments)
            name = f"winter_{args.height:g}m_{args.mass:g}kg_{args.segments}seg"
        path = write_chain_urdf(args.out, name, straight_links(segments))
        print(f"wrote {path}", file=sys.stderr)
        urdf = path
    else:
        urdf = args.urdf or DEFAULT_URDF
    body = load_body(urdf)
    if args.json:
        print(json.dumps(body.describe(), indent=2))
    else:
        print(_body_table(body))
    return 0


def _cmd_simulate(args: argparse.Namespace) -> int:
    from posture_id.body import DEFAULT_URDF, load_body
    from posture_id.parameters import DecParameters
    from posture_id.simulation import SimulationOptions, simulate
    from posture_id.stimulus import prts, tilt_from_csv

    body = load_body(args.body or DEFAULT_URDF)
    params = DecParameters.from_json(args.params, body) if args.params else None
    if args.tilt:
        stimulus = tilt_from_csv(args.tilt)
    else:
        stimulus = prts(amplitude_deg=args.amplitude_deg, cycles=args.cycles, states=args.states)
    options = SimulationOptions(
        sway_limit_deg=args.sway_limit_deg, deadband_rad_s=args.deadband_rad_s
    )
    result = simulate(body, params, stimulus, options)
    result.to_csv(args.out)
    print(f"wrote {args.out} ({len(result.time)} samples at {options.sample_rate_hz:g} Hz)",
          file=sys.stderr)
    if args.plot:
        result.plot(args.plot)
        print(f"wrote {args.plot}", file=sys.stderr)
    if not result.stable:
        print(
            f"posture-id: warning: the body left the ±{options.sway_limit_deg:g}° sway limit "
            f"at t = {result.abort_time:.3f} s; the recording stops there",
            file=sys.stderr,
        )
        return 1
    return 0


def _cmd_dataset_generate(args: argparse.Namespace) -> int:
    from tqdm import tqdm

    from posture_id.body import DEFAULT_URDF
    from posture_id.dataset import DatasetConfig, generate_dataset

    config = DatasetConfig(
        trials=args.trials, body=str(args.body or DEFAULT_URDF), seed=args.seed,
        shard_size=args.shard_size, amplitude_deg=args.amplitude_deg, cycles=args.cycles,
        sway_limit_deg=args.sway_limit_deg,
    )
    bar = tqdm(total=config.trials, unit="trial", desc="kept trials", file=sys.stderr,
               disable=args.quiet)

    def progress(done: int, total: int) -> None:
        bar.update(done - bar.n)

    try:
        data = generate_dataset(config, args.out, workers=args.workers,
                                scheduler=args.scheduler, progress=progress)
    finally:
        bar.close()
    print(_dataset_summary(data), file=sys.stderr)
    return 0


def _dataset_summary(data) -> str:
    m = data.manifest
    c = m["counts"]
    s = m["split"]
    return (
        f"{data.path}: {c['used']} trials used ({c['kept']} kept of {c['simulated']} simulated, "
        f"{c['rejection_rate']:.1%} rejected) in {len(m['shards'])} shards; body "
        f"{m['body']['name']} ({m['body']['n_segments']} segments); split by trial: "
        + ", ".join(f"{k} {s[k]['trials']} trials = {s[k]['modular_samples']} modular samples"
                    for k in ("train", "validation", "test"))
    )


def _cmd_dataset_info(args: argparse.Namespace) -> int:
    import numpy as np

    from posture_id.dataset import Dataset
    from posture_id.plotting import plot_dataset_overview, plot_images

    data = Dataset.open(args.dir, verify=not args.no_verify)
    print(_dataset_summary(data))
    kp, sway, kept = [], [], []
    sample = None
    for arrays in data.iter_shards():
        kp.append(arrays["targets"][:, :, 0])
        sway.append(arrays["max_sway_deg"])
        kept.append(arrays["kept"])
        if sample is None and len(arrays["targets"]):
            sample = (arrays["modular"][0], arrays["monolithic"][0])
    joints = data.manifest["body"]["joints"]
    limit = data.manifest["options"]["sway_limit_deg"]
    figures = args.figures or Path(args.dir)
    overview = figures / "dataset_overview.png"
    plot_dataset_overview(np.concatenate(kp), joints, np.concatenate(sway),
                          np.concatenate(kept), limit, path=overview)
    images = figures / "dataset_images.png"
    plot_images(sample[0], sample[1], joints, path=images)
    print(f"wrote {overview} and {images}")
    return 0


def _cmd_fit(args: argparse.Namespace) -> int:
    from posture_id.body import DEFAULT_URDF, load_body
    from posture_id.parameters import DecParameters
    from posture_id.recording import Recording

    body = load_body(args.body or DEFAULT_URDF)
    recording = Recording.from_csv(args.recording, body.segment_names)
    init = DecParameters.from_json(args.init, body) if args.init else None
    from posture_id.fit import FitOptions, fit_recording

    options = FitOptions(classes=args.classes, starts=args.starts,
                         compile="never" if args.no_compile else "auto")

    def progress(message: str) -> None:
        print(f"posture-id fit: {message}", file=sys.stderr, flush=True)

    result = fit_recording(recording, body, init, options, progress=progress,
                           source=str(args.recording))
    result.to_json(args.out)
    print(f"wrote {args.out}", file=sys.stderr)
    if args.plot:
        result.plot(args.plot)
        print(f"wrote {args.plot}", file=sys.stderr)
    print(_fit_table(result))
    return 0 if result.converged else 1


def _fit_table(result) -> str:
    lines = [
        f"{'module':<8}{'Kp':>11}{'Ki':>11}{'Kd':>11}{'Δ s':>11}  controls   (± standard error; "
        "* poorly determined)"
    ]
    for i, joint in enumerate(result.joints):
        m = result.parameters[joint]
        cells = []
        for k, (value, width, digits) in enumerate(
            ((m.kp, 11, 2), (m.ki, 11, 3), (m.kd, 11, 3), (m.delay_s, 11, 4))
        ):
            flag = "*" if result.poorly_determined[i, k] else " "
            cells.append(f"{value:>{width - 1}.{digits}f}{flag}")
        lines.append(f"{joint:<8}{''.join(cells)}  {m.controls}")
        errs = "".join(f"{'±' + format(e, '.' + str(d) + 'g'):>{w}}" for e, w, d in
                       zip(result.standard_errors[i], (11, 11, 11, 11), (3, 3, 3, 3),
                           strict=True))
        lines.append(f"{'':<8}{errs}")
    status = "converged" if result.converged else "NOT converged"
    lines.append(f"{status} in {result.iterations} iterations, {result.wall_time_s:.1f} s, "
                 f"residual RMS {result.rms_deg:.5f}° ({result.backend})")
    lines += [f"note: {n}" for n in result.notices]
    return "\n".join(lines)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="posture-id",
        description="Identify DEC posture-control parameters from body sway.",
    )
    sub = parser.add_subparsers(dest="command", required=True)

    body = sub.add_parser("body", help="describe a body (URDF) or write one")
    body.add_argument("urdf", nargs="?", type=Path, help="URDF file (default: the TIP)")
    body.add_argument("--json", action="store_true", help="print JSON instead of a table")
    body.add_argument("--height", type=float, help="write a Winter body: height, m")
    body.add_argument("--mass", type=float, help="write a Winter body: mass, kg")
    body.add_argument("--segments", type=int, default=3, choices=(1, 2, 3),
                      help="written body: 3 shank+thigh+trunk, 2 leg+trunk, 1 whole body")
    body.add_argument("--default-tip", action="store_true",
                      help="write the default triple inverted pendulum of MODEL §1")
    body.add_argument("--from-robot", choices=("talos", "g1", "human"),
                      help="lump a humanoid shipped by example-robot-data")
    body.add_argument("--lump", type=Path, metavar="URDF",
                      help="lump a whole-body URDF (floating base, two legs) into a chain")
    body.add_argument("--ankle-joints", nargs=2, metavar=("LEFT", "RIGHT"),
                      help="--lump: ankle pitch joints")
    body.add_argument("--knee-joints", nargs=2, metavar=("LEFT", "RIGHT"),
                      help="--lump: knee joints (needed for 3 segments)")
    body.add_argument("--hip-joints", nargs=2, metavar=("LEFT", "RIGHT"),
                      help="--lump: hip pitch joints")
    body.add_argument("--srdf", type=Path, help="--lump: SRDF holding the reference posture")
    body.add_argument("--posture", help="--lump: name of the posture in the SRDF")
    body.add_argument("--out", type=Path, help="where to write the generated URDF")
    body.set_defaults(func=_cmd_body)

    sim = sub.add_parser("simulate", help="simulate a DEC-controlled body on the tilting platform")
    sim.add_argument("--body", type=Path, help="URDF (default: the TIP)")
    sim.add_argument("--params", type=Path, help="parameter JSON (default: the body's defaults)")
    sim.add_argument("--amplitude-deg", type=float, default=1.0,
                     help="PRTS peak-to-peak tilt, degrees (default 1)")
    sim.add_argument("--cycles", type=int, default=2, help="PRTS cycles (default 2)")
    sim.add_argument("--states", type=int, default=242, choices=(242, 80),
                     help="PRTS length (default 242 states, 60.5 s a cycle)")
    sim.add_argument("--tilt", type=Path, help="tilt CSV (time_s,tilt_deg) instead of the PRTS")
    sim.add_argument("--sway-limit-deg", type=float, default=6.0,
                     help="abort when a segment leaves ±this angle (default 6)")
    sim.add_argument("--deadband-rad-s", type=float, default=0.0003,
                     help="tilt-estimator dead-band θ, rad/s (default 0.0003)")
    sim.add_argument("--out", type=Path, required=True, help="recording CSV to write")
    sim.add_argument("--plot", type=Path, help="plot of tilt and sway to write (PNG)")
    sim.set_defaults(func=_cmd_simulate)

    fit = sub.add_parser("fit", help="identify DEC parameters from a recording (least squares)")
    fit.add_argument("recording", type=Path, help="recording CSV (time_s,tilt_deg,<seg>_deg...)")
    fit.add_argument("--body", type=Path, help="URDF (default: the TIP)")
    fit.add_argument("--init", type=Path, help="initial guess, parameter JSON (e.g. the CNN's)")
    fit.add_argument("--out", type=Path, required=True, help="fit result JSON to write")
    fit.add_argument("--plot", type=Path, help="recorded versus fitted sway (PNG)")
    fit.add_argument("--classes", choices=("relaxed", "exhaustive", "fixed"), default="relaxed",
                     help="how to find the classes (default: relaxed, then polished)")
    fit.add_argument("--starts", type=int, default=1,
                     help="relaxed fits from the guess and from STARTS−1 prior draws; "
                          "the best is polished (guards against local minima)")
    fit.add_argument("--no-compile", action="store_true",
                     help="run CasADi in its virtual machine (no C compiler)")
    fit.set_defaults(func=_cmd_fit)

    data = sub.add_parser("dataset", help="training data: generate a data set, describe one")
    dsub = data.add_subparsers(dest="dataset_command", required=True)
    gen = dsub.add_parser("generate", help="simulate random trials into a data-set directory")
    gen.add_argument("--trials", type=int, required=True, help="kept (stable) trials wanted")
    gen.add_argument("--out", type=Path, required=True, help="data-set directory")
    gen.add_argument("--workers", type=int, help="local threads (default: all cores)")
    gen.add_argument("--scheduler", help="Dask distributed scheduler address (tcp://host:port)")
    gen.add_argument("--body", type=Path, help="URDF (default: the TIP)")
    gen.add_argument("--seed", type=int, default=0, help="root seed (default 0)")
    gen.add_argument("--shard-size", type=int, default=256,
                     help="simulated trials per shard (default 256)")
    gen.add_argument("--amplitude-deg", type=float, default=1.0, help="PRTS peak-to-peak, °")
    gen.add_argument("--cycles", type=int, default=2, help="PRTS cycles (default 2)")
    gen.add_argument("--sway-limit-deg", type=float, default=6.0,
                     help="reject trials leaving ±this angle (default 6)")
    gen.add_argument("--quiet", action="store_true", help="no progress bar")
    gen.set_defaults(func=_cmd_dataset_generate)
    info = dsub.add_parser("info", help="counts, rejection rate, splits, Fig. 2 and images")
    info.add_argument("dir", type=Path)
    info.add_argument("--figures", type=Path, help="where to write the PNGs (default: DIR)")
    info.add_argument("--no-verify", action="store_true", help="skip the shard SHA-256 check")
    info.set_defaults(func=_cmd_dataset_info)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return args.func(args)
    except PostureIdError as exc:
        print(f"posture-id: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
