"""The public API: every exported name resolves and is documented, argument by argument;
the layers stay one-way on import."""

from __future__ import annotations

import inspect
import re
import subprocess
import sys
from pathlib import Path

import posture_id


def test_every_exported_name_is_the_object_it_names():
    """Each name resolves (lazily or not) to the class or function of that name in its
    stage's package; the two constants are what they say."""
    for name in posture_id.__all__:
        obj = getattr(posture_id, name)
        if name == "__version__":
            assert re.fullmatch(r"\d+\.\d+\.\d+\S*", obj), obj
        elif name == "DEFAULT_URDF":
            assert Path(obj).is_file() and Path(obj).suffix == ".urdf"
        elif name == "BAND_PRESETS":
            assert "peterka11" in obj and len(obj["peterka11"].centres_hz) == 11
        elif name == "identify" and obj is sys.modules["posture_id.identify"]:
            assert obj.identify.__name__ == "identify" and callable(obj)  # the package
        else:
            assert obj.__name__ == name, (name, obj)
            assert obj.__module__.startswith("posture_id."), (name, obj.__module__)


def test_the_command_line_imports_nothing_heavy():
    """Importing the command line (every command's parser) leaves scipy.signal, .stats and
    .fft, torch and CasADi to the commands that need them: `posture-id simulate` starts
    fast."""
    heavy = ("scipy.signal", "scipy.stats", "scipy.fft", "torch", "casadi", "matplotlib",
             "distributed")
    code = f"import sys, posture_id.cli; print(sorted(m for m in {heavy} if m in sys.modules))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.strip()
    assert out == "[]"


def test_import_does_not_load_casadi_torch_or_matplotlib():
    code = ("import sys, posture_id; "
            "print(sorted(m for m in ('casadi', 'torch', 'matplotlib', 'distributed') "
            "if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.strip()
    assert out == "[]"


def _public_callables():
    """(label, function) of every exported function and of every public method, class
    method and property of every exported class."""
    for name in posture_id.__all__:
        obj = getattr(posture_id, name)
        if name == "identify":  # the package's name too, and it calls the function
            obj = sys.modules["posture_id.identify"].identify
        if inspect.isfunction(obj):
            yield name, obj
        elif inspect.isclass(obj):
            yield name, obj
            for member, value in vars(obj).items():
                if member.startswith("_"):
                    continue
                if isinstance(value, classmethod | staticmethod):
                    value = value.__func__
                elif isinstance(value, property):
                    value = value.fget
                if inspect.isfunction(value):
                    yield f"{name}.{member}", value


def test_every_public_function_and_argument_is_documented():
    """Every exported function, class and public method has a docstring, and a function's
    docstring names each of its arguments (the API reference is made from them)."""
    undocumented, unnamed = [], []
    for label, obj in _public_callables():
        doc = inspect.getdoc(obj) or ""
        if not doc.strip():
            undocumented.append(label)
        elif inspect.isfunction(obj) and "." not in label:
            for argument in inspect.signature(obj).parameters:
                if argument not in ("self", "cls") and not re.search(
                        rf"\b{re.escape(argument)}\b", doc):
                    unnamed.append(f"{label}({argument})")
    assert not undocumented, f"no docstring: {undocumented}"
    assert not unnamed, f"arguments the docstring does not name: {unnamed}"


def _references():
    """The docs site's hook (docs/config/references.py) as a module."""
    import importlib.util

    spec = importlib.util.spec_from_file_location(
        "references", Path(__file__).resolve().parents[1] / "docs" / "config" / "references.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_reference_shows_a_table_of_the_arguments_written_one_entry_each():
    """A docstring whose ``Args:`` give each argument an entry of its own is rendered as a
    table of the arguments (Google style); identify's and Identifier's are; one that packs
    two arguments on a line is shown as written."""
    from posture_id.identify.core import Identifier
    from posture_id.identify.core import identify as identify_function

    references = _references()
    assert references.one_entry_per_argument(identify_function)
    assert references.one_entry_per_argument(Identifier)

    def packed(a: int, b: int, c: int = 0) -> int:
        """Sum.

        Args:
            a, b: the terms. c: another.
        """
        return a + b + c

    def one_each(a: int, *rest: int, **named: int) -> int:
        """Sum.

        Args:
            a: the first term.
            *rest: the others.
            **named: more, by name.

        Returns:
            the sum.
        """
        return a + sum(rest) + sum(named.values())

    assert references.argument_entries(packed) == ["a, b: the terms. c: another."]
    assert not references.one_entry_per_argument(packed)
    assert references.one_entry_per_argument(one_each)
    entry = "::: posture_id.identify.core.identify\n    options:\n      docstring_style: google"
    assert entry in references.api_reference()
