"""The docs match the program: every command they quote names flags and choices the
command line has, and the concrete ones that are cheap run as quoted."""

from __future__ import annotations

import argparse
import os
import re
import shlex
from pathlib import Path

import pytest

from posture_id.cli import build_parser, main

ROOT = Path(__file__).resolve().parents[1]
DOCS = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
#: A quoted command: a line of a code block, or an inline `...` span.
_BLOCK = re.compile(r"^\s*(posture-id [^`#\n]*?)(?:\s+#.*)?$", re.MULTILINE)
_INLINE = re.compile(r"`(posture-id [^`]*)`")


def quoted_commands() -> list[tuple[str, str]]:
    """(where, command) of every posture-id command the README and docs quote; a code
    line ending in a backslash is joined with the next."""
    out = []
    for path in DOCS:
        text = path.read_text(encoding="utf-8").replace("\\\n", " ")
        for pattern in (_BLOCK, _INLINE):
            for match in pattern.finditer(text):
                line = text.count("\n", 0, match.start()) + 1
                out.append((f"{path.relative_to(ROOT)}:{line}", match.group(1).strip()))
    return out


def _subparsers(parser: argparse.ArgumentParser) -> dict[str, argparse.ArgumentParser]:
    for action in parser._actions:  # noqa: SLF001 - argparse keeps them here
        if isinstance(action, argparse._SubParsersAction):  # noqa: SLF001
            return dict(action.choices)
    return {}


def _flags(parser: argparse.ArgumentParser) -> dict[str, argparse.Action]:
    return {flag: action for action in parser._actions  # noqa: SLF001
            for flag in action.option_strings}


COMMANDS = quoted_commands()


def test_the_docs_quote_commands():
    assert len(COMMANDS) > 50  # the extraction works


@pytest.mark.parametrize(("where", "command"), COMMANDS, ids=[w for w, _ in COMMANDS])
def test_every_quoted_flag_and_choice_exists(where, command):
    """Each quoted command names a real subcommand, and every --flag it shows (in a
    template too: [--flag X], --flag a|b) is one of that subcommand's, with any literal
    choice among its choices."""
    root = build_parser()
    words = command.replace("[", " ").replace("]", " ").split()[1:]
    if not words or words[0] in ("--debug", "--help", "...", "-h"):
        return
    commands = _subparsers(root)
    assert words[0] in commands, f"{where}: no command {words[0]!r}"
    parser = commands[words[0]]
    for word in words[1:]:  # down the sub-commands named (network cnn data generate, ...)
        below = _subparsers(parser)
        if not below or word.startswith("-") or word not in below:
            break
        parser = below[word]
    flags = _flags(parser) | _flags(root)
    for k, word in enumerate(words):
        if not word.startswith("--"):
            continue
        flag = word.split("=")[0]
        assert flag in flags, f"{where}: {words[0]} has no {flag} ({command})"
        action = flags[flag]
        if action.choices and k + 1 < len(words):
            for value in words[k + 1].split("|"):
                if value.isidentifier() or value.lstrip("+-").isdigit():
                    assert value in map(str, action.choices), (
                        f"{where}: {flag} takes {sorted(map(str, action.choices))}, the docs "
                        f"say {value!r}")


#: Concrete quoted commands that are cheap: run as quoted (outputs into a temporary
#: folder), each must exit 0.
_RUNNABLE = re.compile(r"^posture-id (body|frf|simulate) [^\[\]|<>]*$")


def _inputs_exist(command: str) -> bool:
    """Every file the command reads (words ending .csv, .urdf or .json that are not
    outputs) is in the repository."""
    words = shlex.split(command)
    outputs = {words[k + 1] for k, w in enumerate(words[:-1]) if w in ("--out", "--plot")}
    return all((ROOT / w).is_file() for w in words
               if w.endswith((".csv", ".urdf", ".json", ".c3d")) and w not in outputs)


@pytest.mark.parametrize("command", sorted({c for _, c in COMMANDS if _RUNNABLE.match(c)
                                            and "..." not in c and _inputs_exist(c)
                                            and not c.split()[-1].startswith("--")
                                            and not any(w.isupper() for w in c.split())}))
def test_cheap_quoted_commands_run(command, tmp_path, monkeypatch):
    words = shlex.split(command)[1:]
    for k, word in enumerate(words):  # outputs go to the temporary folder
        if word in ("--out", "--plot") and k + 1 < len(words):
            words[k + 1] = str(tmp_path / Path(words[k + 1]).name)
    monkeypatch.chdir(ROOT)
    assert main(words) == 0, command


def _prose_blocks(text: str) -> list[str]:
    """The README's bullets and paragraphs, code blocks left out."""
    prose = re.sub(r"```.*?```", "", text, flags=re.DOTALL)
    return [b for b in re.split(r"\n(?=- )|\n\n", prose) if b.strip()]


def test_every_number_the_readme_claims_names_where_it_comes_from():
    """A bullet or paragraph of the README that states a measured number (a percentage, a
    time, a ratio) names the doc or benchmark that reproduces it."""
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    unsourced = [b[:120] for b in _prose_blocks(text)
                 if re.search(r"\d[\d.,  ]*\s?(?:%|ms\b|s\b|×)", b)
                 and not re.search(r"(docs|benchmarks)/[\w./-]+", b)]
    assert not unsourced, unsourced


@pytest.mark.parametrize("report", sorted([*(ROOT / "docs" / "results").glob("*.md"),
                                           *(ROOT / "docs").glob("**/calibration_report.md"),
                                           *(ROOT / "docs" / "results").glob("*/*.md")]),
                         ids=lambda p: str(p.relative_to(ROOT)))
def test_every_results_report_names_the_command_that_wrote_it(report):
    text = report.read_text(encoding="utf-8")
    assert re.search(r"[Mm]ade by `(posture-id|benchmarks/|\.venv/bin/python)", text), report


#: Every page of the documentation: the README and every Markdown file under docs/.
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]
#: What no page may say: the model is docs/model.md, inside the repository.
_OUTSIDE = ("../shared", "MODEL.md", "MODEL §", "/work/")
_LINK = re.compile(r"\[[^\]\n]*\]\(\s*<?([^)\s>]+)>?(?:\s+[\"'][^\"']*[\"'])?\s*\)")
_EXTERNAL = re.compile(r"^(?:https?://|mailto:)", re.IGNORECASE)


def _prose_lines(text: str) -> list[tuple[int, str]]:
    """(line number, line) of a page's prose: fenced and indented code blocks left out,
    inline code spans blanked."""
    out, fence, code, blank = [], None, False, True
    for number, line in enumerate(text.splitlines(), 1):
        stripped = line.lstrip()
        if fence is not None:
            if stripped.startswith(fence):
                fence = None
            continue
        if stripped.startswith(("```", "~~~")):
            fence = stripped[:3]
            continue
        code = line.startswith(("    ", "\t")) and (blank or code) and bool(stripped)
        blank = not stripped
        if not code:
            out.append((number, re.sub(r"`[^`]*`", "``", line)))
    return out


def _link_problem(page: Path, target: str) -> str | None:
    """Why a link target of ``page`` is wrong, or None: a relative path (its #fragment
    dropped) must name a file or folder inside the repository."""
    if _EXTERNAL.match(target) or target.startswith("#"):
        return None
    path = target.split("#", 1)[0].split("?", 1)[0]
    if not path:
        return None
    resolved = (page.parent / path).resolve()
    if not resolved.is_relative_to(ROOT):
        return f"link {target!r} leaves the repository"
    if not resolved.exists():
        return f"link {target!r} names no file"
    return None


def test_no_page_refers_outside_the_repository():
    """No page names a file outside the repository (the model is docs/model.md), and every
    relative link resolves to a file inside it."""
    problems = []
    for page in PAGES:
        where = page.relative_to(ROOT)
        text = page.read_text(encoding="utf-8")
        for number, line in enumerate(text.splitlines(), 1):
            problems += [f"{where}:{number}: {s!r}" for s in _OUTSIDE if s in line]
        for number, line in _prose_lines(text):
            for match in _LINK.finditer(line):
                problem = _link_problem(page, match.group(1))
                if problem:
                    problems.append(f"{where}:{number}: {problem}")
    assert not problems, "\n".join(problems)


def test_the_code_cites_the_model_inside_the_repository():
    """The package's docstrings, comments and messages cite docs/model.md, never a file
    outside the repository (generated copies in _prebuilt/ are not sources)."""
    problems = []
    for path in sorted((ROOT / "posture_id").rglob("*.py")):
        if "_prebuilt" in path.parts:
            continue
        for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
            problems += [f"{path.relative_to(ROOT)}:{number}: {s!r}"
                         for s in ("MODEL §", "../shared") if s in line]
    assert not problems, "\n".join(problems)


def test_the_link_check_sees_what_it_must():
    """The checks above catch what they are for, and leave code and external links alone."""
    page = ROOT / "docs" / "model.md"
    assert _link_problem(page, "../../elsewhere/MODEL.md") == (
        "link '../../elsewhere/MODEL.md' leaves the repository")
    assert _link_problem(page, "missing.md#x") == "link 'missing.md#x' names no file"
    for fine in ("model.md#8-the-independent-channel-model", "#2-the-dec-controller",
                 "https://example.org/x", "mailto:a@b.c", "../README.md", "tutorials/cohort.py"):
        assert _link_problem(page, fine) is None, fine
    lines = _prose_lines("a [x](a.md)\n\n    code [y](b.md)\n\n```\n[z](c.md)\n```\n`[w](d.md)`\n")
    assert [n for n, line in lines if _LINK.search(line)] == [1]


def test_the_pages_describe_the_program_as_it_is():
    """No page of the README or docs/ narrates how the work was organised (issue or stop
    numbers, dates of changes): history is CHANGELOG.md's."""
    narrating = re.compile(r"\bissues? \d+|\bstops? \d+|\b20\d\d-\d\d-\d\d\b", re.IGNORECASE)
    found = [f"{path.relative_to(ROOT)}:{n}: {line.strip()[:80]}"
             for path in [ROOT / "README.md", *sorted((ROOT / "docs").glob("**/*.md"))]
             if "results" not in path.parts and "models" not in path.parts
             and path.name != "changelog.md"
             for n, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1)
             if narrating.search(line)]
    assert not found, found


def _links_to_no_page(site: Path) -> list[str]:
    """``page: href`` of every link between the site's pages (the served-only 404 page
    aside) that names a folder or nothing, as a link opened from disk would show it."""
    bad = []
    for page in sorted(site.rglob("*.html")):
        if page.name == "404.html":  # served only: its links are absolute
            continue
        for href in re.findall(r'href="([^"]+)"', page.read_text(encoding="utf-8")):
            target = href.split("#")[0].split("?")[0]
            if not target or re.match(r"^[a-z]+:", target):
                continue
            path = (page.parent / target).resolve()
            if path.is_dir() or not path.exists():
                bad.append(f"{page.relative_to(site)}: {href}")
    return bad


@pytest.mark.slow("builds the documentation site")
def test_the_site_works_opened_from_disk(tmp_path):
    """Every link between the built site's pages names an existing page file (``.html``),
    not a folder a browser opened from disk would list."""
    import subprocess
    import sys

    config = (ROOT / "docs" / "config" / "mkdocs.yml").read_text(encoding="utf-8")
    site = tmp_path / "site"
    built = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--quiet", "-f", "-",
                            "--site-dir", str(site)], input=config, cwd=ROOT, text=True,
                           capture_output=True,
                           env={**os.environ, "NO_MKDOCS_2_WARNING": "1"})
    assert built.returncode == 0, built.stderr[-2000:]
    assert (site / "index.html").exists()
    assert _links_to_no_page(site) == []
    (site / "broken.html").write_text('<a href="api/">the API</a><a href="none.html">x</a>')
    assert _links_to_no_page(site) == ["broken.html: api/", "broken.html: none.html"]
