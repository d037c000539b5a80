"""The command lines in README.md and docs/*.md match the CLI (``hapmotion.cli``, introspected):

- every option written for ``hapmotion CMD`` exists on that command;
- every option of every command is documented somewhere;
- an options table of a command lists every option of that command.

An option is "written for CMD" when it follows ``hapmotion CMD`` in a code block line (up to a shell comment,
pipe or ``;``) or in the same inline code span, or when it is in the first column of an options table (header
``Option``) whose section names ``hapmotion CMD`` before the table. Options are long (``--gain``) or short
(``-o``); either spelling documents an option.
"""

from __future__ import annotations

import re
from pathlib import Path

import click
import pytest

from hapmotion.cli import cli

ROOT = Path(__file__).resolve().parents[1]
DOCS = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]

OPTION = re.compile(r"(?<![\w-])(?:--[a-z][a-z0-9]*(?:-[a-z0-9]+)*|-[a-zA-Z])(?![\w-])")
COMMAND = re.compile(r"(?<![\w.-])hapmotion\s+([a-z][a-z-]*)")
SHELL_END = re.compile(r"\s#|\||;|&&")  # a comment, a pipe or the next command ends a command line
HEADING = re.compile(r"^#{1,6}\s")
GENERIC = {"--help", "-h"}  # every command has them, from click


def command_options() -> dict[str, list[set[str]]]:
    """The options of every command as click declares them: one set of spellings per option (``{"-o",
    "--output"}``, ``{"--mirror", "--no-mirror"}``); ``--help`` is left out."""
    return {name: [{*param.opts, *param.secondary_opts} for param in command.params
                   if isinstance(param, click.Option) and not param.hidden]
            for name, command in cli.commands.items()}


def spellings(options: list[set[str]]) -> set[str]:
    return set().union(*options, GENERIC)


def doc_lines(path: Path) -> list[tuple[int, str, bool]]:
    """``(line number, text, in a code block)``; a code line ending in a backslash is joined with the next."""
    out: list[tuple[int, str, bool]] = []
    in_code = False
    pending: tuple[int, str] | None = None
    for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
        if line.lstrip().startswith("```"):
            in_code = not in_code
            continue
        if in_code:
            start, text = pending if pending else (number, "")
            text += line
            if line.rstrip().endswith("\\"):
                pending = (start, text.rstrip()[:-1] + " ")
                continue
            pending = None
            out.append((start, text, True))
        else:
            out.append((number, line, False))
    return out


def command_mentions(text: str, in_code: bool) -> list[tuple[str, str]]:
    """``(command, the text written for it)`` for each ``hapmotion CMD`` on a line."""
    spans = [text] if in_code else text.split("`")[1::2]
    out = []
    for span in spans:
        for found in COMMAND.finditer(span):
            rest = span[found.end():]
            nxt = COMMAND.search(rest)
            rest = rest[:nxt.start()] if nxt else rest
            if in_code:
                end = SHELL_END.search(rest)
                rest = rest[:end.start()] if end else rest
            out.append((found.group(1), rest))
    return out


def table_cells(line: str) -> list[str]:
    return [c.strip() for c in re.split(r"(?<!\\)\|", line.strip().strip("|"))]


def written_options(path: Path) -> list[tuple[int, str, str, int]]:
    """``(line number, command, option, table)`` for every option the page writes for a command (see the module
    doc); ``table`` is the line number of the options table's header, 0 outside tables; command ``"?"`` for a
    table whose section names no command."""
    out = []
    lines = doc_lines(path)
    section_commands: list[str] = []  # commands named since the last heading, in order
    table_command: str | None = None
    table_start = 0
    in_table = False
    for i, (number, text, in_code) in enumerate(lines):
        if not in_code and HEADING.match(text):
            section_commands = []
        mentions = command_mentions(text, in_code)
        for command, rest in mentions:
            out += [(number, command, opt, 0) for opt in OPTION.findall(rest)]
        is_row = not in_code and text.lstrip().startswith("|")
        if is_row and not in_table:
            in_table = True
            table_command, table_start = None, number
            if table_cells(text)[0].lower() == "option":
                table_command = section_commands[-1] if section_commands else "?"
        elif not is_row:
            in_table = False
        elif table_command is not None and not set(table_cells(text)[0]) <= set("-: "):
            out += [(number, table_command, opt, table_start) for opt in OPTION.findall(table_cells(text)[0])]
        if not is_row:
            section_commands += [command for command, _ in mentions]
    return out


def test_every_option_written_for_a_command_exists_on_it():
    options = command_options()
    wrong = []
    for path in DOCS:
        for number, command, option, _ in written_options(path):
            where = f"{path.relative_to(ROOT)}:{number}"
            if command == "?":
                wrong.append(f"{where}: an options table whose section names no `hapmotion CMD` ({option})")
            elif command not in options:
                wrong.append(f"{where}: `hapmotion {command}` is not a command (with {option})")
            elif option not in spellings(options[command]):
                wrong.append(f"{where}: `hapmotion {command}` has no {option}")
    assert not wrong, "\n".join(wrong)


def test_every_option_of_every_command_is_documented():
    written = set()
    for path in DOCS:
        written.update(OPTION.findall(path.read_text(encoding="utf-8")))
    missing = [f"hapmotion {command} {'/'.join(sorted(option))}" for command, opts in sorted(command_options().items())
               for option in opts if not option & written]
    assert not missing, "not in README.md or docs/*.md:\n" + "\n".join(missing)


def test_an_options_table_lists_every_option_of_its_command():
    options = command_options()
    tables: dict[tuple[str, int, str], set[str]] = {}
    for path in DOCS:
        for _, command, option, table in written_options(path):
            if table and command in options:
                tables.setdefault((str(path.relative_to(ROOT)), table, command), set()).add(option)
    assert {command for _, _, command in tables} >= {"live", "listen", "view"}  # the tables are still found
    missing = [f"{page}:{table}: the options table of `hapmotion {command}` lacks {'/'.join(sorted(option))}"
               for (page, table, command), listed in sorted(tables.items())
               for option in options[command] if not option & listed]
    assert not missing, "\n".join(missing)


@pytest.mark.parametrize("text, in_code, expected", [
    ("hapmotion live --source osc://:9000 --sink player -q   # --not-this", True,
     [("live", {"--source", "--sink", "-q"})]),
    ("hapmotion render a.bvh -o a.csv | hapmotion plot a.csv --dpi 90", True,
     [("render", {"-o"}), ("plot", {"--dpi"})]),
    ("run `hapmotion view x.bvh --audio s.ogg` then --not-this and `hapmotion.live --no`", False,
     [("view", {"--audio"})]),
])
def test_options_are_read_from_the_command_they_follow(text, in_code, expected):
    got = [(command, set(OPTION.findall(rest))) for command, rest in command_mentions(text, in_code)]
    assert got == expected


def test_options_tables_are_read_for_the_command_their_section_names(tmp_path):
    page = tmp_path / "page.md"
    page.write_text("## The seat\n\n`hapmotion listen` takes:\n\n| Option | Meaning |\n|---|---|\n"
                    "| `--delay MS`, `--mirror/--no-mirror` | see `--not-this` |\n\n## Other\n\n"
                    "| option | meaning |\n|---|---|\n| `--lost` | x |\n", encoding="utf-8")
    assert written_options(page) == [(7, "listen", "--delay", 5), (7, "listen", "--mirror", 5),
                                     (7, "listen", "--no-mirror", 5), (13, "?", "--lost", 11)]
