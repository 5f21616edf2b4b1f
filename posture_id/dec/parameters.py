"""DEC controller parameters: defaults (docs/model.md §3), normalisation and the JSON format.

JSON format (SI units), one object per module named by its URDF joint::

    {"ankle": {"kp": 465.975, "ki": 11.649, "kd": 116.49, "delay_s": 0.1,
               "controls": "com"}, ...}

``"controls"`` is ``"com"`` for class C = +1 (COM in space) and ``"joint"`` for C = −1
(joint angle). ``"kpas"`` and ``"bpas"`` (passive stiffness and damping) are optional and
default to the body's defaults.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from dataclasses import asdict, dataclass, replace
from pathlib import Path
from types import MappingProxyType

import numpy as np

from posture_id.choices import Choice
from posture_id.errors import ParameterError
from posture_id.fileio import JsonFile

__all__ = [
    "Controls",
    "parameter_block",
    "ModuleParameters",
    "DecParameters",
    "PAPER_TABLE",
    "PAPER_MGH",
    "DEFAULT_CLASSES",
    "default_parameters",
    "normalise",
    "denormalise",
    "ParameterArrays",
    "MAX_DELAY_S",
    "normalise_arrays",
    "denormalise_arrays",
]

#: docs/model.md §3 (paper Table 1), columns ankle, knee, hip. Kp is m·g·h of the default body.
PAPER_MGH = {"ankle": 465.975, "knee": 245.25, "hip": 73.575}
PAPER_TABLE = {
    "ankle": {"kd": 116.49, "ki": 11.649, "kpas": 232.5, "bpas": 145.0, "delay_s": 0.100},
    "knee": {"kd": 18.394, "ki": 6.1312, "kpas": 61.25, "bpas": 11.25, "delay_s": 0.070},
    "hip": {"kd": 18.394, "ki": 1.8394, "kpas": 36.5, "bpas": 11.25, "delay_s": 0.121},
}
class Controls(Choice):
    """A module's class C: the variable it controls. A string enum: it compares equal to,
    prints and writes to JSON as its value ("com", "joint")."""

    COM = "com"  # C = +1: the COM-above angle in space
    JOINT = "joint"  # C = −1: the joint angle


    def __format__(self, spec: str) -> str:
        return format(self.value, spec)

    def __hash__(self) -> int:
        return hash(self.value)

    @property
    def sign(self) -> int:
        """C: +1 for the COM in space, −1 for the joint angle."""
        return 1 if self is Controls.COM else -1

    @classmethod
    def of_sign(cls, c: float) -> Controls:
        """The class of a class value (≥ 0: COM)."""
        return cls.COM if c >= 0 else cls.JOINT


#: Default class per column **[decision]**: lowest +1 (COM), middle −1 (joint), top +1.
DEFAULT_CLASSES = {"ankle": Controls.COM, "knee": Controls.JOINT, "hip": Controls.COM}
_CONTROLS = {c.value: c.sign for c in Controls}
#: Longest lumped delay accepted, s (sizes the simulator's delay buffers).
MAX_DELAY_S = 2.0
_REQUIRED = ("kp", "ki", "kd", "delay_s", "controls")
_OPTIONAL = ("kpas", "bpas")


@dataclass(frozen=True)
class ModuleParameters:
    """Parameters of one DEC module (SI units).

    Attributes:
        kp: N·m/rad, proportional gain. ki: N·m/(rad·s), integral gain.
        kd: N·m·s/rad, derivative gain. delay_s: s, lumped delay Δ of the servo term.
        controls: :class:`Controls` (given as one or as its string, ``"com"``: C = +1,
            COM-above angle in space; ``"joint"``: C = −1).
        kpas: N·m/rad, passive stiffness. bpas: N·m·s/rad, passive damping.
    """

    kp: float
    ki: float
    kd: float
    delay_s: float
    controls: Controls
    kpas: float
    bpas: float

    def __post_init__(self) -> None:
        if isinstance(self.controls, str) and self.controls in _CONTROLS:
            object.__setattr__(self, "controls", Controls(self.controls))

    @property
    def sign(self) -> int:
        """Class C: +1 controls the COM in space, −1 the joint angle."""
        return _CONTROLS[self.controls]


@dataclass(frozen=True)
class DecParameters(JsonFile):
    """Parameters of every module of a body, keyed by URDF joint name, support upward.

    Immutable: ``modules`` is a read-only mapping; :meth:`replace` makes changed copies.
    """

    modules: Mapping[str, ModuleParameters]

    def __post_init__(self) -> None:
        object.__setattr__(self, "modules", MappingProxyType(dict(self.modules)))

    def __hash__(self) -> int:
        return hash(tuple(self.modules.items()))

    @property
    def joints(self) -> tuple[str, ...]:
        """The modules' URDF joint names, support upward."""
        return tuple(self.modules)

    def __getitem__(self, joint: str) -> ModuleParameters:
        return self.modules[joint]

    def array(self, name: str) -> np.ndarray:
        """(N,) values of one field (``"kp"``, ``"delay_s"``, ``"sign"`` ...), support upward."""
        return np.array([getattr(m, name) for m in self.modules.values()], dtype=float)

    def arrays(self):
        """This parameter set as a one-trial :class:`ParameterArrays` (1, N)."""
        return ParameterArrays.from_parameters([self])

    def replace(self, joint: str, **changes) -> DecParameters:
        """A copy with some fields of one module changed (validated)."""
        mods = dict(self.modules)
        mods[joint] = replace(mods[joint], **changes)
        _validate_module(mods[joint], f"module '{joint}'")
        return DecParameters(mods)

    def to_dict(self) -> dict:
        """The parameter-file format: one object per module keyed by joint (SI units)."""
        return {j: {**asdict(m), "controls": m.controls.value} for j, m in self.modules.items()}

    def identified_table(self, class_probability=None) -> list[str]:
        """Lines of a table of the identified values, with P(C = +1) when given."""
        probability = (list(class_probability) if class_probability is not None
                       else [None] * len(self.modules))
        lines = [f"{'module':<10}{'Kp':>10}{'Ki':>9}{'Kd':>9}{'Δ s':>8}  controls  P(com)"]
        for (joint, m), p in zip(self.modules.items(), probability, strict=True):
            shown = "  -" if p is None else f"{p:.3f}"
            lines.append(f"{joint:<10}{m.kp:>10.3f}{m.ki:>9.4f}{m.kd:>9.3f}{m.delay_s:>8.4f}  "
                         f"{m.controls:<8}  {shown}")
        return lines

    def summary(self) -> str:
        """A printable table, one row per module."""
        lines = [f"{'module':<10}{'Kp':>10}{'Ki':>9}{'Kd':>9}{'Δ s':>7}{'Kpas':>9}{'Bpas':>9}"
                 "  controls"]
        for joint, m in self.modules.items():
            lines.append(f"{joint:<10}{m.kp:>10.3f}{m.ki:>9.4f}{m.kd:>9.3f}{m.delay_s:>7.3f}"
                         f"{m.kpas:>9.3f}{m.bpas:>9.3f}  {m.controls}")
        return "\n".join(lines)

    @classmethod
    def from_dict(cls, data: Mapping, body, name: str = "parameters") -> DecParameters:
        """Validate a mapping against a body; missing passive terms take the defaults.

        Raises:
            ParameterError: naming ``name``, the module, the field and the problem.
        """
        if not isinstance(data, Mapping):
            raise ParameterError(f"{name}: expected a JSON object keyed by joint name")
        if data.get("model") == "ic" or (isinstance(data.get("parameters"), Mapping)
                                         and data["parameters"].get("model") == "ic"):
            raise ParameterError(
                f"{name}: the independent-channel model's parameters (\"model\": \"ic\"), "
                "not DEC's modules keyed by joint: give --model ic (simulate, fit), or a DEC "
                "parameter file")
        defaults = default_parameters(body)
        expected = body.joint_names
        for joint in expected:
            if joint not in data:
                raise ParameterError(
                    f"{name}: module '{joint}' is missing (body joints: {', '.join(expected)})"
                )
        for joint in data:
            if joint not in expected:
                raise ParameterError(
                    f"{name}: module '{joint}' is not a joint of body '{body.name}' "
                    f"(body joints: {', '.join(expected)})"
                )
        mods = {}
        for joint in expected:
            entry = data[joint]
            where = f"{name}: module '{joint}'"
            if not isinstance(entry, Mapping):
                raise ParameterError(f"{where}: expected an object with {', '.join(_REQUIRED)}")
            for key in entry:
                if key not in _REQUIRED + _OPTIONAL:
                    raise ParameterError(
                        f"{where}: unknown field '{key}' (allowed: "
                        f"{', '.join(_REQUIRED + _OPTIONAL)})"
                    )
            for key in _REQUIRED:
                if key not in entry:
                    raise ParameterError(f"{where}: field '{key}' is missing")
            values = {}
            for key in ("kp", "ki", "kd", "delay_s", *_OPTIONAL):
                if key not in entry:
                    values[key] = getattr(defaults[joint], key)
                    continue
                value = entry[key]
                if isinstance(value, bool) or not isinstance(value, int | float):
                    raise ParameterError(f"{where}: field '{key}' must be a number, got {value!r}")
                values[key] = float(value)
            module = ModuleParameters(controls=entry["controls"], **values)
            _validate_module(module, where)
            mods[joint] = module
        return cls(mods)

    @classmethod
    def from_json(cls, path: str | Path, body) -> DecParameters:
        """Read and validate a parameter JSON file for ``body``."""
        path = Path(path)
        try:
            data = json.loads(path.read_text(encoding="utf-8-sig"))
        except FileNotFoundError:
            raise ParameterError(f"{path}: no such parameter file") from None
        except IsADirectoryError:
            raise ParameterError(f"{path}: is a folder, expected a parameter file (JSON)") from None
        except UnicodeDecodeError as exc:
            raise ParameterError(f"{path}: not UTF-8 text (byte {exc.start})") from None
        except OSError as exc:
            raise ParameterError(f"{path}: cannot be read ({exc.strerror})") from None
        except json.JSONDecodeError as exc:
            raise ParameterError(f"{path}: not valid JSON ({exc})") from None
        return cls.from_dict(data, body, name=str(path))


def _validate_module(m: ModuleParameters, where: str) -> None:
    if not isinstance(m.controls, str) or m.controls not in _CONTROLS:
        raise ParameterError(
            f"{where}: field 'controls' must be \"com\" or \"joint\", got {m.controls!r}"
        )
    for key in ("kp", "ki", "kd", "delay_s", "kpas", "bpas"):
        value = getattr(m, key)
        if not math.isfinite(value):
            raise ParameterError(f"{where}: field '{key}' is not finite ({value})")
        if value < 0:
            raise ParameterError(f"{where}: field '{key}' is negative ({value})")
    if m.delay_s > MAX_DELAY_S:
        raise ParameterError(f"{where}: field 'delay_s' is {m.delay_s:g} s, longer than the "
                             f"{MAX_DELAY_S:g} s supported (it is in seconds, not ms)")


def _column(index: int, n: int) -> str:
    """docs/model.md §3 column of module ``index`` of ``n``: lowest ankle, top hip, others knee."""
    if index == 0:
        return "ankle"
    if index == n - 1:
        return "hip"
    return "knee"


def default_parameters(body) -> DecParameters:
    """docs/model.md §3 defaults for ``body``: the paper's ratios to m·g·h times this body's m·g·h.

    The ratios are taken from the table (value / default-body m·g·h) so the default body
    gets the table exactly; delays keep the column's seconds; classes per column.
    """
    n = body.n_segments
    mods = {}
    for i, (joint, mgh) in enumerate(zip(body.joint_names, body.mgh, strict=True)):
        col = _column(i, n)
        scale = float(mgh) / PAPER_MGH[col]
        row = PAPER_TABLE[col]
        mods[joint] = ModuleParameters(
            kp=float(mgh),
            ki=row["ki"] * scale,
            kd=row["kd"] * scale,
            delay_s=row["delay_s"],
            controls=DEFAULT_CLASSES[col],
            kpas=row["kpas"] * scale,
            bpas=row["bpas"] * scale,
        )
    return DecParameters(mods)


#: Order of a module's normalised target (docs/model.md §3): [K̃p, K̃i, K̃d, Δ̃, C].
TARGET_FIELDS = ("kp", "ki", "kd", "delay_s")


def parameter_block(parameters: DecParameters, normalised: np.ndarray,
                    class_probability: np.ndarray | None = None) -> dict:
    """The identified parameters as every result writes them to JSON: ``parameters`` (the
    parameter-file format, SI units), ``normalised`` ([K̃p, K̃i, K̃d, Δ̃, C] per module) and
    ``class_probability_com`` (P(C = +1) per module, or None).

    Args:
        normalised: (N, 5), modules in ``parameters``' order. class_probability: (N,).
    """
    joints = parameters.joints
    return {
        "parameters": parameters.to_dict(),
        "normalised": {j: dict(zip((*TARGET_FIELDS, "class"), map(float, row), strict=True))
                       for j, row in zip(joints, np.asarray(normalised), strict=True)},
        "class_probability_com": None if class_probability is None else dict(
            zip(joints, map(float, class_probability), strict=True)),
    }


def normalise(params: DecParameters, defaults: DecParameters) -> np.ndarray:
    """(N, 5) targets [K̃p, K̃i, K̃d, Δ̃, C] with p̃ = (p − p_default)/p_default."""
    return normalise_arrays(params.arrays(), defaults)[0]


def denormalise(targets: np.ndarray, defaults: DecParameters) -> DecParameters:
    """Inverse of :func:`normalise`; the class is read by its sign (≥ 0 → COM)."""
    targets = np.array(targets, dtype=float)
    targets[:, 4] = np.where(targets[:, 4] >= 0, 1.0, -1.0)
    return denormalise_arrays(targets[None], defaults).trial(0, defaults.joints)


def normalise_arrays(params: ParameterArrays, defaults: DecParameters) -> np.ndarray:
    """(B, N, 5) targets [K̃p, K̃i, K̃d, Δ̃, C] of B trials (docs/model.md §3)."""
    columns = []
    for field in TARGET_FIELDS:
        base = defaults.array(field)
        columns.append((getattr(params, field) - base) / base)
    return np.stack([*columns, params.sign], axis=-1)


def denormalise_arrays(targets: np.ndarray, defaults: DecParameters) -> ParameterArrays:
    """(B, N, 5) targets → parameter arrays; passive terms at the defaults, the class
    column kept as it is (±1, or a relaxed value in between)."""
    targets = np.asarray(targets, dtype=float)
    shape = targets.shape[:2]
    values = {f: defaults.array(f) * (1.0 + targets[..., k])
              for k, f in enumerate(TARGET_FIELDS)}
    return ParameterArrays(
        **values, sign=targets[..., 4],
        kpas=np.broadcast_to(defaults.array("kpas"), shape),
        bpas=np.broadcast_to(defaults.array("bpas"), shape),
    )


@dataclass(frozen=True)
class ParameterArrays:
    """Parameters of B trials as arrays, each (B, N), support upward (SI units).

    ``sign`` holds the class C (+1 COM in space, −1 joint angle). A value strictly between
    is the least-squares fit's relaxed class: the controlled variable is then
    (1 + C)/2 · x_COM + (1 − C)/2 · x_joint.
    """

    kp: np.ndarray
    ki: np.ndarray
    kd: np.ndarray
    delay_s: np.ndarray
    sign: np.ndarray
    kpas: np.ndarray
    bpas: np.ndarray

    FIELDS = ("kp", "ki", "kd", "delay_s", "sign", "kpas", "bpas")

    def __post_init__(self) -> None:
        shape = np.shape(self.kp)
        for name in self.FIELDS:
            arr = np.ascontiguousarray(getattr(self, name), dtype=float)
            if arr.ndim != 2 or arr.shape != shape:
                raise ParameterError(
                    f"parameter array '{name}' has shape {arr.shape}, expected {shape} (B, N)"
                )
            if not np.all(np.isfinite(arr)):
                raise ParameterError(f"parameter array '{name}' holds NaN or infinite values")
            if name == "sign":
                if not np.all(np.abs(arr) <= 1.0):
                    raise ParameterError("parameter array 'sign' must lie in [-1, 1]")
            elif np.any(arr < 0):
                b, i = np.argwhere(arr < 0)[0]
                raise ParameterError(
                    f"parameter array '{name}': trial {b}, module {i} is negative ({arr[b, i]})"
                )
            object.__setattr__(self, name, arr)

    @property
    def n_trials(self) -> int:
        """B, the number of trials (rows of each array)."""
        return self.kp.shape[0]

    @classmethod
    def from_parameters(cls, params: list[DecParameters]) -> ParameterArrays:
        """Stack per-trial parameter sets (all for the same body)."""
        if not params:
            raise ParameterError("no parameter sets given")
        return cls(**{f: np.stack([p.array(f) for p in params]) for f in cls.FIELDS})

    def trial(self, b: int, joints: tuple[str, ...]) -> DecParameters:
        """Trial ``b`` as a :class:`DecParameters` keyed by ``joints``."""
        mods = {}
        for i, joint in enumerate(joints):
            mods[joint] = ModuleParameters(
                kp=float(self.kp[b, i]), ki=float(self.ki[b, i]), kd=float(self.kd[b, i]),
                delay_s=float(self.delay_s[b, i]),
                controls=Controls.of_sign(self.sign[b, i]),
                kpas=float(self.kpas[b, i]), bpas=float(self.bpas[b, i]),
            )
        return DecParameters(mods)
