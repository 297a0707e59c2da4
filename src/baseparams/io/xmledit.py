"""Editing an XML file in place: attribute values changed, elements added, everything else kept.

:func:`parse` reads a document with expat and keeps, for every element, where its start tag and
its end tag are in the file's bytes. An :class:`Editor` then changes attribute values inside
start tags, adds attributes, inserts elements (one per line, indented like their siblings) and
comments, and returns the document with every other byte as it was: the XML declaration,
comments, blank lines, indentation, attribute order and quoting. ElementTree's serialiser
rewrites all of these; a model file written back should differ from its source only where the
values changed.
"""

from __future__ import annotations

import re
import xml.parsers.expat
from dataclasses import dataclass, field

from ..errors import ModelError

_ATTR = re.compile(r"""(\s)([^\s=/>]+)(\s*=\s*)("[^"]*"|'[^']*')""")


@dataclass(eq=False)
class Node:
    """One element of a parsed document and where it is in the text.

    Parameters
    ----------
    tag : str
        The element's name, as written (no namespace processing).
    attrs : dict of str to str
        Its attributes, as read.
    start : int
        Index of the start tag's ``<`` in the text.
    head_end : int
        Index just after the start tag's ``>``.
    close : int or None
        Index of the end tag's ``<`` (``</tag>``), or None for an empty element (``<tag/>``).
    parent : Node or None
        The enclosing element.
    children : list of Node
        Child elements in document order.
    comments : list of tuple
        ``(start, end, text)`` of the comments directly inside the element.
    """

    tag: str
    attrs: dict
    start: int
    head_end: int = -1
    close: int | None = None
    parent: Node | None = None
    children: list = field(default_factory=list)
    comments: list = field(default_factory=list)

    def __repr__(self) -> str:
        name = self.attrs.get("name")
        return f"<Node <{self.tag}{f' name={name!r}' if name else ''}> at {self.start}, {len(self.children)} children>"

    def find(self, tag: str) -> Node | None:
        """The first child element named ``tag``.

        Parameters
        ----------
        tag : str
            The element name.

        Returns
        -------
        Node or None
            The child, or None when there is none.
        """
        return next((c for c in self.children if c.tag == tag), None)

    def findall(self, tag: str) -> list[Node]:
        """The child elements named ``tag``.

        Parameters
        ----------
        tag : str
            The element name.

        Returns
        -------
        list of Node
            In document order.
        """
        return [c for c in self.children if c.tag == tag]


def _head_end(text: str, start: int) -> int:
    """Index just after the ``>`` closing the start tag at ``start`` (quoted values skipped)."""
    k, quote = start + 1, None
    while k < len(text):
        ch = text[k]
        if quote:
            if ch == quote:
                quote = None
        elif ch in "\"'":
            quote = ch
        elif ch == ">":
            return k + 1
        k += 1
    raise ModelError("unterminated start tag")  # pragma: no cover - expat rejects it first


def parse(text: str, what: str) -> Node:
    """The document's root element with every element's position in ``text``.

    Parameters
    ----------
    text : str
        The whole document (a byte-order mark, whitespace before it and whitespace or NUL bytes
        after it are skipped, as the URDF reader skips them; positions are in ``text``).
    what : str
        The document's name, for messages.

    Returns
    -------
    Node
        The root element.

    Raises
    ------
    ModelError
        Malformed XML (one line naming ``what``, the line and the column).
    """
    # what the URDF reader tolerates: a byte-order mark and whitespace before, whitespace and NULs after
    lead = len(text) - len(text.lstrip("\ufeff \t\r\n"))
    body = text[lead:len(text.rstrip(" \t\r\n\x00"))]
    data = body.encode("utf-8")
    # expat reports byte offsets of the UTF-8 encoding; map them to character offsets
    char_at = None if len(data) == len(body) else _byte_to_char(body)
    p = xml.parsers.expat.ParserCreate("utf-8")
    stack: list[Node] = []
    root: list[Node] = []

    def pos() -> int:
        b = p.CurrentByteIndex
        return lead + (b if char_at is None else char_at[b])

    def on_start(name, attrs):
        node = Node(name, dict(attrs), pos(), parent=stack[-1] if stack else None)
        node.head_end = _head_end(text, node.start)
        if stack:
            stack[-1].children.append(node)
        else:
            root.append(node)
        stack.append(node)

    def on_end(name):
        node = stack.pop()
        if not text[:node.head_end].endswith("/>"):
            node.close = pos()

    def on_comment(body):
        if stack:
            start = pos()
            stack[-1].comments.append((start, start + len(body) + 7, body))

    p.StartElementHandler, p.EndElementHandler, p.CommentHandler = on_start, on_end, on_comment
    try:
        p.Parse(data, True)
    except xml.parsers.expat.ExpatError as exc:
        line = exc.lineno + text[:lead].count("\n")
        raise ModelError(f"{what}: malformed XML ({xml.parsers.expat.ErrorString(exc.code)}: line {line}, "
                         f"column {exc.offset})") from None
    return root[0]


def _byte_to_char(text: str) -> list[int]:
    """``char_at[b]``: the character index of UTF-8 byte offset ``b`` (for ``b`` at a character start)."""
    out = []
    for k, ch in enumerate(text):
        out += [k] * len(ch.encode("utf-8"))
    out.append(len(text))
    return out


def _escape(value: str, quote: str) -> str:
    return value.replace("&", "&amp;").replace("<", "&lt;").replace(quote, "&quot;" if quote == '"' else "&apos;")


class Editor:
    """Edits of a parsed document, applied together by :meth:`text`.

    Parameters
    ----------
    text : str
        The document :func:`parse` read.
    """

    def __init__(self, text: str):
        self.source = text
        self.newline = "\r\n" if "\r\n" in text else "\n"
        self._attrs: dict[int, tuple[Node, dict]] = {}
        self._append: dict[int, tuple[Node, list]] = {}
        self._edits: list[tuple[int, int, str]] = []

    def indent(self, node: Node) -> str | None:
        """The whitespace before ``node`` on its line.

        Parameters
        ----------
        node : Node
            An element of the document.

        Returns
        -------
        str or None
            The indentation, or None when other text precedes the element on its line.
        """
        line = self.source.rfind("\n", 0, node.start) + 1
        ws = self.source[line:node.start]
        return ws if ws.strip() == "" else None

    def child_indent(self, node: Node) -> str:
        """Indentation for a new child of ``node``.

        Parameters
        ----------
        node : Node
            The parent.

        Returns
        -------
        str
            Its children's indentation, else its own plus the document's step (its root's
            children's indentation, two spaces by default).
        """
        for c in node.children:
            ws = self.indent(c)
            if ws is not None:
                return ws
        own = self.indent(node) or ""
        step = "  "
        top = node
        while top.parent is not None:
            top = top.parent
        for c in top.children:  # the document's indentation step: its root's children's
            ws = self.indent(c)
            if ws:
                step = ws
                break
        return own + step

    def set(self, node: Node, **values: str) -> None:
        """Set attributes of ``node``.

        Parameters
        ----------
        node : Node
            The element.
        **values : str
            New attribute values: an existing attribute changes its value in place (quoting
            kept); others are added after the last attribute.
        """
        self._attrs.setdefault(id(node), (node, {}))[1].update(values)

    def append(self, node: Node, lines: list[str]) -> None:
        """Append children to ``node``, one line each, indented like its children.

        Parameters
        ----------
        node : Node
            The parent (an empty ``<tag/>`` is opened and closed).
        lines : list of str
            Lines of XML; leading spaces are kept after the child indentation (nested blocks).
        """
        self._append.setdefault(id(node), (node, []))[1].extend(lines)

    def insert_before(self, node: Node, line: str) -> None:
        """Insert a line just before ``node``, indented like it.

        Parameters
        ----------
        node : Node
            The element.
        line : str
            The XML inserted (an element or a comment).
        """
        ws = self.indent(node)
        if ws is None:
            self._edits.append((node.start, node.start, line))
        else:
            self._edits.append((node.start, node.start, line + self.newline + ws))

    def replace(self, start: int, end: int, text: str) -> None:
        """Replace a span of the source.

        Parameters
        ----------
        start, end : int
            The span ``source[start:end]`` (e.g. a comment's, from :attr:`Node.comments`).
        text : str
            Its replacement.
        """
        self._edits.append((start, end, text))

    def remove_line(self, start: int, end: int) -> None:
        """Remove a span of the source, and its whole line when nothing else is on it.

        Parameters
        ----------
        start, end : int
            The span ``source[start:end]``.
        """
        line = self.source.rfind("\n", 0, start) + 1
        stop = self.source.find("\n", end)
        stop = len(self.source) if stop < 0 else stop
        if self.source[line:start].strip() == "" and self.source[end:stop].strip() == "" and line > 0:
            self._edits.append((line - 1, end if stop == len(self.source) else stop, ""))
        else:
            self._edits.append((start, end, ""))

    def _head(self, node: Node, values: dict, empty_to_open: bool) -> str:
        head = self.source[node.start:node.head_end]
        found = {m.group(2): m for m in _ATTR.finditer(head)}
        out, pos = [], 0
        for m in sorted((found[k] for k in values if k in found), key=lambda m: m.start(4)):
            q = m.group(4)[0]
            out += [head[pos:m.start(4)], q + _escape(values[m.group(2)], q) + q]
            pos = m.end(4)
        out.append(head[pos:])
        head = "".join(out)
        new = [k for k in values if k not in found]
        if new:
            last = list(_ATTR.finditer(head))
            at = last[-1].end() if last else 1 + len(node.tag)
            head = head[:at] + "".join(f' {k}="{_escape(values[k], chr(34))}"' for k in new) + head[at:]
        if empty_to_open:
            head = head[:-2].rstrip() + ">"
        return head

    def text(self) -> str:
        """The edited document.

        Returns
        -------
        str
            The source with every edit applied; every other character as it was.
        """
        edits = list(self._edits)
        nl = self.newline
        heads = {k: v for k, v in self._attrs.items()}
        for key, (node, lines) in self._append.items():
            ci = self.child_indent(node)
            block = "".join(nl + ci + ln for ln in lines)
            if node.close is None:  # <tag .../>: open it, add the children and the end tag
                values = heads.pop(key, (node, {}))[1]
                own = self.indent(node)
                edits.append((node.start, node.head_end, self._head(node, values, True) + block + nl + (own or "")
                              + f"</{node.tag}>"))
                continue
            line = self.source.rfind("\n", 0, node.close)
            if self.source[line + 1:node.close].strip() == "" and line >= 0:
                at = line - 1 if nl == "\r\n" and self.source[line - 1] == "\r" else line
                edits.append((at, at, block))
            else:  # the end tag follows other text on its line
                edits.append((node.close, node.close, block + nl + (self.indent(node) or "")))
        for node, values in heads.values():
            edits.append((node.start, node.head_end, self._head(node, values, False)))
        out, pos = [], 0
        for start, end, new in sorted(edits, key=lambda e: (e[0], e[1] != e[0])):
            if start < pos:
                raise ModelError("overlapping edits of one XML document")  # pragma: no cover - a bug
            out += [self.source[pos:start], new]
            pos = end
        out.append(self.source[pos:])
        return "".join(out)
