"""An argparse parser whose errors are one line (`NAME: error: ...`, exit 2). ROS-free."""

from __future__ import annotations

import argparse
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
