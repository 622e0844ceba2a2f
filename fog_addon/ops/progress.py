"""Progress of long operations (adding the fog to 1 000 materials takes seconds).

``apply_fog`` and ``remove_fog`` call ``progress(stage, done, total)`` as they
go: ``stage`` one of STAGES, ``done`` of ``total`` items of that stage.  Two
reporters: Blender's progress cursor for the operators (``window_progress``)
and a line per stage for the command line (``ConsoleProgress``).
"""
import contextlib
import sys
import time

STAGES = ("appended fog", "lights and tables", "materials", "world", "lights")


def silent(stage, done, total):
    """The default reporter: nothing."""


def overall(stage, done, total):
    """Fraction of the whole operation in [0, 1] (each stage an equal share)."""
    k = STAGES.index(stage)
    return (k + (done / total if total else 1.0)) / len(STAGES)


@contextlib.contextmanager
def window_progress(window_manager):
    """A reporter driving Blender's progress cursor (``progress_begin/update/end``), ended on exit."""
    window_manager.progress_begin(0.0, 1.0)
    try:
        yield lambda stage, done, total: window_manager.progress_update(overall(stage, done, total))
    finally:
        window_manager.progress_end()


class ConsoleProgress:
    """A line per stage, and every tenth of a long stage, with the time since the start (command line)."""

    def __init__(self, out=sys.stdout, prefix="progress: "):
        self.out, self.prefix, self.t0, self.last = out, prefix, time.perf_counter(), None

    def __call__(self, stage, done, total):
        step = max(total // 10, 1)
        if stage != self.last or (total >= 100 and done % step == 0) or done == total:
            self.last = stage
            print(f"{self.prefix}{stage} {done}/{total} ({time.perf_counter() - self.t0:.1f} s)",
                  file=self.out, flush=True)
