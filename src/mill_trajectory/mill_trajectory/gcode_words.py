"""One RS274/NGC line read into a block: words, parameter settings, an O-word. ROS-free.

As LinuxCNC reads a line: spaces and tabs outside comments do not count ("X 1 0" is X10),
case does not matter, comments are in parentheses or from ';' to the end of the line, and
a comment "(MSG, text)", "(DEBUG, text)" or "(PRINT, text)" is a message (DEBUG and PRINT
with #<name> and #123 replaced by their values). A '/' first is block delete. A word is a
letter and a
value: a number ("X-1.5"), a parameter ("#1", "#<depth>", "#<_global>", "#[#1+1]"), an
expression in brackets ("[#1 * 2 + 0.5]") or a function ("SIN[30]"); "#1 = value" sets a
parameter. Values are read when the line runs, with the parameters as they stand before
it: a parameter set on a line is new only from the next line on (LinuxCNC's rule).

Expressions: binary operators, loosest first, AND OR XOR; EQ NE GT GE LT LE; + -; * / MOD;
** (all left to right, comparisons and logic give 1 or 0); functions SIN COS TAN ASIN ACOS
ATAN[y]/[x] (degrees), ABS EXP FIX (floor) FUP (ceiling) ROUND LN SQRT, EXISTS[#<name>].

Every error names the file, the line and the column (1-based) where the trouble starts; a
file that cannot be read (read_file: a program or a tool table) is named alone.
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

# The word letters this reader knows (O is the O-word); anything else is unsupported.
LETTERS = frozenset('DFGHIJKLMNPQRSTXYZ')
_NUMBER = re.compile(r'(\d+\.?\d*|\.\d+)')
_RUN = '0123456789.'
KEYWORDS = (
    'endsub',
    'endwhile',
    'endrepeat',
    'endif',
    'elseif',
    'else',
    'sub',
    'call',
    'if',
    'while',
    'do',
    'repeat',
    'return',
    'break',
    'continue',
)
# The keywords whose O-word carries values: all of them for call, else one bracketed value.
VALUED = {'call', 'if', 'elseif', 'while', 'repeat', 'return', 'endsub'}
FUNCTIONS = (
    'EXISTS',
    'ROUND',
    'ASIN',
    'ACOS',
    'ATAN',
    'SQRT',
    'ABS',
    'COS',
    'EXP',
    'FIX',
    'FUP',
    'SIN',
    'TAN',
    'LN',
)
# Binary operators: text, precedence (higher binds tighter).
OPERATORS = (
    ('**', 4),
    ('*', 3),
    ('/', 3),
    ('MOD', 3),
    ('+', 2),
    ('-', 2),
    ('EQ', 1),
    ('NE', 1),
    ('GT', 1),
    ('GE', 1),
    ('LT', 1),
    ('LE', 1),
    ('AND', 0),
    ('OR', 0),
    ('XOR', 0),
)
EQUAL = 1e-6  # EQ and NE: numbers this close are equal (LinuxCNC's TOLERANCE_EQUAL)
MAX_NUMBERED = 5602  # parameters #1 .. #5602 exist (as in LinuxCNC)

Key = int | str  # a numbered parameter, or a named one (lower case, without < >)


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


def read_file(path: str | Path, encoding: str, what: str) -> str:
    """The text of a file; a missing or unreadable one is a GcodeError naming the file."""
    name = str(path)
    try:
        return Path(path).read_text(encoding=encoding)
    except FileNotFoundError:
        raise GcodeError(Where(name, 0, 0), f'no such {what} file') from None
    except (OSError, UnicodeDecodeError) as exc:
        raise GcodeError(Where(name, 0, 0), f'cannot read: {exc}') from None


@dataclass(frozen=True)
class Word:
    letter: str
    value: float
    text: str  # as written (spaces dropped), for messages
    where: Where


@dataclass(frozen=True)
class OWord:
    """An O-word: `name` 'o100' or 'o<name>', keyword ('' for a program number like O1001)."""

    name: str
    keyword: str
    values: tuple[float, ...]
    where: Where


@dataclass
class Block:
    """One line read: its words, its parameter settings, its O-word and messages."""

    words: list[Word] = field(default_factory=list)
    settings: list[tuple[Key, float, Where]] = field(default_factory=list)
    oword: OWord | None = None
    # (channel, text, where): channel MSG, DEBUG or PRINT; DEBUG and PRINT with their
    # parameters' values in the text, as they stand when the line runs
    messages: list[tuple[str, str, Where]] = field(default_factory=list)
    delete: bool = False  # '/' first: block delete


class Parameters:
    """How a line reads parameters: read(key, where) raises GcodeError if it is not set."""

    def read(self, key: Key, where: Where) -> float:
        raise NotImplementedError

    def exists(self, key: Key) -> bool:
        raise NotImplementedError


class _NoParameters(Parameters):
    """For reading a line's shape only (the O-word structure): every value is 0."""

    def read(self, key: Key, where: Where) -> float:
        return 0.0

    def exists(self, key: Key) -> bool:
        return False


SHAPE_ONLY = _NoParameters()


class _Line:
    """The line's characters outside comments, spaces dropped, each with its column."""

    def __init__(self, line: str, file: str, number: int) -> None:
        self.file, self.number = file, number
        self.chars: list[tuple[str, int]] = []
        self.comments: list[tuple[str, int]] = []
        i, n = 0, len(line)
        while i < n:
            c = line[i]
            if c in ' \t\r\n':
                i += 1
            elif c == ';':
                self.comments.append((line[i + 1 :], i + 1))
                break
            elif c == '(':
                close = line.find(')', i + 1)
                if close < 0:
                    raise GcodeError(self.at(i + 1), 'comment "(" is not closed on this line')
                self.comments.append((line[i + 1 : close], i + 1))
                i = close + 1
            else:
                self.chars.append((c, i + 1))
                i += 1
        self.pos = 0

    def at(self, column: int) -> Where:
        return Where(self.file, self.number, column)

    def here(self) -> Where:
        if self.pos < len(self.chars):
            return self.at(self.chars[self.pos][1])
        end = self.chars[-1][1] + 1 if self.chars else 1
        return self.at(end)

    def peek(self, k: int = 0) -> str:
        i = self.pos + k
        return self.chars[i][0] if i < len(self.chars) else ''

    def startswith(self, text: str) -> bool:
        return all(self.peek(k).upper() == c for k, c in enumerate(text))

    def done(self) -> bool:
        return self.pos >= len(self.chars)

    def take(self, count: int = 1) -> str:
        text = ''.join(c for c, _ in self.chars[self.pos : self.pos + count])
        self.pos += count
        return text


class _Reader:
    """Values and expressions of one line, read with the parameters as they stand."""

    def __init__(self, line: _Line, params: Parameters) -> None:
        self.line, self.params = line, params
        self.shape = params is SHAPE_ONLY  # values do not matter: no arithmetic errors

    def error(self, message: str, where: Where | None = None) -> GcodeError:
        return GcodeError(where or self.line.here(), message)

    def number(self) -> float:
        line = self.line
        start = line.pos
        where = line.here()
        while not line.done() and line.peek() in _RUN:
            line.pos += 1
        text = ''.join(c for c, _ in line.chars[start : line.pos])
        if not text:
            raise self.error('a number is missing', where)
        if not _NUMBER.fullmatch(text):
            raise self.error(f'malformed number {text!r}', where)
        return float(text)

    def value(self) -> float:
        """A number, a parameter, a bracketed expression, a function, or a signed value."""
        line = self.line
        c = line.peek()
        if c in '+-':
            line.take()
            v = self.value()
            return -v if c == '-' else v
        if c == '[':
            return self.bracketed()
        if c == '#':
            where = line.here()
            return self.params.read(self.parameter(), where)
        if c.isdigit() or c == '.':
            return self.number()
        if c.isalpha():
            return self.function()
        if not c:
            raise self.error('a value is missing at the end of the line')
        raise self.error(f'unexpected character {c!r} where a value should be')

    def bracketed(self) -> float:
        line = self.line
        if line.peek() != '[':
            raise self.error('"[" expected')
        open_at = line.here()
        line.take()
        v = self.expression()
        if line.peek() != ']':
            if line.done():
                raise self.error('"[" is not closed on this line', open_at)
            raise self.error(f'unexpected {line.peek()!r} in an expression')
        line.take()
        return v

    def parameter(self) -> Key:
        """After '#': a number, <name>, [expression] or another parameter; the key."""
        line = self.line
        where = line.here()
        line.take()  # '#'
        c = line.peek()
        if c == '<':
            line.take()
            name = []
            while not line.done() and line.peek() != '>':
                name.append(line.take())
            if line.done():
                raise self.error('parameter name "<" is not closed', where)
            line.take()
            if not name:
                raise self.error('empty parameter name', where)
            return ''.join(name).lower()
        v = self.value() if c in '#[' else self.number() if c.isdigit() else None
        if v is None:
            raise self.error('"#" needs a parameter number or <name>', where)
        if v != int(v) or not 1 <= v <= MAX_NUMBERED:
            raise self.error(
                f'parameter number {v:g} is not a whole number 1..{MAX_NUMBERED}', where
            )
        return int(v)

    def function(self) -> float:
        line = self.line
        where = line.here()
        name = next((f for f in FUNCTIONS if line.startswith(f)), None)
        if name is None:
            word = []
            while not line.done() and line.peek().isalpha():
                word.append(line.take())
            raise self.error(f'unknown function {"".join(word).upper()!r}', where)
        line.take(len(name))
        if line.peek() != '[':
            raise self.error(f'{name} needs its argument in [ ]')
        if name == 'EXISTS':
            line.take()
            if line.peek() != '#':
                raise self.error('EXISTS needs a parameter: EXISTS[#<name>]')
            key = self.parameter()
            if line.peek() != ']':
                raise self.error('"]" expected after the parameter')
            line.take()
            return 1.0 if self.params.exists(key) else 0.0
        arg_at = line.here()
        a = self.bracketed()
        if name == 'ATAN':
            if line.peek() != '/':
                raise self.error('ATAN takes two arguments: ATAN[y]/[x]')
            line.take()
            return math.degrees(math.atan2(a, self.bracketed()))
        return self.safely(lambda: _apply(name, a, arg_at))

    def safely(self, f: Callable[[], float]) -> float:
        try:
            return f()
        except GcodeError:
            if self.shape:
                return 0.0
            raise

    def expression(self, level: int = 0) -> float:
        """Operators of precedence >= level, left to right (precedence climbing)."""
        left = self.value() if level > 4 else self.expression(level + 1)
        while True:
            op = self.operator(level)
            if op is None:
                return left
            where = self.line.here()
            self.line.take(len(op))
            right = self.value() if level >= 4 else self.expression(level + 1)
            left = self.safely(lambda: _binary(op, left, right, where))  # noqa: B023

    def operator(self, level: int) -> str | None:
        for text, precedence in OPERATORS:
            if precedence == level and self.line.startswith(text):
                if text == '*' and self.line.startswith('**'):
                    continue
                return text
        return None


def _apply(name: str, a: float, where: Where) -> float:
    if name in ('ASIN', 'ACOS') and not -1.0 <= a <= 1.0:
        raise GcodeError(where, f'{name}[{a:g}]: the argument must be in -1..1')
    if name == 'SQRT' and a < 0.0:
        raise GcodeError(where, f'SQRT[{a:g}] of a negative number')
    if name == 'LN' and a <= 0.0:
        raise GcodeError(where, f'LN[{a:g}]: the argument must be > 0')
    functions: dict[str, Callable[[float], float]] = {
        'SIN': lambda x: math.sin(math.radians(x)),
        'COS': lambda x: math.cos(math.radians(x)),
        'TAN': lambda x: math.tan(math.radians(x)),
        'ASIN': lambda x: math.degrees(math.asin(x)),
        'ACOS': lambda x: math.degrees(math.acos(x)),
        'ABS': abs,
        'EXP': math.exp,
        'FIX': lambda x: float(math.floor(x)),
        'FUP': lambda x: float(math.ceil(x)),
        'ROUND': lambda x: float(math.floor(abs(x) + 0.5)) * (1.0 if x >= 0 else -1.0),
        'LN': math.log,
        'SQRT': math.sqrt,
    }
    try:
        return functions[name](a)
    except OverflowError:
        raise GcodeError(where, f'{name}[{a:g}] is too large') from None


def _binary(op: str, a: float, b: float, where: Where) -> float:
    if op in ('/', 'MOD') and b == 0.0:
        raise GcodeError(where, f'division by zero ({a:g} {op} 0)')
    if op == '**':
        try:
            result = math.pow(a, b)
        except (ValueError, OverflowError):
            raise GcodeError(where, f'{a:g} ** {b:g} has no real value') from None
        return result
    if op == 'MOD':
        m = math.fmod(a, b)
        return m + abs(b) if m < 0.0 else m
    table: dict[str, Callable[[float, float], float]] = {
        '*': lambda x, y: x * y,
        '/': lambda x, y: x / y,
        '+': lambda x, y: x + y,
        '-': lambda x, y: x - y,
        'EQ': lambda x, y: float(abs(x - y) < EQUAL),
        'NE': lambda x, y: float(abs(x - y) >= EQUAL),
        'GT': lambda x, y: float(x > y),
        'GE': lambda x, y: float(x >= y),
        'LT': lambda x, y: float(x < y),
        'LE': lambda x, y: float(x <= y),
        'AND': lambda x, y: float(x != 0.0 and y != 0.0),
        'OR': lambda x, y: float(x != 0.0 or y != 0.0),
        'XOR': lambda x, y: float((x != 0.0) != (y != 0.0)),
    }
    return table[op](a, b)


CHANNELS = ('MSG', 'DEBUG', 'PRINT')  # comments that reach the operator (LinuxCNC's)
_IN_TEXT = re.compile(r'#<([^>]*)>|#(\d+)')


def _with_values(text: str, params: Parameters, where: Where) -> str:
    """A DEBUG or PRINT text with each #<name> and #123 replaced by its value (as LinuxCNC,
    six decimals); a parameter that is not set is refused as anywhere else."""

    def value(m: re.Match[str]) -> str:
        key: Key = m.group(1).lower() if m.group(1) is not None else int(m.group(2))
        return f'{params.read(key, where):.6f}'

    return _IN_TEXT.sub(value, text)


def read_block(text: str, file: str, number: int, params: Parameters = SHAPE_ONLY) -> Block:
    """One line read into a block (see the module doc); GcodeError names the first bad column."""
    block = Block()
    if text.strip() == '%':
        return block
    line = _Line(text, file, number)
    for comment, column in line.comments:
        body = comment.strip()
        channel, _, said = body.partition(',')
        channel = channel.strip().upper()
        if channel in CHANNELS and _:
            where = line.at(column)
            said = said.strip()
            if channel != 'MSG' and params is not SHAPE_ONLY:
                said = _with_values(said, params, where)
            block.messages.append((channel, said, where))
    reader = _Reader(line, params)
    if line.peek() == '/':
        line.take()
        block.delete = True
    while not line.done():
        c = line.peek()
        where = line.here()
        if c == '#':
            key = reader.parameter()
            if line.peek() != '=':
                raise reader.error('a parameter alone: "#... = value" sets one', where)
            line.take()
            block.settings.append((key, reader.value(), where))
        elif c in 'oO':
            if (block.words and any(w.letter != 'N' for w in block.words)) or block.settings:
                raise reader.error('an O-word must come first on its line', where)
            block.oword = _oword(reader, where)
            if not line.done():
                raise reader.error(
                    f'{block.oword.name} {block.oword.keyword}'.strip()
                    + ' takes nothing else on its line'
                )
        elif c.isalpha():
            letter = c.upper()
            start = line.pos
            if letter not in LETTERS:
                run = line.pos + 1
                while run < len(line.chars) and line.chars[run][0] in _RUN + '+-':
                    run += 1
                shown = ''.join(ch for ch, _ in line.chars[start:run])
                raise reader.error(f'unsupported word {shown!r}', where)
            line.take()
            after = line.peek()
            if not after or (after.isalpha() and not any(line.startswith(f) for f in FUNCTIONS)):
                raise reader.error(f'word {letter} has no number', where)
            value = reader.value()
            shown = letter + ''.join(ch for ch, _ in line.chars[start + 1 : line.pos])
            block.words.append(Word(letter, value, shown, where))
        else:
            raise reader.error(f'unexpected character {c!r}', where)
    return block


def _oword(reader: _Reader, where: Where) -> OWord:
    line = reader.line
    line.take()  # 'o'
    if line.peek() == '<':
        line.take()
        name = []
        while not line.done() and line.peek() != '>':
            name.append(line.take())
        if line.done() or not name:
            raise reader.error('O-word name "<" is not closed', where)
        line.take()
        label = f'o<{"".join(name).lower()}>'
    elif line.peek().isdigit():
        n = reader.number()
        if n != int(n):
            raise reader.error(f'O-word number {n:g} is not a whole number', where)
        label = f'o{int(n)}'
    else:
        raise reader.error('an O-word needs a number or <name>', where)
    keyword = ''
    if line.peek().isalpha():
        k_at = line.here()
        keyword = next((k for k in KEYWORDS if line.startswith(k.upper())), '')
        if not keyword:
            word = ''.join(c for c, _ in line.chars[line.pos :])
            raise reader.error(f'unknown O-word keyword {word!r}', k_at)
        line.take(len(keyword))
    values: list[float] = []
    if keyword in VALUED:
        while line.peek() == '[' and (keyword == 'call' or not values):
            values.append(reader.bracketed())
        if keyword in ('if', 'elseif', 'while', 'repeat') and not values:
            raise reader.error(f'{label} {keyword} needs a condition in [ ]')
    elif keyword == '' and label.startswith('o<'):
        raise reader.error(f'{label} needs a keyword (sub, call, if, while, ...)', where)
    return OWord(label, keyword, tuple(values), where)


def words_of(line: str, file: str, number: int) -> list[Word]:
    """The words of one line without parameters (comments dropped)."""
    return read_block(line, file, number).words


Point = tuple[float, float, float]


@dataclass(frozen=True)
class Move:
    """One step of the program. kind: rapid, line, arc, dwell, stop (come to rest), spindle
    (come to rest; the spindle changes to `spindle`) or message (nothing moves)."""

    kind: str
    start: Point
    end: Point
    where: Where
    feed: float | None = None  # line, arc [m/s]
    center: Point | None = None  # arc, in the plane (the normal coordinate is start's)
    plane: tuple[int, int, int] = (0, 1, 2)
    sweep: float = 0.0  # arc: signed angle about the normal [rad], > 0 counter-clockwise
    duration: float = 0.0  # dwell [s]
    spindle: float = 0.0  # spindle speed during this move [rev/min], signed; 0 off
    coolant: str = ''  # '', 'mist', 'flood' or 'mist+flood'
    message: str = ''  # stop (why: a tool change, M0, M1), message (its text)
    channel: str = ''  # message: MSG, DEBUG or PRINT
    pause: bool = False  # stop: M0, or M1 with the optional stop on: wait for the operator
    tolerance: float | None = None  # path tolerance from G64 P [m]; None: the machine's
    exact_stop: bool = False  # G61/G61.1 and canned cycles: the move ends at rest
