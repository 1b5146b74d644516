"""The progress of a run in time (:class:`jaxnet.io.progress.Progress`): a bar on a terminal, plain lines elsewhere
(a log, a pipe), each saying the simulated time, the step rate and the Newton iterations per step."""

import io

from jaxnet.io.progress import Progress


class Terminal(io.StringIO):
    def isatty(self):
        return True


def run(out, n=100, **options):
    with Progress(0.0, 10.0, file=out, mininterval=0, **options) as bar:
        for step in range(1, n + 1):
            bar.update(step * 10.0 / n, step, 3)
    return out.getvalue()


def test_a_log_gets_a_plain_line_at_every_tenth_of_the_run():
    text = run(io.StringIO())
    lines = text.splitlines()
    assert "\r" not in text and len(lines) == 10
    assert lines[0].startswith("dynamics:  10% t = 1/10 s, ") and lines[-1].startswith("dynamics: 100% t = 10/10 s, ")
    assert all("3.00 Newton it./step" in line and "steps/s" in line for line in lines)


def test_a_terminal_gets_a_bar_redrawn_in_place():
    text = run(Terminal())
    assert "\r" in text and "t = 10/10 s" in text and "3.00 Newton it./step" in text


def test_a_run_stopped_between_two_lines_says_where_it_got_to():
    out = io.StringIO()
    with Progress(0.0, 10.0, file=out) as bar:
        bar.update(2.5, 25, 50)    # past 20 %: a line
        bar.update(2.7, 27, 4)     # not yet 30 %: none, until the run stops
    lines = out.getvalue().splitlines()
    assert [line.split(",")[0] for line in lines] == ["dynamics:  25% t = 2.5/10 s", "dynamics:  27% t = 2.7/10 s"]
