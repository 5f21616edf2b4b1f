"""MkDocs hook: the references made from the program itself.

A page holding the marker ``<!-- cli-reference -->`` gets, in its place, the ``--help`` of
``posture-id`` and of every command and sub-command; one holding ``<!-- api-reference -->``
gets an entry (rendered by mkdocstrings from the docstrings) for every name
``posture_id`` exports. Neither can drift from the program. The docstrings' cross-reference
roles (``:func:`~posture_id.x.name```) are shown as the code they name.
"""

from __future__ import annotations

import argparse
import os
import re

MARKER = "<!-- cli-reference -->"
API_MARKER = "<!-- api-reference -->"


def _parsers(parser: argparse.ArgumentParser, path: tuple[str, ...]):
    yield path, parser
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, child in action.choices.items():
                yield from _parsers(child, (*path, name))


def reference() -> str:
    """Every parser's help, a section each."""
    from posture_id.cli import build_parser

    os.environ["COLUMNS"] = "100"  # one width, whatever the terminal
    parts = []
    for path, parser in _parsers(build_parser(), ("posture-id",)):
        level = "#" * min(len(path) + 1, 4)
        parts.append(f"{level} `{' '.join(path)}`\n\n```text\n{parser.format_help()}```\n")
    return "\n".join(parts)


_ENTRY = re.compile(r"(\*{0,2}\w+)(?: \([^)]*\))?: \S")


def argument_entries(obj) -> list[str] | None:
    """The names of the entries of ``obj``'s ``Args:`` section, one an argument (Google
    style: ``name: text``, its text's further lines indented deeper); None where the
    docstring has no such section."""
    import inspect

    lines = (inspect.getdoc(obj) or "").splitlines()
    if "Args:" not in (line.strip() for line in lines):
        return None
    start = next(k for k, line in enumerate(lines) if line.strip() == "Args:")
    indent = len(lines[start]) - len(lines[start].lstrip()) + 4
    names = []
    for line in lines[start + 1:]:
        if line.strip() and len(line) - len(line.lstrip()) < indent:
            break  # the next section
        if line.strip() and len(line) - len(line.lstrip()) == indent:
            entry = _ENTRY.match(line.strip())
            names.append(entry.group(1) if entry else line.strip())
    return names


def one_entry_per_argument(obj) -> bool:
    """Whether ``obj``'s docstring gives each of its arguments an entry of its own, and
    nothing else (rendered then as a table of the arguments, their types from the
    annotations, and their defaults)."""
    import inspect

    signature = inspect.signature(obj.__init__ if inspect.isclass(obj) else obj)
    wanted = [("*" if p.kind is p.VAR_POSITIONAL else "**" if p.kind is p.VAR_KEYWORD
               else "") + p.name for p in signature.parameters.values()
              if p.name not in ("self", "cls")]
    entries = argument_entries(obj)
    return entries is not None and sorted(entries) == sorted(wanted)


def api_reference() -> str:
    """A mkdocstrings entry for every class and function ``posture_id`` exports, by the
    module it is defined in; one written one entry per argument is parsed as such (Google
    style), the others shown as written."""
    import inspect

    import posture_id

    entries = []
    for name in posture_id.__all__:
        obj = getattr(posture_id, name)
        if inspect.ismodule(obj):  # posture_id.identify: the package, callable as its function
            obj = getattr(obj, name)
        if inspect.isclass(obj) or inspect.isfunction(obj):
            style = ("\n    options:\n      docstring_style: google"
                     if one_entry_per_argument(obj) else "")
            entries.append(f"::: {obj.__module__}.{name}{style}\n")
    return "\n".join(entries)


def on_page_markdown(markdown: str, page, config, files) -> str:  # noqa: ARG001 - MkDocs API
    if MARKER in markdown:
        markdown = markdown.replace(MARKER, reference())
    if API_MARKER in markdown:
        markdown = markdown.replace(API_MARKER, api_reference())
    return markdown


_ROLE = re.compile(r":(?:func|class|meth|data|mod|attr|exc):(<code>)~?")


def on_page_content(html: str, page, config, files) -> str:  # noqa: ARG001 - MkDocs API
    """Drop the docstrings' reST roles before their code spans."""
    return _ROLE.sub(r"\1", html)
