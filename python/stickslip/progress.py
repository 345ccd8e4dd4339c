"""A progress bar: tqdm's when it is installed (its notebook widget in a
notebook with ipywidgets, its text bar in one without), otherwise one line
rewritten in place on a terminal and a line every tenth of the way
elsewhere (a log, a notebook without tqdm)."""

from __future__ import annotations

import sys
import warnings
from typing import Any, Optional, TextIO


class Progress:
    def __init__(self, total: Optional[int], desc: str, initial: int = 0,
                 enabled: bool = True, stream: Optional[TextIO] = None):
        self.total = total
        self.desc = desc
        self.n = initial
        self._stream = stream or sys.stderr
        self._bar: Any = None
        self._shown = -1
        self._enabled = enabled
        if not enabled:
            return
        try:
            with warnings.catch_warnings():
                # in a notebook without ipywidgets tqdm.auto warns, then
                # draws its text bar: what such a notebook can show
                warnings.simplefilter("ignore")
                from tqdm.auto import tqdm
        except ImportError:
            self._show()
            return
        self._bar = tqdm(total=total, desc=desc, initial=initial)

    def update(self, n: int = 1) -> None:
        self.n += n
        if self._bar is not None:
            self._bar.update(n)
        elif self._enabled:
            self._show()

    def set(self, n: int) -> None:
        """Move to ``n`` done (a job's progress, read from its status)."""
        if n > self.n:
            self.update(n - self.n)

    def _show(self, end: bool = False) -> None:
        tty = self._stream.isatty()
        if self.total:
            tenth = 10 * self.n // self.total
            if not tty and not end and tenth == self._shown:
                return
            self._shown = tenth
            text = "%s: %d/%d (%d%%)" % (self.desc, self.n, self.total,
                                         100 * self.n // self.total)
        else:
            text = "%s: %d" % (self.desc, self.n)
        self._stream.write(("\r" + text) if tty else text + "\n")
        self._stream.flush()

    def close(self) -> None:
        if self._bar is not None:
            self._bar.close()
        elif self._enabled and self._stream.isatty():
            self._stream.write("\n")
            self._stream.flush()
