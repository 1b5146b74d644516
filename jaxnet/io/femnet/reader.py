"""FEMNET's way of reading a ``.don`` file, made strict: skip to the next colon, check the label before it, read
numbers as C's scanf does, and name the file and the line of whatever is wrong.

FEMNET (phobos ``chargement_don.c``) reads a case with ``fscanf``: it skips everything up to the next colon,
whatever the text before it, and reads the values after it. :class:`Reader` does the same, but checks each
label against the field the grammar (:mod:`.grammar`) expects there, and raises
:class:`~jaxnet.scene.SceneError` as ``file:LINE: message`` for a misspelt label, a missing, non-numeric or
non-finite value, a value out of range, a value too many or too few on a line.
"""

from __future__ import annotations

import bisect
import dataclasses
import math
import re

from jaxnet.scene import SceneError

#: positions (m) beyond this distance from the origin are surely mistakes (check "position")
MAX_COORDINATE = 1e5
#: panel coordinates U, V (meshes) beyond this are surely mistakes (check "meshes")
MAX_MESHES = 1e7

#: a decimal number as C's scanf reads it
_NUMBER = re.compile(r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?")


@dataclasses.dataclass(frozen=True)
class Value:
    """A number read from a file, with the line it is on (for messages)."""

    value: float
    line: int


class Reader:
    """FEMNET's way of reading: skip to the next colon, check the label before it, read numbers.

    ``text`` is the whole file, ``path`` how messages name it; ``pos`` the offset reached (the parsers of
    :mod:`.grammar` move it past what they read themselves), ``starts`` the offset of each line's start,
    ``last`` the (what, line) of the last value or label read, named when a value is missing or stray."""

    def __init__(self, text, path):
        self.text = text
        self.path = path
        self.pos = 0
        self.starts = [0] + [m.end() for m in re.finditer("\n", text)]
        self.last = None
        self.warnings = []   # what was read as FEMNET would, with a difference worth saying (file:LINE: ...)
        self.stray_ignored = False   # the last field read is one after which FEMNET's skipping drops stray values

    def line(self, pos=None):
        """The 1-based line of the offset ``pos`` (default: the offset reached)."""
        return bisect.bisect_right(self.starts, self.pos if pos is None else pos)

    def line_text(self, line):
        """The text of the 1-based ``line``, with its newline."""
        return self.text[self.starts[line - 1]:self.starts[line] if line < len(self.starts) else len(self.text)]

    def error(self, message, line=None):
        """A SceneError ``file:LINE: message`` (default LINE: the line reached)."""
        return SceneError(f"{self.path}:{line if line is not None else self.line()}: {message}")

    def label(self, pattern, what):
        """Skip to the next colon; the label before it (its last line), normalised (lower case, runs of blanks as
        one space), must match ``pattern`` (a compiled regular expression), that of the field messages name
        ``what``. Returns the normalised label."""
        colon = self.text.find(":", self.pos)
        if colon < 0:
            raise self.error(f"the file ends before the field '{what}' (truncated file?)", self.line(len(self.text)))
        before = self.text[self.pos:colon].split("\n")
        label = before[-1]
        # FEMNET skips whatever lies between a value and the next label; a number there is a value too many (a
        # line with more fields than its entry has), which FEMNET would drop silently
        for k, text in enumerate(before[:-1]):
            stray = [t for t in text.split() if _NUMBER.fullmatch(t) or t.lower().lstrip("+-") in ("nan", "inf")]
            if stray and self.stray_ignored:
                self.warnings.append(f"{self.path}:{self.line(self.pos) + k}: value {stray[0]!r} after {self.last[0]} "
                                     "ignored, as FEMNET's reader skips it (that field is unused)")
            elif stray:
                after = f" after {self.last[0]}" if self.last else ""
                raise self.error(f"unexpected value {stray[0]!r}{after}, before the field '{what}': a line with more "
                                 "values than its entry has?", self.line(self.pos) + k)
        self.pos = colon + 1
        self.stray_ignored = False
        self.last = (f"the label {label.strip()!r}", self.line(colon))
        norm = " ".join(label.lower().split())
        if norm in ("dynamic", "dynamique"):  # "Dynamic: Time step (s):" has two colons
            colon = self.text.find(":", self.pos)
            if colon >= 0 and "\n" not in self.text[self.pos:colon]:
                norm = "dynamic: " + " ".join(self.text[self.pos:colon].lower().split())
                self.pos = colon + 1
        if not pattern.fullmatch(norm):
            raise self.error(f"expected the field '{what}', found the label {label.strip()!r}", self.line(colon))
        return norm

    def token(self, what):
        """The next word (anything between blanks) and its line."""
        m = re.compile(r"\S+").search(self.text, self.pos)
        if m is None:
            raise self.error(f"the file ends before the value of '{what}' (truncated file?)", self.line(len(self.text)))
        self.pos = m.end()
        return m.group(0), self.line(m.start())

    def missing(self):
        """Whether the value expected next is missing: the line of the last label ends without one, and the next
        word, on a later line, is not a number."""
        m = re.compile(r"\S+").search(self.text, self.pos)
        return (m is not None and self.last is not None and self.line(m.start()) > self.last[1]
                and not _NUMBER.fullmatch(m.group(0)))

    def number(self, what, check=None):
        """The next word as a finite number (a :class:`Value`), which passes ``check``: None, ">=0", ">0",
        "position" (m, within :data:`MAX_COORDINATE` of the origin) or "meshes" (at most :data:`MAX_MESHES`)."""
        tok, line = self.token(what)
        if tok.lower().lstrip("+-") in ("nan", "inf", "infinity"):
            raise self.error(f"'{what}': {tok!r} is not a finite number", line)
        # a decimal number as C's scanf reads it (Python's float() would also take "1_000" or "0x1p3")
        if not _NUMBER.fullmatch(tok):
            if self.last is not None and line > self.last[1]:
                # the value is missing from the line above (too few values there), not wrong here
                raise self.error(f"'{what}': missing: the line ends after {self.last[0]} (too few values on the "
                                 f"line?); the next line starts with {tok!r}", self.last[1])
            raise self.error(f"'{what}': expected a number, found {tok!r}", line)
        self.last = (f"'{what}'", line)
        v = float(tok)
        if not math.isfinite(v):
            raise self.error(f"'{what}': {tok!r} is not a finite number", line)
        if check == "position" and not abs(v) <= MAX_COORDINATE:
            raise self.error(f"'{what}': {v!r} m is out of range (a net within {MAX_COORDINATE:g} m of the origin)", line)
        if check == "meshes" and not abs(v) <= MAX_MESHES:
            raise self.error(f"'{what}': {v!r} meshes is out of range (at most {MAX_MESHES:g})", line)
        if check == ">=0" and v < 0:
            raise self.error(f"'{what}' must be >= 0, got {v!r}", line)
        if check == ">0" and not v > 0:
            raise self.error(f"'{what}' must be > 0, got {v!r}", line)
        return Value(v, line)

    def integer(self, what, minimum=None):
        """The next word as an integer (a :class:`Value` of an int), at least ``minimum`` when given."""
        v = self.number(what)
        if v.value != int(v.value) or (minimum is not None and v.value < minimum):
            raise self.error(f"'{what}' must be an integer{'' if minimum is None else f' >= {minimum}'}, got {v.value!r}", v.line)
        return Value(int(v.value), v.line)

    def one_line(self, values, line, what, fields, previous=None):
        """The values of a row (a corner, a cable end, X Y Z) must all be on its line ``line``, and a row must not
        start on the line of the ``previous`` row (its (what, line)): a row with a value missing or one too many
        would otherwise shift the next rows, and the error show up lines later, or never. ``fields`` names the
        row's values, separated by blanks."""
        if previous is not None and previous[1] == line:
            what, line = previous  # the previous row had a value too many: this one began on its line
        elif all(v.line == line for v in values):
            return
        found = len(self.line_text(line).split(":")[-1].split())
        raise self.error(f"{what}: expected {len(fields.split())} values on its line ({fields}), found {found}", line)
