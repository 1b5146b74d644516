"""The progress of a run in time: the simulated time over the end time, with the wall-clock step rate and the
mean number of Newton iterations per step.

On a terminal it is a bar redrawn in place (tqdm); on anything else (a log file, a pipe, a notebook's captured
output) it is a plain line at every tenth of the run and at its end, since a bar redrawn with carriage returns
would make one line of thousands of updates there.
"""

from __future__ import annotations

import sys
import time as _time


class Progress:
    """Progress of a dynamic run from ``t0`` to ``t_end`` (s); a context manager.

    The figure is the simulated time over the end time, of the whole run (a run resumed at t0 starts at t0); beside
    it the time steps per second of wall-clock time and the mean number of Newton iterations per step, both since
    this progress started.
    ``update(t, steps, newton_iterations)``: t the simulated time now (s); steps the number of steps taken
    so far (cumulative, as ``Record.step``); newton_iterations the Newton iterations of the steps taken
    since the previous update (of the one step just taken when called at every step). ``steps0``: the
    step count at the start (a resumed run), not counted in the rate. ``disable=True``: no output (the
    figures are still kept in ``steps_per_second`` and ``newton_per_step``). ``file``: where it is written
    (standard error by default); ``terminal``: draw a bar (True) or write lines (False), by default a bar
    where ``file`` is a terminal. ``lines``: how many plain lines a whole run writes (one each time the run
    passes another 1/lines of it). Other keywords go to tqdm (the bar).
    """

    def __init__(self, t0, t_end, disable=False, steps0=0, desc="dynamics", file=None, terminal=None, lines=10,
                 **tqdm_kwargs):
        self.t0, self.t_end = float(t0), float(t_end)
        self.steps0 = self.steps = int(steps0)
        self.newton_iterations = 0
        self.start = _time.perf_counter()
        self.desc, self.disable, self.lines = desc, bool(disable), max(1, int(lines))
        self.file = sys.stderr if file is None else file
        if terminal is None:
            isatty = getattr(self.file, "isatty", None)
            terminal = bool(isatty()) if callable(isatty) else False
        self.bar = None
        self.t = self.t0
        self.shown = None                     # the simulated time of the last plain line (s)
        self.written = self._tenth(self.t0)   # the last fraction of the run a plain line was written at
        if terminal:
            from tqdm import tqdm  # imported here: only runs that show a bar need it

            bar_format = "{desc}: {percentage:3.0f}%|{bar}| t = {n:.4g}/{total:.4g} s [{elapsed}<{remaining}{postfix}]"
            # the whole run's time, a resumed run's bar starting where it stopped
            self.bar = tqdm(total=self.t_end, initial=self.t0, desc=desc, disable=disable, file=self.file,
                            bar_format=tqdm_kwargs.pop("bar_format", bar_format), **tqdm_kwargs)

    @property
    def steps_per_second(self):
        """Steps taken since the start per second of wall-clock time."""
        wall = _time.perf_counter() - self.start
        return (self.steps - self.steps0) / wall if wall > 0 else 0.0

    @property
    def newton_per_step(self):
        """Mean Newton iterations per step since the start (0 before the first step)."""
        taken = self.steps - self.steps0
        return self.newton_iterations / taken if taken else 0.0

    def _tenth(self, t):
        """How many whole 1/lines of the run lie before the simulated time t (s)."""
        span = self.t_end if self.t_end > 0 else 1.0
        return int(self.lines * min(max(t, 0.0), span) / span + 1e-9)

    def _figures(self):
        return f"{self.steps_per_second:.3g} steps/s, {self.newton_per_step:.2f} Newton it./step"

    def _line(self):
        """A plain line of the run's progress now."""
        share = 100.0 * self.t / self.t_end if self.t_end > 0 else 100.0
        wall = _time.perf_counter() - self.start
        self.file.write(f"{self.desc}: {share:3.0f}% t = {self.t:.4g}/{self.t_end:.4g} s, {self._figures()}, "
                        f"{wall:.1f} s elapsed\n")
        self.file.flush()
        self.shown = self.t

    def update(self, t, steps, newton_iterations=0):
        """Show the run at simulated time t (s), ``steps`` steps taken so far, ``newton_iterations`` spent
        since the previous update."""
        self.steps = int(steps)
        self.newton_iterations += int(newton_iterations)
        self.t = min(max(float(t), self.t0), self.t_end)
        if self.bar is not None:
            self.bar.set_postfix_str(self._figures(), refresh=False)
            self.bar.update(self.t - self.bar.n)
        elif not self.disable and self._tenth(self.t) > self.written:
            self.written = self._tenth(self.t)
            self._line()

    def close(self):
        if self.bar is not None:
            self.bar.close()
        elif not self.disable and self.steps > self.steps0 and self.shown != self.t:
            self._line()   # the run's end, or where a run stopped between two lines got to

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False
