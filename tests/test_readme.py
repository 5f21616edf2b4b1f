"""The README's quickstart runs as written: its command blocks (a subject's CSV, a lab's
CSV, a C3D trial, the comparison with the IC model, a robot lumped, simulated and
identified) and its Python example, on the shipped examples, each in a fresh folder."""

from __future__ import annotations

import json
import re
import shlex
from pathlib import Path

import pytest

from posture_id.cli import main

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text(encoding="utf-8")
_FENCE = re.compile(r"```(\w*)\n(.*?)```", re.DOTALL)


def _blocks(language: str) -> list[str]:
    return [body for lang, body in _FENCE.findall(README) if lang == language]


def _commands() -> list[str]:
    """Every ``posture-id`` line of the README's plain code blocks, in order."""
    return [line.strip() for block in _blocks("") for line in block.splitlines()
            if line.strip().startswith("posture-id ")]


def _in_the_repository(word: str) -> str:
    """A word naming a file of the repository (the shipped examples, urdf/) made absolute;
    any other word as it is."""
    return str(ROOT / word) if "/" in word and (ROOT / word).exists() else word


def test_the_readme_is_short_and_quotes_five_commands_and_a_robot():
    assert len(README.splitlines()) <= 150
    commands = _commands()
    assert sum(c.startswith("posture-id identify ") for c in commands) >= 4
    assert any(c.startswith("posture-id compare ") for c in commands)
    assert any("--from-robot" in c for c in commands)
    assert len(_blocks("python")) == 1


@pytest.mark.slow("the README's commands end to end")
def test_the_quickstart_commands_run_as_written(tmp_path, monkeypatch, capsys):
    """Each command answers (0, or 1 for an answer its verdict doubts) and writes its
    result; the subject's parameters are the ones the shipped truth holds, within 20 %."""
    monkeypatch.chdir(tmp_path)
    for command in _commands():
        words = [_in_the_repository(w) for w in shlex.split(command)[1:]]
        assert main(words) in (0, 1), command
    for name in ("result.json", "lab.json", "c3d.json", "compare.json", "talos.json"):
        assert (tmp_path / name).is_file(), name
    assert (tmp_path / "result.png").is_file() and (tmp_path / "result.intervals.png").is_file()
    truth = json.loads((ROOT / "posture_id/studies/examples/tip_subject.truth.json").read_text())
    found = json.loads((tmp_path / "result.json").read_text())["parameters"]
    for joint, module in truth.items():
        assert found[joint]["controls"] == module["controls"], joint
        assert abs(found[joint]["kp"] / module["kp"] - 1) < 0.2, joint


@pytest.mark.slow("the README's Python example end to end")
def test_the_python_example_runs_as_written(tmp_path, monkeypatch, capsys):
    (code,) = _blocks("python")
    code = code.replace('"posture_id/studies/examples/', f'"{ROOT}/posture_id/studies/examples/')
    monkeypatch.chdir(tmp_path)
    exec(compile(code, "README.md", "exec"), {})  # noqa: S102 - the README's own example
    out = capsys.readouterr().out
    assert "ankle" in out and (tmp_path / "result.png").is_file()
