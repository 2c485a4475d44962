"""An argparse parser whose errors are one line (`NAME: error: ...`, exit 2). ROS-free."""

from __future__ import annotations

import argparse
import math
import sys
from typing import Any, NoReturn


class OneLineParser(argparse.ArgumentParser):
    """name: what the error line starts with (default: prog)."""

    def __init__(self, *args: Any, name: str | None = None, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.name = name

    def error(self, message: str) -> NoReturn:  # one line, no usage block
        print(f'{self.name or self.prog}: error: {message}', file=sys.stderr)
        raise SystemExit(2)


def _finite(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f'{text!r} is not a number') from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f'{text!r} is not finite')
    return value


def positive(text: str) -> float:
    """An argparse type: a finite number > 0."""
    value = _finite(text)
    if not value > 0:
        raise argparse.ArgumentTypeError(f'{text!r} must be > 0')
    return value


def non_negative(text: str) -> float:
    """An argparse type: a finite number >= 0."""
    value = _finite(text)
    if not value >= 0:
        raise argparse.ArgumentTypeError(f'{text!r} must be >= 0')
    return value
