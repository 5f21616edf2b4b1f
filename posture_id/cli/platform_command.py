"""``posture-id stimulus PROTOCOL``: a protocol as the platform's command file (time and
tilt at a chosen rate), to play in the lab; the file reads back with ``--tilt``."""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from posture_id.cli.arguments import check_output_file, command_rate, positive_int, say
from posture_id.cli.stimulus import protocol_profile
from posture_id.errors import PostureIdError

__all__ = ["add_parser"]


def add_parser(sub) -> None:
    p = sub.add_parser("stimulus", help="write a protocol (JSON, from posture-id design) as "
                       "the platform's command file: time_s,tilt_deg at a chosen rate")
    p.add_argument("protocol", type=Path, help="protocol file (JSON)")
    p.add_argument("--out", type=Path, required=True, help="command file (CSV)")
    p.add_argument("--rate-hz", type=command_rate, default=100.0,
                   help="command rate, Hz, up to 10 kHz (default %(default)g)")
    p.add_argument("--part", type=positive_int,
                   help="which recording of a two-amplitude protocol (1 or 2)")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    check_output_file(args.out, "--out", inputs=(args.protocol,))
    from posture_id.fileio import atomic_write_text
    from posture_id.simulation.protocols import read_protocol

    protocol = read_protocol(args.protocol)
    profile = protocol_profile(protocol, args.part, args.protocol)
    frequencies = getattr(protocol.recordings[(args.part or 1) - 1], "frequencies_hz", None)
    if frequencies is not None and max(frequencies) >= args.rate_hz / 2 - 1e-9:
        raise PostureIdError(f"{args.protocol}: --rate-hz {args.rate_hz:g}: the protocol's "
                             f"{max(frequencies):g} Hz is at or above the command file's "
                             f"Nyquist frequency ({args.rate_hz / 2:g} Hz; a sine there is "
                             "sampled at its zeros): give a rate above twice its highest "
                             "frequency")
    steps = int(np.floor(profile.duration * args.rate_hz + 1e-9))
    t = np.arange(steps + 1) / args.rate_hz
    tilt = np.degrees(profile.angle(t))
    lines = ["time_s,tilt_deg"] + [f"{a:.6f},{b:.6f}" for a, b in zip(t, tilt, strict=True)]
    atomic_write_text(args.out, "\n".join(lines) + "\n")
    single = protocol.recordings[(args.part or 1) - 1]
    repeat = (f"; record it {single.repetitions} times" if single.repetitions > 1 else "")
    say(f"wrote {args.out}: {profile.description}, {profile.duration:g} s at "
        f"{args.rate_hz:g} Hz, {np.ptp(tilt):.3g}° peak to peak, peak velocity "
        f"{single.peak_velocity_deg_s:.3g}°/s{repeat}")
    return 0
