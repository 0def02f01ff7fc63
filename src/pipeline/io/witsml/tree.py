"""The XML tree of a WITSML document, parsed with expat in one call over the whole file, each
element's text joined once (linear time: fed in chunks, expat rescans a token split by every
chunk, and appending to a string per chunk copies it), keeping each element's line so every
problem names it; a DOCTYPE or an entity declaration is refused (a WITSML document needs
neither, and they are how XML documents attack their readers)."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any
from xml.parsers import expat

from pipeline.errors import InputFileError
from pipeline.io.witsml.terms import NS


@dataclass
class Node:
    """One XML element: local name, namespace, attributes, text, children and its line."""

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
    """Something the parser refuses to read."""


def parse(path: Path) -> Node:
    """The document's root element, with lines; malformed XML is an InputFileError."""
    parser = expat.ParserCreate(namespace_separator=" ")
    parser.buffer_text = True
    stack: list[Node] = []
    pieces: list[list[str]] = []  # the text pieces of each open element, joined at its end
    roots: list[Node] = []

    def start(name: str, attrs: dict[str, str]) -> None:
        namespace, _, local = name.rpartition(" ")
        node = Node(local, namespace, attrs, parser.CurrentLineNumber)
        (stack[-1].children if stack else roots).append(node)
        stack.append(node)
        pieces.append([])

    def end(name: str) -> None:
        stack.pop().text = "".join(pieces.pop())

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
    try:  # one Parse call: fed in chunks, expat rescans a token cut by each chunk boundary
        parser.Parse(path.read_bytes(), True)  # (a 30 MB attribute: minutes, not 0.05 s)
    except expat.ExpatError as exc:
        raise InputFileError(
            path,
            f"not well-formed XML: {expat.ErrorString(exc.code)} (column {exc.offset + 1})",
            line=exc.lineno,
        ) from None
    except _Refused as exc:
        raise InputFileError(path, str(exc), line=parser.CurrentLineNumber) from None
    except (LookupError, ValueError) as exc:  # UnicodeError is a ValueError
        # the encoding the XML declaration names is unknown, not text, or multi-byte
        raise InputFileError(
            path, f"unusable encoding in the XML declaration: {exc}", line=parser.CurrentLineNumber
        ) from None
    except OSError as exc:
        raise InputFileError(path, f"cannot read the file: {exc}") from None
    return roots[0]
