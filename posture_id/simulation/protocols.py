"""Stimulus protocols: what a lab plays on its platform, as typed, JSON-round-trippable
objects that the simulator, the fit and ``identify`` accept (``--protocol FILE``).

A protocol is one or more recordings of a periodic tilt:

- :class:`PrtsProtocol`: a PRTS of any length (242 or 80 states), state duration,
  peak-to-peak amplitude and cycles, recorded ``repetitions`` times;
- :class:`MultisineProtocol`: sines at chosen harmonics of a period, equal amplitudes
  unless given, Schroeder phases (a low crest factor) unless given, scaled to a
  peak-to-peak tilt;
- :class:`SumOfSinesProtocol`: sines with chosen frequencies, amplitudes and phases, as
  they are (their period is the least common one);
- :class:`TwoAmplitudeProtocol`: one of the above recorded at two peak-to-peak
  amplitudes (the DEC's dead-band makes the response depend on the amplitude).

Each single protocol gives its tilt as a :class:`~.stimulus.TiltProfile`
(:meth:`profile`); sines are sampled at :data:`KNOT_RATE_HZ` and start level (their
value at t = 0 is subtracted, a constant tilt the locked analysis removes).
:func:`protocol_from_dict` reads any of them back from ``to_dict()``; a bad field is
named.
"""

from __future__ import annotations

import json
import math
from dataclasses import MISSING, asdict, dataclass, field, replace
from fractions import Fraction
from pathlib import Path

import numpy as np

from posture_id.errors import StimulusError
from posture_id.simulation.stimulus import PRTS_REGISTERS, TiltProfile, prts

__all__ = ["PrtsProtocol", "MultisineProtocol", "SumOfSinesProtocol", "TwoAmplitudeProtocol",
           "Protocol", "SingleProtocol", "protocol_from_dict", "protocol_to_dict", "read_protocol",
           "write_protocol", "KNOT_RATE_HZ", "schroeder_phases"]

#: Knots per second of a sampled sine tilt (piecewise linear between them).
KNOT_RATE_HZ = 200.0
#: Period grid: a period must be a whole number of these (whole samples at 50 and 100 Hz).
_PERIOD_GRID_S = 0.02


def _positive(name: str, value: float) -> float:
    if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
        raise StimulusError(f"protocol {name} must be a finite number > 0, got {value!r}")
    return float(value)


def _count(name: str, value) -> int:
    if (isinstance(value, bool) or not isinstance(value, int | float)
            or not math.isfinite(value) or int(value) != value or value < 1):
        raise StimulusError(f"protocol {name} must be a whole number ≥ 1, got {value!r}")
    return int(value)


def _numbers(values, count: int, refusal: str) -> tuple[float, ...]:
    """``values`` as ``count`` finite floats (one per sine); ``refusal`` where they are not."""
    if not all(isinstance(v, int | float) and not isinstance(v, bool) for v in values):
        raise StimulusError(refusal)
    numbers = tuple(float(v) for v in values)
    if len(numbers) != count or not all(math.isfinite(v) for v in numbers):
        raise StimulusError(refusal)
    return numbers


#: The largest peak-to-peak tilt a protocol may ask of a posture platform, degrees.
MAX_PLATFORM_DEG = 20.0
#: A protocol's frequencies lie below this, Hz: the Nyquist frequency of the 50 Hz
#: recordings (and far above what a posture platform follows).
MAX_FREQUENCY_HZ = KNOT_RATE_HZ / 8
#: The longest protocol, every recording and repetition, s: a subject's session.
MAX_SESSION_S = 2 * 3600.0


def _below_nyquist(name: str, highest_hz: float) -> None:
    """Refuse a protocol frequency at or above :data:`MAX_FREQUENCY_HZ` (a sine at the
    Nyquist frequency of the 50 Hz recordings is sampled at its zeros: it vanishes)."""
    if highest_hz >= MAX_FREQUENCY_HZ - 1e-9:
        raise StimulusError(f"protocol {name} reach {highest_hz:g} Hz: at or above "
                            f"{MAX_FREQUENCY_HZ:g} Hz, the 50 Hz recordings' Nyquist "
                            "frequency (a sine there is sampled at its zeros); keep every "
                            "frequency below it")


def _amplitude(name: str, value: float, limit: float = MAX_PLATFORM_DEG) -> float:
    value = _positive(name, value)
    if value > limit:
        raise StimulusError(f"protocol {name} is {value:g}°: more than the {limit:g}° a "
                            "posture platform tilts (and far beyond upright stance)")
    return value


def _period(name: str, value: float) -> float:
    value = _positive(name, value)
    steps = value / _PERIOD_GRID_S
    if abs(steps - round(steps)) > 1e-6:
        raise StimulusError(f"protocol {name} must be a whole number of {_PERIOD_GRID_S:g} s "
                            f"(whole samples at 50 Hz), got {value:g} s")
    return round(steps) * _PERIOD_GRID_S


class _Recorded:
    """What every protocol has: its recordings, their minutes, peak tilt and peak rate."""

    @property
    def recordings(self) -> tuple[SingleProtocol, ...]:
        """The distinct recordings (each made ``repetitions`` times)."""
        raise NotImplementedError

    @property
    def recording_minutes(self) -> float:
        """Minutes of recording in all (every repetition)."""
        return sum(r.repetitions * r.duration_s / 60 for r in self.recordings)

    @property
    def peak_to_peak_deg(self) -> float:
        """The largest peak-to-peak tilt of the recordings, degrees."""
        return max(float(np.ptp(np.degrees(r.profile().angles))) for r in self.recordings)

    @property
    def peak_velocity_deg_s(self) -> float:
        """The fastest tilt of the recordings, degrees/s."""
        return max(float(np.degrees(np.max(np.abs(np.diff(p.angles) / np.diff(p.times)))))
                   for p in (r.profile() for r in self.recordings))

    def to_dict(self) -> dict:
        return protocol_to_dict(self)  # type: ignore[arg-type]


class _Single(_Recorded):
    """What every single-recording protocol has: a tilt, its cycles and repetitions."""

    cycles: int
    repetitions: int

    @property
    def period_s(self) -> float:
        raise NotImplementedError

    def profile(self) -> TiltProfile:
        raise NotImplementedError

    @property
    def recordings(self) -> tuple[SingleProtocol, ...]:
        """The distinct recordings (each made ``repetitions`` times)."""
        return (self,)  # type: ignore[return-value]

    @property
    def duration_s(self) -> float:
        """s, one recording."""
        return self.cycles * self.period_s

    def _check_session(self) -> None:
        """Refuse a protocol longer than a session (:data:`MAX_SESSION_S`)."""
        total = self.repetitions * self.duration_s
        if total > MAX_SESSION_S:
            raise StimulusError(
                f"protocol of {self.repetitions} × {self.cycles} cycles of {self.period_s:g} s"
                f" = {total / 3600:.3g} h: longer than the {MAX_SESSION_S / 3600:g} h of a "
                "session on a platform (fewer cycles or repetitions)")

    def with_cycles(self, cycles: int) -> SingleProtocol:
        return replace(self, cycles=cycles)  # type: ignore[type-var]

    def with_amplitude(self, peak_to_peak_deg: float) -> SingleProtocol:
        raise NotImplementedError


@dataclass(frozen=True)
class PrtsProtocol(_Single):
    """A PRTS (docs/model.md §4) of ``states`` states of ``state_s`` s, ``amplitude_deg``
    peak to peak, ``cycles`` cycles per recording, ``repetitions`` recordings."""

    states: int = 242
    state_s: float = 0.25
    amplitude_deg: float = 1.0
    cycles: int = 2
    repetitions: int = 1
    kind: str = field(default="prts", init=False)

    def __post_init__(self) -> None:
        if self.states not in PRTS_REGISTERS:
            raise StimulusError(f"protocol states must be one of {sorted(PRTS_REGISTERS)}, "
                                f"got {self.states!r}")
        _amplitude("amplitude_deg", self.amplitude_deg)
        _count("cycles", self.cycles)
        _count("repetitions", self.repetitions)
        _period("state_s × states", self.state_s * self.states)
        self._check_session()

    @property
    def period_s(self) -> float:
        return self.states * self.state_s

    def profile(self) -> TiltProfile:
        return prts(self.amplitude_deg, self.cycles, self.states, self.state_s)

    def with_amplitude(self, peak_to_peak_deg: float) -> PrtsProtocol:
        return replace(self, amplitude_deg=peak_to_peak_deg)

    def label(self) -> str:
        rep = f" ×{self.repetitions} rec" if self.repetitions > 1 else ""
        return (f"PRTS {self.states}×{self.state_s:g} s, {self.amplitude_deg:g}° p-p, "
                f"{self.cycles} cyc{rep}")


def schroeder_phases(count: int) -> np.ndarray:
    """(count,) rad, Schroeder's phases −πk(k−1)/count for equal amplitudes: a low crest
    factor."""
    k = np.arange(1, count + 1)
    return -np.pi * k * (k - 1) / count


def _sines(frequencies: np.ndarray, amplitudes: np.ndarray, phases: np.ndarray,
           duration: float, period: float, description: str) -> TiltProfile:
    n = int(round(duration * KNOT_RATE_HZ))
    t = np.arange(n + 1) / KNOT_RATE_HZ
    x = (amplitudes[None] * np.sin(2 * np.pi * np.outer(t, frequencies) + phases[None])).sum(1)
    x -= float((amplitudes * np.sin(phases)).sum())
    return TiltProfile(t, np.radians(x), description, period_s=period, periodic_from_s=0.0,
                       cycles=int(round(duration / period)))


@dataclass(frozen=True)
class MultisineProtocol(_Single):
    """Sines at ``harmonics`` of 1/``period_s`` (frequency k/period), relative
    ``weights`` (default equal), ``phases_rad`` (default Schroeder's), scaled to
    ``amplitude_deg`` peak to peak."""

    period_s: float = 60.0
    harmonics: tuple[int, ...] = (1, 2, 3, 5, 8, 12, 18, 27, 40, 60, 90)
    amplitude_deg: float = 1.0
    weights: tuple[float, ...] | None = None
    phases_rad: tuple[float, ...] | None = None
    cycles: int = 2
    repetitions: int = 1
    kind: str = field(default="multisine", init=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "period_s", _period("period_s", self.period_s))
        _amplitude("amplitude_deg", self.amplitude_deg)
        _count("cycles", self.cycles)
        _count("repetitions", self.repetitions)
        h = tuple(_count("harmonics", k) for k in self.harmonics)
        if not h or len(set(h)) != len(h):
            raise StimulusError(f"protocol harmonics must be distinct whole numbers ≥ 1, "
                                f"got {self.harmonics!r}")
        object.__setattr__(self, "harmonics", h)
        for name in ("weights", "phases_rad"):
            value = getattr(self, name)
            if value is None:
                continue
            value = _numbers(value, len(h), f"protocol {name} must be {len(h)} finite numbers "
                             f"(one per harmonic), got {value!r}")
            if name == "weights" and (min(value) < 0 or max(value) <= 0):
                raise StimulusError("protocol weights must be ≥ 0, not all 0")
            object.__setattr__(self, name, value)
        _below_nyquist("harmonics", max(h) / self.period_s)
        self._check_session()

    @property
    def frequencies_hz(self) -> np.ndarray:
        return np.array(self.harmonics) / self.period_s

    def profile(self) -> TiltProfile:
        f = self.frequencies_hz
        w = np.ones(len(f)) if self.weights is None else np.array(self.weights)
        phases = (schroeder_phases(len(f)) if self.phases_rad is None
                  else np.array(self.phases_rad))
        one = _sines(f, w, phases, self.period_s, self.period_s, "")
        scale = self.amplitude_deg / float(np.ptp(np.degrees(one.angles)))
        return _sines(f, w * scale, phases, self.cycles * self.period_s, self.period_s,
                      self.label())

    def with_amplitude(self, peak_to_peak_deg: float) -> MultisineProtocol:
        return replace(self, amplitude_deg=peak_to_peak_deg)

    def label(self) -> str:
        rep = f" ×{self.repetitions} rec" if self.repetitions > 1 else ""
        f = self.frequencies_hz
        return (f"multisine {len(f)} sines {f.min():.3g}–{f.max():.3g} Hz, "
                f"{self.amplitude_deg:g}° p-p, {self.period_s:g} s ×{self.cycles}{rep}")


@dataclass(frozen=True)
class SumOfSinesProtocol(_Single):
    """Sines of ``frequencies_hz`` with ``amplitudes_deg`` (each sine's amplitude, half
    its peak to peak) and ``phases_rad`` (default 0), as given; the period is the least
    common one of the frequencies (at most 300 s)."""

    frequencies_hz: tuple[float, ...] = (0.1, 0.3, 0.7)
    amplitudes_deg: tuple[float, ...] = (0.5, 0.3, 0.2)
    phases_rad: tuple[float, ...] | None = None
    cycles: int = 2
    repetitions: int = 1
    kind: str = field(default="sum_of_sines", init=False)

    def __post_init__(self) -> None:
        f = tuple(_positive("frequencies_hz", v) for v in self.frequencies_hz)
        a = tuple(_amplitude("amplitudes_deg", v, MAX_PLATFORM_DEG / 2)
                  for v in self.amplitudes_deg)
        if not f or len(a) != len(f) or len(set(f)) != len(f):
            raise StimulusError("protocol frequencies_hz must be distinct, one amplitude each")
        object.__setattr__(self, "frequencies_hz", f)
        object.__setattr__(self, "amplitudes_deg", a)
        if self.phases_rad is not None:
            object.__setattr__(self, "phases_rad", _numbers(
                self.phases_rad, len(f), f"protocol phases_rad must be {len(f)} finite numbers"))
        _count("cycles", self.cycles)
        _count("repetitions", self.repetitions)
        _below_nyquist("frequencies_hz", max(f))
        self.period_s  # noqa: B018 (checks the frequencies are commensurate)
        self._check_session()

    @property
    def period_s(self) -> float:
        periods = [Fraction(1 / f).limit_denominator(1000) for f in self.frequencies_hz]
        for f, p in zip(self.frequencies_hz, periods, strict=True):
            if abs(float(p) - 1 / f) > 1e-9 * (1 / f):
                raise StimulusError(f"protocol frequency {f:g} Hz has no period on a 1 ms "
                                    "grid")
        period = _lcm(periods)
        if period > 300:
            raise StimulusError(f"protocol frequencies_hz have a common period of "
                                f"{float(period):g} s: over 300 s")
        return _period("period (least common period of frequencies_hz)", float(period))

    def profile(self) -> TiltProfile:
        f = np.array(self.frequencies_hz)
        phases = np.zeros(len(f)) if self.phases_rad is None else np.array(self.phases_rad)
        return _sines(f, np.array(self.amplitudes_deg), phases, self.cycles * self.period_s,
                      self.period_s, self.label())

    def with_amplitude(self, peak_to_peak_deg: float) -> SumOfSinesProtocol:
        scale = peak_to_peak_deg / self.peak_to_peak_deg
        return replace(self, amplitudes_deg=tuple(a * scale for a in self.amplitudes_deg))

    def label(self) -> str:
        rep = f" ×{self.repetitions} rec" if self.repetitions > 1 else ""
        return (f"{len(self.frequencies_hz)} sines "
                + ", ".join(f"{f:g}" for f in self.frequencies_hz)
                + f" Hz, {self.period_s:g} s ×{self.cycles}{rep}")


def _lcm(periods: list[Fraction]) -> Fraction:
    """The least common multiple of positive fractions."""
    out = periods[0]
    for p in periods[1:]:
        num = math.lcm(out.numerator * p.denominator, p.numerator * out.denominator)
        out = Fraction(num, out.denominator * p.denominator)
    return out


SingleProtocol = PrtsProtocol | MultisineProtocol | SumOfSinesProtocol


@dataclass(frozen=True)
class TwoAmplitudeProtocol(_Recorded):
    """``base`` recorded at two peak-to-peak amplitudes (each ``base.repetitions``
    times): two recordings to be identified together."""

    base: SingleProtocol
    amplitudes_deg: tuple[float, float] = (1.0, 3.0)
    kind: str = field(default="two_amplitudes", init=False)

    def __post_init__(self) -> None:
        if not isinstance(self.base, (PrtsProtocol, MultisineProtocol, SumOfSinesProtocol)):
            raise StimulusError("protocol base of two amplitudes must be a single protocol")
        a = tuple(_amplitude("amplitudes_deg", v, MAX_PLATFORM_DEG / 2)
                  for v in self.amplitudes_deg)
        if len(a) != 2 or a[0] == a[1]:
            raise StimulusError(f"protocol amplitudes_deg must be two different amplitudes, "
                                f"got {self.amplitudes_deg!r}")
        object.__setattr__(self, "amplitudes_deg", a)

    @property
    def recordings(self) -> tuple[SingleProtocol, ...]:
        return tuple(self.base.with_amplitude(a) for a in self.amplitudes_deg)

    def profile(self) -> TiltProfile:
        raise StimulusError(f"{self.label()} is two recordings; take one of its "
                            "recordings (--part 1 or 2 on the command line)")

    def label(self) -> str:
        both = " + ".join(f"{a:g}" for a in self.amplitudes_deg) + "° p-p"
        base = self.base.label()
        if isinstance(self.base, SumOfSinesProtocol):
            return f"{base} at {both}, two recordings"
        return base.replace(f"{self.base.amplitude_deg:g}° p-p", both, 1) + ", two recordings"


Protocol = SingleProtocol | TwoAmplitudeProtocol

_KINDS = {"prts": PrtsProtocol, "multisine": MultisineProtocol,
          "sum_of_sines": SumOfSinesProtocol, "two_amplitudes": TwoAmplitudeProtocol}


def protocol_to_dict(protocol: Protocol) -> dict:
    """JSON-ready fields, ``kind`` first (read back by :func:`protocol_from_dict`)."""
    data = asdict(protocol)
    if isinstance(protocol, TwoAmplitudeProtocol):
        data["base"] = protocol_to_dict(protocol.base)
    data = {k: list(v) if isinstance(v, tuple) else v for k, v in data.items()}
    return {"kind": data.pop("kind"), **data}


def protocol_from_dict(data: dict, where: str = "protocol") -> Protocol:
    """The protocol ``to_dict()`` wrote; a missing or unknown kind, an unknown field or a
    bad value is refused with its name."""
    if not isinstance(data, dict):
        raise StimulusError(f"{where}: a protocol is a JSON object, got {type(data).__name__}")
    kind = data.get("kind")
    if kind not in _KINDS:
        raise StimulusError(f"{where}: field 'kind' must be one of {sorted(_KINDS)}, "
                            f"got {kind!r}")
    cls = _KINDS[kind]
    fields = {k: v for k, v in data.items() if k != "kind"}
    known = {f for f in cls.__dataclass_fields__ if f != "kind"}
    unknown = sorted(set(fields) - known)
    missing = sorted(name for name, f in cls.__dataclass_fields__.items()
                     if f.init and name not in fields and f.default is MISSING
                     and f.default_factory is MISSING)
    if missing:
        raise StimulusError(f"{where}: a {kind} protocol needs the field(s) {missing}")
    if unknown:
        raise StimulusError(f"{where}: unknown field(s) {unknown} for a {kind} protocol "
                            f"(fields: {sorted(known)})")
    if cls is TwoAmplitudeProtocol and "base" in fields:
        fields["base"] = protocol_from_dict(fields["base"], f"{where} base")
    fields = {k: tuple(v) if isinstance(v, list) else v for k, v in fields.items()}
    try:
        return cls(**fields)
    except StimulusError as exc:
        raise StimulusError(f"{where}: {exc}") from None
    except TypeError as exc:
        raise StimulusError(f"{where}: {exc}") from None


def read_protocol(path: str | Path) -> Protocol:
    """A protocol from a JSON file (``write_protocol``)."""
    path = Path(path)
    if path.is_dir():
        raise StimulusError(f"{path}: is a folder, not a protocol file (JSON, from "
                            "posture-id design)")
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise StimulusError(f"{path}: no such protocol file") from None
    except PermissionError:
        raise StimulusError(f"{path}: the protocol file is not readable") from None
    except UnicodeDecodeError as exc:
        raise StimulusError(f"{path}: not UTF-8 text (byte {exc.object[exc.start]:#04x} at "
                            f"{exc.start}); save the protocol as UTF-8 JSON") from None
    except json.JSONDecodeError as exc:
        raise StimulusError(f"{path}: not valid JSON ({exc})") from None
    return protocol_from_dict(data, str(path))


def write_protocol(protocol: Protocol, path: str | Path) -> Path:
    """Write a protocol as JSON, atomically."""
    from posture_id.fileio import atomic_write_text, json_text

    return atomic_write_text(Path(path), json_text(protocol_to_dict(protocol)))
