"""A G-code program's control flow: its lines, the O-word structure (subroutines, if/elseif/
else, while, do-while, repeat, break, continue, return), its parameters and the run, line by
line (mill_trajectory.gcode_line). ROS-free.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from typing import Any

from mill_trajectory.gcode_line import run_line
from mill_trajectory.gcode_state import State
from mill_trajectory.gcode_tools import comp_off
from mill_trajectory.gcode_words import (
    GcodeError,
    Key,
    Move,
    OWord,
    Parameters,
    Where,
    read_block,
)

ITERATIONS = 100_000  # loop passes (while, do, repeat) in one run of a program


CALL_DEPTH = 10  # subroutine calls nested at most (as LinuxCNC)


_COMMENTS = r'(?:\s*\([^)]*\))*\s*'


_OWORD_LINE = re.compile(rf'^{_COMMENTS}/?{_COMMENTS}(?:[nN][\s\d.]*)?{_COMMENTS}[oO]')


@dataclass
class _Frame:
    """A running subroutine (or the main program): its local parameters and loops."""

    sub: str
    back: int  # line index to go on at when it returns
    numbered: dict[int, float] = field(default_factory=dict)  # #1 .. #30
    named: dict[str, float] = field(default_factory=dict)  # names without a leading '_'
    repeats: dict[int, int] = field(default_factory=dict)  # repeat line -> passes left


class Program(Parameters):
    """The program's lines, their O-word structure, its parameters, and the run."""

    def __init__(self, text: str, file: str, state: State) -> None:
        self.lines = text.splitlines()
        self.file = file
        self.state = state
        self.end = len(self.lines)
        first = next((i for i, t in enumerate(self.lines) if t.strip()), None)
        if first is not None and self.lines[first].strip() == '%':
            # A program opened by '%' ends at the next '%'.
            close = next(
                (i for i in range(first + 1, self.end) if self.lines[i].strip() == '%'), None
            )
            self.end = self.end if close is None else close
        self.globals: dict[Key, float] = {}
        self.frames = [_Frame('', self.end)]
        self.subs: dict[str, int] = {}
        self.passes = 0
        self._structure()

    # -- parameters
    def _home(self, key: Key) -> tuple[dict[Any, float], Key]:
        frame = self.frames[-1]
        if isinstance(key, int):
            return (frame.numbered, key) if key <= 30 else (self.globals, key)
        return (self.globals, key) if key.startswith('_') else (frame.named, key)

    def read(self, key: Key, where: Where) -> float:
        table, k = self._home(key)
        if k in table:
            return float(table[k])
        if isinstance(key, int):
            s = self.state
            if 5420 <= key <= 5422:  # the current position, program coordinates
                i = key - 5420
                return (s.here[i] - s.offset(i)) * s.unit
            if key == 5220:
                return float(s.system + 1)
            if key == 5400:
                return float(s.loaded)
            return 0.0  # numbered parameters start at 0 (LinuxCNC)
        raise GcodeError(where, f'parameter #<{key}> is used before it is set')

    def exists(self, key: Key) -> bool:
        table, k = self._home(key)
        return isinstance(key, int) or k in table

    # -- the O-word structure
    def _structure(self) -> None:
        """Match every O-word block; an unclosed or mismatched one is refused."""
        self.owords: dict[int, OWord] = {}
        self.link: dict[int, int] = {}  # opener <-> closer, branch -> next branch
        self.endif: dict[int, int] = {}  # if / elseif / else -> its endif
        self.loop: dict[int, int] = {}  # break / continue -> the loop's opener
        self.sub_of: dict[int, int] = {}  # return -> its sub
        stack: list[tuple[str, str, int]] = []  # name, keyword, line index
        branch: dict[int, int] = {}  # if -> its last branch so far
        for i in range(self.end):
            if not _OWORD_LINE.match(self.lines[i]):
                continue
            o = read_block(self.lines[i], self.file, i + 1).oword
            if o is None:
                continue
            self.owords[i] = o
            k, top = o.keyword, stack[-1] if stack else None
            named = f'{o.name} {k}'
            if k in ('sub', 'if', 'do', 'repeat') or (
                k == 'while' and not (top and top[:2] == (o.name, 'do'))
            ):
                if k == 'sub' and any(s[1] == 'sub' for s in stack):
                    raise GcodeError(o.where, f'{named}: a sub cannot be defined inside a sub')
                stack.append((o.name, k, i))
                if k == 'if':
                    branch[i] = i
            elif k == 'while':  # closes a do
                assert top is not None
                self.link[top[2]], self.link[i] = i, top[2]
                stack.pop()
            elif k in ('elseif', 'else', 'endif', 'endwhile', 'endrepeat', 'endsub'):
                want = {'elseif': 'if', 'else': 'if', 'endif': 'if', 'endwhile': 'while'}
                opener = want.get(k, k[3:])
                if not top or top[:2] != (o.name, opener):
                    raise GcodeError(o.where, f'{named} without an open {o.name} {opener}')
                start = top[2]
                if opener == 'if':
                    last = branch[start]
                    if k != 'endif' and last != start and self.owords[last].keyword == 'else':
                        raise GcodeError(o.where, f'{named} after {o.name} else')
                    self.link[last] = i
                    branch[start] = i
                    self.endif[start] = i
                    if k == 'endif':
                        stack.pop()
                        node = start
                        while node != i:
                            self.endif[node] = i
                            node = self.link[node]
                else:
                    self.link[start], self.link[i] = i, start
                    stack.pop()
            elif k in ('break', 'continue', 'return'):
                kinds = ('sub',) if k == 'return' else ('while', 'do', 'repeat')
                found = None
                for s in reversed(stack):
                    if s[0] == o.name and s[1] in kinds:
                        found = s
                        break
                    if s[1] == 'sub':
                        break
                if found is None:
                    what = 'sub' if k == 'return' else 'loop'
                    raise GcodeError(o.where, f'{named} outside its {o.name} {what}')
                (self.sub_of if k == 'return' else self.loop)[i] = found[2]
        if stack:
            name, k, i = stack[-1]
            closer = {'if': 'endif', 'do': 'while', 'sub': 'endsub'}.get(k, f'end{k}')
            raise GcodeError(self.owords[i].where, f'{name} {k} is not closed (no {name} {closer})')

    # -- the run
    def run(self) -> list[Move]:
        pc = 0
        while pc < self.end:
            o = self.owords.get(pc)
            if o is not None:
                pc = self._oword(pc, o)
                continue
            block = read_block(self.lines[pc], self.file, pc + 1, self)
            assert block.oword is None, 'an O-word line the structure pass did not see'
            if block.delete and self.state.setup.block_delete:
                pc += 1
                continue
            for key, value, _where in block.settings:
                table, k = self._home(key)
                table[k] = value
            if run_line(self.state, block, Where(self.file, pc + 1, 1)):
                break
            pc += 1
        comp_off(self.state)
        return self.state.moves

    def _value(self, pc: int) -> tuple[OWord, tuple[float, ...]]:
        """The O-word at line pc with its values read now."""
        block = read_block(self.lines[pc], self.file, pc + 1, self)
        assert block.oword is not None
        return block.oword, block.oword.values

    def _pass(self, o: OWord) -> None:
        self.passes += 1
        if self.passes > ITERATIONS:
            raise GcodeError(
                o.where, f'{o.name} {o.keyword}: more than {ITERATIONS} loop passes (runaway loop?)'
            )

    def _oword(self, pc: int, shape: OWord) -> int:
        """Run the O-word at line pc; the next line to run."""
        k = shape.keyword
        frame = self.frames[-1]
        if k == '':  # a program number (O1001): nothing to do
            return pc + 1
        if k == 'sub':
            self.subs[shape.name] = pc
            return self.link[pc] + 1
        if k in ('endsub', 'return'):
            o, values = self._value(pc)
            if len(self.frames) == 1:
                raise GcodeError(o.where, f'{o.name} {k} outside a call')
            if values:
                self.globals['_value'] = values[0]
                self.globals['_value_returned'] = 1.0
            self.frames.pop()
            return frame.back
        if k == 'call':
            o, values = self._value(pc)
            start = self.subs.get(o.name)
            if start is None:
                raise GcodeError(o.where, f'{o.name} call: no such subroutine defined before it')
            if len(self.frames) >= CALL_DEPTH + 1:
                raise GcodeError(o.where, f'{o.name} call: more than {CALL_DEPTH} nested calls')
            if len(values) > 30:
                raise GcodeError(o.where, f'{o.name} call: at most 30 arguments')
            numbered = dict(frame.numbered)
            numbered.update({n + 1: v for n, v in enumerate(values)})
            self.frames.append(_Frame(o.name, pc + 1, numbered))
            self.globals['_value_returned'] = 0.0
            return start + 1
        if k == 'if':
            node = pc
            while True:
                kind = self.owords[node].keyword
                if kind in ('if', 'elseif'):
                    _o, values = self._value(node)
                    if values[0] != 0.0:
                        return node + 1
                    node = self.link[node]
                else:  # else: run it; endif: past it
                    return node + 1
        if k in ('elseif', 'else'):  # the branch above ran: skip to past the endif
            return self.endif[pc] + 1
        if k == 'endif':
            return pc + 1
        if k == 'while' and self.link[pc] < pc:  # the end of a do .. while
            o, values = self._value(pc)
            if values[0] != 0.0:
                self._pass(o)
                return self.link[pc] + 1
            return pc + 1
        if k == 'while':
            o, values = self._value(pc)
            return pc + 1 if values[0] != 0.0 else self.link[pc] + 1
        if k == 'endwhile':
            self._pass(shape)
            return self.link[pc]
        if k == 'do':
            return pc + 1
        if k == 'repeat':
            o, values = self._value(pc)
            count = values[0]
            if count != int(count) or count < 0:
                raise GcodeError(o.where, f'{o.name} repeat [{count:g}]: not a whole number >= 0')
            if count == 0:
                return self.link[pc] + 1
            frame.repeats[pc] = int(count)
            return pc + 1
        if k == 'endrepeat':
            start = self.link[pc]
            left = frame.repeats.get(start, 1) - 1
            if left > 0:
                self._pass(shape)
                frame.repeats[start] = left
                return start + 1
            frame.repeats.pop(start, None)
            return pc + 1
        if k in ('break', 'continue'):
            start = self.loop[pc]
            kind, end = self.owords[start].keyword, self.link[start]
            if k == 'break':
                frame.repeats.pop(start, None)
                return end + 1
            if kind == 'while':
                self._pass(shape)
                return start
            return end  # do: its while tests; repeat: its endrepeat counts
        raise GcodeError(shape.where, f'{shape.name} {k}: not supported')  # pragma: no cover
