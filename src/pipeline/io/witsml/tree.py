"""The XML tree of a WITSML document, parsed with expat a MiB of the file at a time (never held
whole), each element's text joined once (appending to a string per piece copies it), keeping
each element's line so every problem names it; a DOCTYPE or an entity declaration is refused
(a WITSML document needs neither, and they are how XML documents attack their readers), as
is an element's text (its ends stripped) or an attribute's value longer than
:data:`~pipeline.io.limits.TEXT_MAX` characters, naming the element and its line: no
WITSML store writes one, and one would be copied into every table and file read from it."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any
from xml.parsers import expat

from pipeline.errors import InputFileError
from pipeline.io.limits import TEXT_MAX
from pipeline.io.witsml.terms import NS


@dataclass(slots=True)
class Node:
    """One XML element: local name, namespace, attributes, text, children and its line (no
    per-instance ``__dict__``: a trajectory of 10⁵ stations is 1.2 million of them)."""

    name: str
    namespace: str
    attrs: dict[str, str]
    line: int
    children: list[Node] = field(default_factory=list)
    text: str = ""

    def all(self, name: str) -> list[Node]:
        """Children of this local name in the WITSML namespace."""
        return [c for c in self.children if c.name == name and c.namespace == NS]

    def get(self, name: str) -> Node | None:
        """The child of this local name (None: none); :class:`RepeatedElement`: several (each
        element read by name is one the schema allows once in its parent)."""
        found = self.all(name)
        if len(found) > 1:
            raise RepeatedElement(self, found[1])
        return found[0] if found else None

    def text_of(self, name: str) -> str | None:
        """The text of the first child of this name, whitespace collapsed (None: no child,
        or no text)."""
        child = self.get(name)
        return " ".join(child.text.split()) or None if child is not None else None


class RepeatedElement(Exception):
    """A second child of a name the schema allows once: which one the file means is unknown
    (``line``: the second's)."""

    def __init__(self, parent: Node, second: Node) -> None:
        super().__init__(
            f"<{second.name}> appears twice in <{parent.name}> (line {parent.line}): WITSML "
            "1.4.1.1 allows one, and which the file means is unknown"
        )
        self.line = second.line


class _Refused(Exception):
    """Something the parser refuses to read (``line``: where, else the parser's line)."""

    def __init__(self, message: str, line: int | None = None) -> None:
        super().__init__(message)
        self.line = line


def _too_long(what: str, line: int) -> _Refused:
    return _Refused(
        f"{what} is longer than {TEXT_MAX:,} characters (WITSML 1.4.1.1's longest text, a "
        "comment, is 4,000): refused",
        line,
    )


CHUNK = 1 << 20
"""Bytes of the file read and parsed at a time (what one ``Parse`` call of the whole file
feeds expat at a time too: a 30 MB attribute parses in 0.5 s; in 64 kB chunks, expat
rescanning the token cut by each, minutes)."""
RUN_MAX = 8 << 20
"""Most bytes without a ``<`` (one tag or text: no WITSML element comes near) expat holds
unparsed and rescans each chunk: a token past it is refused before it costs seconds."""


def _feed(parser: Any, path: Path) -> None:
    """Parse the file chunk by chunk: the document is never held whole (a 925 MiB file of
    one hostile line repeated was read into memory before its first error: 1 GiB)."""
    run, newlines, line = 0, 0, 1  # bytes since the last "<", lines read, the "<"'s line
    with path.open("rb") as fh:
        while chunk := fh.read(CHUNK):
            at = chunk.rfind(b"<")
            if at >= 0:
                run, line = len(chunk) - at - 1, 1 + newlines + chunk.count(b"\n", 0, at)
            else:
                run += len(chunk)
            newlines += chunk.count(b"\n")
            if run > RUN_MAX:
                raise _Refused(
                    f"over {RUN_MAX >> 20} MiB of one tag or text from its '<' on (no WITSML "
                    "element comes near): refused",
                    line,
                )
            parser.Parse(chunk, False)
    parser.Parse(b"", True)


SHARED_MAX = 64
"""Longest name, attribute or text kept once however often it repeats (a uom, a namespace, a
``typeTrajStation``: the same few strings on every station); longer ones are each their own."""
_SHARED_COUNT = 1 << 14
"""Most distinct strings shared per document (a station's uid or md repeats no other's)."""


def parse(path: Path) -> Node:
    """The document's root element, with lines; malformed XML is an InputFileError."""
    parser = expat.ParserCreate(namespace_separator=" ")
    parser.buffer_text = True
    stack: list[Node] = []
    pieces: list[list[str]] = []  # the text pieces of each open element, joined at its end
    roots: list[Node] = []
    shared: dict[str, str] = {}  # one copy of each short repeated string
    once_attrs: dict[tuple[tuple[str, str], ...], dict[str, str]] = {}

    def once(value: str) -> str:
        found = shared.get(value)
        if found is None:
            found = value
            if len(shared) < _SHARED_COUNT:
                shared[value] = value
        return found

    def start(name: str, attrs: dict[str, str]) -> None:
        namespace, _, local = name.rpartition(" ")
        for key, value in attrs.items():
            if len(value) > TEXT_MAX:
                line = parser.CurrentLineNumber
                raise _too_long(f"attribute {key.rpartition(' ')[2]!r} of <{local}>", line)
        if attrs:  # {"uom": "m"} on every md: one dict (attributes are only read)
            items = tuple(
                (once(k), once(v) if len(v) <= SHARED_MAX else v) for k, v in attrs.items()
            )
            attrs = once_attrs.get(items) or dict(items)
            if len(once_attrs) < _SHARED_COUNT and all(len(v) <= SHARED_MAX for _, v in items):
                once_attrs.setdefault(items, attrs)
        node = Node(once(local), once(namespace), attrs, parser.CurrentLineNumber)
        (stack[-1].children if stack else roots).append(node)
        stack.append(node)
        pieces.append([])

    def end(name: str) -> None:
        node = stack.pop()
        text = "".join(pieces.pop())
        node.text = once(text) if len(text) <= SHARED_MAX else text
        # its ends stripped: the whitespace between a trajectory's 10⁵ indented stations is 10⁶
        if len(node.text) > TEXT_MAX and len(node.text.strip()) > TEXT_MAX:
            raise _too_long(f"the text of <{node.name}>", node.line)

    def text(data: str) -> None:
        if stack:
            pieces[-1].append(data)

    def refuse(*args: Any) -> None:
        raise _Refused("DOCTYPE and entity declarations are not accepted in WITSML")

    parser.StartElementHandler = start
    parser.EndElementHandler = end
    parser.CharacterDataHandler = text
    parser.StartDoctypeDeclHandler = refuse
    parser.EntityDeclHandler = refuse
    try:
        _feed(parser, path)
    except expat.ExpatError as exc:
        raise InputFileError(
            path,
            f"not well-formed XML: {expat.ErrorString(exc.code)} (column {exc.offset + 1})",
            line=exc.lineno,
        ) from None
    except _Refused as exc:
        line = exc.line or parser.CurrentLineNumber
        raise InputFileError(path, str(exc), line=line) from None
    except (LookupError, ValueError) as exc:  # UnicodeError is a ValueError
        # the encoding the XML declaration names is unknown, not text, or multi-byte
        raise InputFileError(
            path, f"unusable encoding in the XML declaration: {exc}", line=parser.CurrentLineNumber
        ) from None
    except OSError as exc:
        raise InputFileError(path, f"cannot read the file: {exc}") from None
    return roots[0]
