"""The progress bar of a run in time: the simulated time over the end time, with the wall-clock step rate
and the mean number of Newton iterations per step (tqdm)."""

from __future__ import annotations

import time as _time


class Progress:
    """Progress bar of a dynamic run from ``t0`` to ``t_end`` (s), over tqdm; a context manager.

    The bar is the simulated time over the end time, of the whole run (a run resumed at t0 starts at t0); the
    postfix the time steps per second of wall-clock time and the mean number of Newton iterations per step,
    both since this bar started.
    ``update(t, steps, newton_iterations)``: t the simulated time now (s); steps the number of steps taken
    so far (cumulative, as ``Record.step``); newton_iterations the Newton iterations of the steps taken
    since the previous update (of the one step just taken when called at every step). ``steps0``: the
    step count at the start (a resumed run), not counted in the rate. ``disable=True``: no output (the
    figures are still kept in ``steps_per_second`` and ``newton_per_step``). Other keywords go to tqdm.
    """

    def __init__(self, t0, t_end, disable=False, steps0=0, desc="dynamics", **tqdm_kwargs):
        from tqdm import tqdm  # imported here: only runs that show progress need it

        self.t0, self.t_end = float(t0), float(t_end)
        self.steps0 = self.steps = int(steps0)
        self.newton_iterations = 0
        self.start = _time.perf_counter()
        bar_format = "{desc}: {percentage:3.0f}%|{bar}| t = {n:.4g}/{total:.4g} s [{elapsed}<{remaining}{postfix}]"
        # the whole run's time, a resumed run's bar starting where it stopped
        self.bar = tqdm(total=self.t_end, initial=self.t0, desc=desc, disable=disable,
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

    def update(self, t, steps, newton_iterations=0):
        """Show the run at simulated time t (s), ``steps`` steps taken so far, ``newton_iterations`` spent
        since the previous update."""
        self.steps = int(steps)
        self.newton_iterations += int(newton_iterations)
        self.bar.set_postfix_str(f"{self.steps_per_second:.3g} steps/s, {self.newton_per_step:.2f} Newton it./step",
                                 refresh=False)
        done = min(max(float(t), self.t0), self.bar.total)
        self.bar.update(done - self.bar.n)

    def close(self):
        self.bar.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False
