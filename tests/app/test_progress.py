"""The progress bar: drawn on a terminal, silent when quiet or when output is not a terminal."""

import io

from tightknot.app.progress import BAR_WIDTH, Progress, phase_progress


class _Tty(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_silent_when_not_a_terminal_or_quiet() -> None:
    pipe = io.StringIO()  # isatty() is False, like a log file or a pipe
    with Progress("knot", stream=pipe) as bar:
        bar.update(0.5, "half")
    assert pipe.getvalue() == ""
    tty = _Tty()
    with Progress("knot", enabled=False, stream=tty) as bar:  # --quiet
        bar.update(0.5, "half")
    assert tty.getvalue() == ""


def test_draws_on_a_terminal_and_clears_its_line() -> None:
    tty = _Tty()
    bar = Progress("knot", stream=tty, min_interval=0.0)
    bar.update(0.5, "step 3")
    text = tty.getvalue()
    assert text.startswith("\rknot [") and "step 3" in text and " 50%" in text
    assert text.count("#") == BAR_WIDTH // 2
    bar.update(2.0)  # clipped
    assert " 100%" in tty.getvalue().split("\r")[-1]
    bar.close("done")
    assert tty.getvalue().endswith("\rdone\n")


def test_redraws_are_throttled_but_the_end_is_shown() -> None:
    tty = _Tty()
    bar = Progress("knot", stream=tty, min_interval=3600.0)
    bar.update(0.1)
    bar.update(0.2)  # within the interval: skipped
    assert tty.getvalue().count("\r") == 1
    bar.update(1.0)  # the end is always drawn
    assert tty.getvalue().count("\r") == 2


def test_phase_progress_maps_the_phases_onto_one_bar() -> None:
    seen: list[float] = []

    class _Bar:
        def update(self, fraction: float, detail: str = "") -> None:
            seen.append(fraction)

    open_update = phase_progress(_Bar(), closed=False)
    open_update("tighten", 1.0, 10)
    open_update("pull", 0.0, 11)
    open_update("pull", 1.0, 20)
    closed_update = phase_progress(_Bar(), closed=True)
    closed_update("tighten", 0.5, 3)
    assert seen == [0.7, 0.7, 1.0, 0.5]
