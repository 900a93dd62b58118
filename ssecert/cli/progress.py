"""What the ``ssecert`` command shows on stderr while it works: the stages and the sets.

The analyses announce their stages (``ssecert.budget.stage`` and the steps of
``Laps``: observability, sparse observability, the observer checks, the LMIs of
each region of attraction, ...) and the enumerations their sets done; the
``_Display`` here is told of both and shows

- on a terminal, a live display drawn by rich: every stage that has run for a
  second or more, nested as the stages are, with its elapsed time, and the
  sets done with the time left (cleared when the command ends);
- off a terminal under ``--verbose``, one line when a stage passes a second
  (``ssecert: observer checks > region of attraction: running for 1.0 s``),
  beside the lines ``--verbose`` prints as each step ends;
- nothing under ``--quiet``, and nothing on a terminal under ``--json -`` unless
  ``--verbose`` asks.

It writes to stderr only: the JSON, HTML and .mat outputs never hold any of it.
"""

from __future__ import annotations

import sys
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any, TextIO

__all__: list[str] = []

AFTER = 1.0  # seconds a stage runs before it is shown
TICK = 0.2  # seconds between the checks of the line mode


def _label(name: str) -> str:
    return name.replace("_", " ")


class _Display:
    """Told of the stages (``begin``/``end``, a ``StageListener``), the sets done
    (``display(label, done, total)``, the enumerations' ``progress``) and the command's own
    stages (``say``); shows them as the module doc says.  ``live``: a terminal display;
    ``lines``: the line mode; neither: silent.  ``clock`` is ``time.monotonic`` but in tests."""

    def __init__(
        self,
        stream: TextIO,
        *,
        live: bool = False,
        lines: bool = False,
        verbose: bool = False,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self.stream = stream
        self.live = live
        self.lines = lines and not live
        self.verbose = verbose
        self.clock = clock
        self.stack: list[list[Any]] = []  # [name, start, task id or None, announced]
        self.sets: tuple[str, int, Any] | None = None  # (label, total, task id)
        self.said = False  # a stage of ``say`` is open (the bottom of the stack)
        self.lock = threading.Lock()
        self.progress: Any = None
        self._stop = threading.Event()
        self._ticker: threading.Thread | None = None

    # --- the listener -------------------------------------------------------------------
    def begin(self, name: str, *, announced: bool = False) -> None:
        with self.lock:
            task = None
            if self.progress is not None:
                indent = "  " * len(self.stack)
                task = self.progress.add_task(f"{indent}{_label(name)}", total=None)
            self.stack.append([name, self.clock(), task, announced])

    def end(self, name: str, seconds: float) -> None:
        with self.lock:
            # an analysis that ended early leaves its inner stages open: close them too
            if not any(item[0] == name for item in self.stack):
                return
            while self.stack:
                item = self.stack.pop()
                self._remove(item[2])
                if item[0] == name:
                    break
            if self.sets is not None and not self.stack:
                self._remove(self.sets[2])
                self.sets = None

    def say(self, message: str) -> None:
        """The command's own stage ``message`` begins (and the one it said before ends)."""
        if self.said and self.stack:
            self.end(self.stack[0][0], 0.0)
        self.said = True
        self.begin(message, announced=self.verbose)
        if self.verbose:  # sys.stderr: above the live display while it is drawn
            sys.stderr.write(f"ssecert: {message}...\n")
            sys.stderr.flush()

    def __call__(self, label: str, done: int, total: int) -> None:
        """``done`` of ``total`` sets of ``label`` (a check's id) are checked."""
        if self.progress is None:
            return
        with self.lock:
            if self.sets is None or self.sets[:2] != (label, total) or done == 0:
                if self.sets is not None:
                    self._remove(self.sets[2])
                indent = "  " * len(self.stack)
                description = f"{indent}sets checked"
                task = self.progress.add_task(description, total=max(total, 1))
                self.sets = (label, total, task)
            self.progress.update(self.sets[2], completed=done)

    def _remove(self, task: Any) -> None:
        if task is not None and self.progress is not None:
            self.progress.remove_task(task)

    # --- the line mode ------------------------------------------------------------------
    def path(self, depth: int) -> str:
        """The open stages down to ``depth``, outermost first."""
        return " > ".join(_label(item[0]) for item in self.stack[: depth + 1])

    def tick(self) -> None:
        """Line mode: a line for each open stage once it has run for ``AFTER`` seconds."""
        with self.lock:
            now = self.clock()
            for depth, item in enumerate(self.stack):
                if not item[3] and now - item[1] >= AFTER:
                    item[3] = True
                    seconds = now - item[1]
                    self.stream.write(f"ssecert: {self.path(depth)}: running for {seconds:.1f} s\n")
                    self.stream.flush()

    def _tick_until_stopped(self) -> None:
        while not self._stop.wait(TICK):
            self.tick()

    # --- start and stop -----------------------------------------------------------------
    def start(self) -> None:
        if self.live:
            self.progress = _live_progress(self.stream, self.clock)
            self.progress.start()
        elif self.lines:
            self._ticker = threading.Thread(target=self._tick_until_stopped, daemon=True)
            self._ticker.start()

    def close(self) -> None:
        """Stop drawing and clear the display (idempotent)."""
        self._stop.set()
        if self._ticker is not None:
            self._ticker.join()
            self._ticker = None
        if self.progress is not None:
            self.progress.stop()
            self.progress = None

    @contextmanager
    def showing(self) -> Iterator[_Display]:
        """Within the block, the analyses' stages come here (``watching_stages``)."""
        from ..budget import watching_stages

        self.start()
        try:
            if self.live or self.lines:
                with watching_stages(self):
                    yield self
            else:
                yield self
        finally:
            self.close()


def stage_display(
    *, quiet: bool = False, verbose: bool = False, json_to_stdout: bool = False
) -> _Display:
    """The display of a command on stderr: live on a terminal (unless ``quiet``, or the JSON
    goes to stdout and ``verbose`` does not ask), lines off a terminal under ``verbose``."""
    terminal = sys.stderr.isatty()
    return _Display(
        sys.stderr,
        live=terminal and not quiet and (verbose or not json_to_stdout),
        lines=not terminal and verbose,
        verbose=verbose,
    )


def _live_progress(stream: TextIO, clock: Callable[[], float]) -> Any:
    """A rich ``Progress`` on ``stream`` that shows a task once it has run for ``AFTER``
    seconds: a spinner, the stage (or the sets done, with a bar and the time left) and the
    time elapsed; cleared when it stops."""
    from rich.console import Console
    from rich.progress import (
        BarColumn,
        Progress,
        ProgressColumn,
        SpinnerColumn,
        TextColumn,
        TimeElapsedColumn,
    )
    from rich.table import Column
    from rich.text import Text

    class Counts(ProgressColumn):
        """The sets done of the total and the time left (blank for a stage)."""

        def render(self, task: Any) -> Any:
            if task.total is None:
                return Text("")
            text = f"{int(task.completed):,}/{int(task.total):,}"
            if task.time_remaining is not None and task.completed < task.total:
                text += f" ({task.time_remaining:.0f} s left)"
            return Text(text)

    class Bar(BarColumn):
        """A bar for the sets (blank for a stage, where rich would pulse one)."""

        def render(self, task: Any) -> Any:
            return super().render(task) if task.total is not None else Text("")

    class Stages(Progress):
        def get_renderables(self) -> Any:
            now = clock()  # (rich may draw before its own get_time is set)
            shown = [t for t in self.tasks if now - (t.start_time or now) >= AFTER]
            if shown:
                yield self.make_tasks_table(shown)

    console = Console(file=stream, stderr=True, highlight=False)
    return Stages(
        SpinnerColumn(),
        TextColumn("{task.description}"),
        TimeElapsedColumn(),
        Bar(bar_width=20),
        Counts(table_column=Column(no_wrap=True, overflow="ellipsis")),
        console=console,
        transient=True,
        redirect_stdout=False,  # stdout carries results; --verbose's lines on stderr go above
        get_time=clock,
        refresh_per_second=4,
    )
