"""The progress display of long tasks (a run, reading a bag). ROS-free.

On a terminal one live bar with the ETA (tqdm); otherwise a plain line every 5 s, so that a
log or a pipe gets a few lines and no control characters.
"""

from __future__ import annotations

import sys
import time
from typing import Any


class Progress:
    """One live bar with the ETA on a terminal (tqdm), a plain line every 5 s otherwise.

    total None: not known (a count and the rate, no share); label: what is progressing;
    decimals: of the values shown (0 for counts); delay: no display during the first
    seconds (a short task shows none).
    """

    def __init__(
        self,
        total: float | None,
        unit: str = 's',
        quiet: bool = False,
        label: str = '',
        decimals: int = 2,
        delay: float = 0.0,
    ) -> None:
        self.total = total
        self.quiet = quiet
        self.label = label
        self.decimals = decimals
        self.tty = sys.stderr.isatty()
        self._bar: Any = None
        self._value = 0.0
        self._started = time.monotonic()
        self._next = self._started + delay
        self._unit = unit

    def note(self, text: str) -> None:
        """A message between progress updates."""
        if self.quiet:
            return
        if self._bar is not None:
            self._bar.write(text, file=sys.stderr)
        else:
            print(text, file=sys.stderr, flush=True)

    def update(self, value: float, extra: str = '') -> None:
        if self.quiet or not value > self._value:
            return
        if self.tty:
            if self._bar is None and time.monotonic() < self._next:
                return
            if self._bar is None:
                from tqdm import tqdm

                d = self.decimals
                known = self.total is not None
                self._bar = tqdm(
                    total=round(self.total, 3) if self.total is not None else None,
                    desc=self.label or None,
                    unit=self._unit,
                    file=sys.stderr,
                    dynamic_ncols=True,
                    bar_format=(
                        f'{{l_bar}}{{bar}}| {{n:.{d}f}}/{{total:.{d}f}} {{unit}} '
                        '[{elapsed}<{remaining}{postfix}]'
                        if known
                        else f'{{desc}}: {{n:.{d}f}} {{unit}} '
                        '[{elapsed}, {rate_fmt}{postfix}]'
                    ),
                )
            self._bar.update(round(value - self._value, 3))
            if extra:
                self._bar.set_postfix_str(extra, refresh=False)
            self._value = value
            return
        self._value = value
        now = time.monotonic()
        if now >= self._next:
            self._next = now + 5.0
            d = self.decimals
            if self.total is None:
                line = f'{value:.{d}f} {self._unit}'
            else:
                share = 100.0 * value / self.total if self.total > 0 else 100.0
                line = f'{value:.{d}f} / {self.total:.{d}f} {self._unit} ({share:.0f} %)'
            line = f'{self.label}: {line}' if self.label else line
            print(line + (f', {extra}' if extra else ''), file=sys.stderr, flush=True)

    def close(self) -> None:
        if self._bar is not None:
            self._bar.close()
            self._bar = None
