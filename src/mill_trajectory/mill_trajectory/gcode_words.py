"""The words of an RS274/NGC line, with the column each starts at. ROS-free.

A line is words (a letter and a number, "G1", "X-1.5", spaces allowed between them),
comments in parentheses and a comment from ';' to the end of the line; case does not
matter. A line holding only '%' (the program's start or end mark) has no words. Every
error names the file, the line and the column (1-based) where the trouble starts.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

# The letters this reader knows; anything else is an unsupported word.
LETTERS = frozenset('GMNXYZIJKRFSP')
_NUMBER = re.compile(r'[+-]?(\d+\.?\d*|\.\d+)')
_NUMBER_RUN = re.compile(r'[-+0-9.eE]*')


@dataclass(frozen=True)
class Where:
    """A place in a G-code file: 1-based line and column."""

    file: str
    line: int
    column: int

    def __str__(self) -> str:
        if self.line <= 0:  # the file as a whole (it cannot be read)
            return self.file
        return f'{self.file}:{self.line}:{self.column}'


class GcodeError(ValueError):
    """A program that cannot run; str() is one line 'file:line:column: what is wrong'."""

    def __init__(self, where: Where, message: str) -> None:
        super().__init__(f'{where}: {message}')
        self.where = where


@dataclass(frozen=True)
class Word:
    letter: str
    value: float
    text: str  # as written, for messages
    where: Where


def words_of(line: str, file: str, number: int) -> list[Word]:
    """The words of one line (comments dropped); GcodeError names the first bad column."""
    words: list[Word] = []
    i, n = 0, len(line)
    if line.strip() == '%':
        return words
    while i < n:
        c = line[i]
        where = Where(file, number, i + 1)
        if c in ' \t\r\n':
            i += 1
        elif c == ';':
            break
        elif c == '(':
            close = line.find(')', i + 1)
            if close < 0:
                raise GcodeError(where, 'comment "(" is not closed on this line')
            i = close + 1
        elif c.isalpha():
            letter = c.upper()
            if letter not in LETTERS:
                word = re.match(r'[A-Za-z][^A-Za-z;( \t]*', line[i:])
                shown = word.group(0) if word else c
                raise GcodeError(where, f'unsupported word {shown!r}')
            j = i + 1
            while j < n and line[j] in ' \t':
                j += 1
            run = _NUMBER_RUN.match(line, j)
            text = run.group(0) if run else ''
            if not text:
                raise GcodeError(where, f'word {letter} has no number')
            if not _NUMBER.fullmatch(text):
                raise GcodeError(Where(file, number, j + 1), f'malformed number {text!r}')
            words.append(Word(letter, float(text), f'{letter}{text}', where))
            i = j + len(text)
        else:
            raise GcodeError(where, f'unexpected character {c!r}')
    return words
