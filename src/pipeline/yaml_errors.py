"""PyYAML's parser errors in gyropipe's words: where the mistake is and what was expected.

The parser reports an indentation mistake by the token it did not expect (``expected
<block end>, but found '<block mapping start>'``, ``mapping values are not allowed here``)
at a mark that is often not where the mistake is. :func:`explain` re-reads the lines above
the mistake to say what a person would: which line is out of line, by how many spaces,
and with what (the keys of a mapping, the ``-`` items of a list, at which column of which
line), or that a tab indents it. Other errors keep the parser's words, its tokens named
(``'<stream end>'`` → "the end of the text").
"""

from __future__ import annotations

import re
from dataclasses import dataclass

import yaml

_ITEM = re.compile(r"( *)(- +)?(?:([^\s#'\"{\[][^:#]*?|'[^']*'|\"[^\"]*\")\s*:(?:\s|$))?")
_TOKENS = {
    "<stream end>": "the end of the text",
    "<block end>": "the end of the block",
    "<block mapping start>": "a key",
    "<block sequence start>": "a '-' list item",
    "<document start>": "'---'",
    "found unexpected end of stream": "the text ends inside it",
}


@dataclass(frozen=True)
class _Open:
    """An open block above the mistake: its column (1-based), whether it is a list's ``-``
    items or a mapping's keys, and the line (1-based) and key it was seen on."""

    column: int
    dash: bool
    line: int
    key: str


def explain(exc: yaml.MarkedYAMLError, text: str) -> tuple[int, int, str]:
    """(line, column, message) of a parser error of ``text``: the line and column are
    1-based (0, 0 where the parser gave no mark)."""
    mark = exc.problem_mark or exc.context_mark
    if mark is None:
        return 0, 0, f"malformed YAML: {_words(str(exc.problem or exc))}"
    lines = text.splitlines()
    line, column = mark.line + 1, mark.column + 1
    problem = str(exc.problem or "")
    if "'\\t'" in problem:
        return line, column, "malformed YAML: a tab; YAML indents with spaces only"
    out_of_line = problem.startswith("expected <block end>") or (
        problem == "mapping values are not allowed here"
    )
    if out_of_line and mark.line < len(lines):
        found = _indentation(lines, mark.line)
        if found is not None:
            return line, found[0], f"malformed YAML: {found[1]}"
    if problem == "mapping values are not allowed here":
        return line, column, "malformed YAML: ': ' inside a value; put the value in quotes"
    opened = _UNCLOSED.get(str(exc.context or ""))
    if opened is not None and exc.context_mark is not None:
        start = exc.context_mark
        where = f"line {start.line + 1}, column {start.column + 1}"
        return (
            line,
            column,
            f"malformed YAML: the {opened} at {where} is not closed ({_words(problem)})",
        )
    return line, column, f"malformed YAML: {_words(problem or str(exc))}"


_UNCLOSED = {
    "while parsing a flow mapping": "'{'",
    "while parsing a flow sequence": "'['",
    "while scanning a quoted scalar": "quote",
}
"""The parser's context of an unclosed bracket or quote → what was opened."""


def _indentation(lines: list[str], at: int) -> tuple[int, str] | None:
    """Column (1-based) and message of line ``at`` (0-based) when it lines up with no
    open block above it; None when it does (the mistake is another)."""
    item = _ITEM.match(lines[at])
    assert item is not None  # every part is optional
    indent = len(item[1]) + 1
    dash = item[2] is not None
    if not dash and item[3] is None:
        return None
    opened = _open_blocks(lines[:at])
    same = [b for b in opened if b.dash == dash]
    if not same or any(b.column == indent for b in same):
        return None
    nearest = min(abs(b.column - indent) for b in same)
    meant = [b for b in same if abs(b.column - indent) == nearest]
    what = "a list's '-' items must line up" if dash else "a mapping's keys must line up"
    spaces = "1 space" if nearest == 1 else f"{nearest} spaces"
    told = " or ".join(
        f"{'more' if indent > b.column else 'less'} than {_named(b)} "
        f"(line {b.line}, column {b.column})"
        for b in meant
    )
    return indent, f"indented {spaces} {told}: {what}"


def _named(block: _Open) -> str:
    return "the list's items" if block.dash else f"the key {block.key!r}"


def _open_blocks(lines: list[str]) -> list[_Open]:
    """The blocks still open after ``lines``, outermost first: each content line closes
    those at or right of its first column, then opens its '-' and its key."""
    opened: list[_Open] = []
    for number, text in enumerate(lines, 1):
        if not text.strip() or text.lstrip().startswith("#"):
            continue
        item = _ITEM.match(text)
        assert item is not None
        column = len(item[1]) + 1
        opened = [b for b in opened if b.column < column]
        if item[2] is not None:
            opened.append(_Open(column, True, number, "-"))
            column += len(item[2])
        if item[3] is not None:
            opened.append(_Open(column, False, number, item[3].strip("'\"")))
    return opened


def _words(problem: str) -> str:
    """The parser's message with its token names in words."""
    for token, words in _TOKENS.items():
        problem = problem.replace(f"'{token}'", words).replace(token, words)
    return problem
