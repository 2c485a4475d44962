"""The figure markers of the markdown docs: `<!-- fig ID -->VALUE`.

The marker is an HTML comment, so it does not show; VALUE is the text right after it, a
number (digits, a decimal point, an exponent, a sign, thin groups of three digits such as
`469 648`) or a word (a verdict such as `agrees`). Units and other text stay outside, so a
figure is exactly what its command prints. Pure text functions: no runs, no files.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Mapping
from dataclasses import dataclass

MARKER = re.compile(r'<!-- fig ([a-z][a-z0-9_.\-]*) -->')  # ids are lower case
VALUE = re.compile(
    r'[−+-]?(?:\d+(?: \d{3})*(?:\.\d+)?(?:e[−+-]?\d+)?|inf)'  # a number
    r'|[A-Za-z]+'  # or a word
)


@dataclass(frozen=True)
class Figure:
    """One marked figure of a document: its id, the printed value and where it is."""

    id: str
    value: str
    line: int
    start: int  # of the value in the text
    end: int


def find(text: str) -> list[Figure]:
    """Every marked figure of `text`, in order. A marker followed by no value has ''."""
    found = []
    for m in MARKER.finditer(text):
        value = VALUE.match(text, m.end())
        end = value.end() if value else m.end()
        line = text.count('\n', 0, m.start()) + 1
        found.append(Figure(m.group(1), text[m.end() : end], line, m.end(), end))
    return found


def differences(
    text: str, figures: Mapping[str, str], name: str, checked: Callable[[str], bool]
) -> list[str]:
    """One line per marked figure whose id is `checked` and whose printed value differs
    from `figures` (or that no command prints); `name` is the document's name."""
    out = []
    for fig in find(text):
        if not checked(fig.id):
            continue
        if fig.id not in figures:
            out.append(f'{name}:{fig.line}: {fig.id}: no command prints this figure')
        elif fig.value != figures[fig.id]:
            out.append(
                f'{name}:{fig.line}: {fig.id}: the docs say {fig.value!r}, '
                f'the command prints {figures[fig.id]!r}'
            )
    return out


def rewrite(text: str, figures: Mapping[str, str]) -> str:
    """`text` with every marked figure that `figures` has replaced by its value."""
    parts, pos = [], 0
    for fig in find(text):
        if fig.id in figures:
            parts += [text[pos : fig.start], figures[fig.id]]
            pos = fig.end
    return ''.join([*parts, text[pos:]])
