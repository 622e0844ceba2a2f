"""Progress of long operations (adding the fog to 1 000 materials takes seconds; a Dense Fog table's bake tens).

``apply_fog`` and ``remove_fog`` call ``progress(stage, done, total)`` as they
go: ``stage`` one of STAGES, ``done`` of ``total`` items of that stage.  Two
reporters: Blender's progress cursor for the operators (``window_progress``)
and a line per stage for the command line (``ConsoleProgress``).

A table's bake (``precompute.model.bakers``: ``missing`` lists the tables not yet
cached with the seconds each is estimated to take) reports ``progress(done,
total)`` of its own; ``bake_progress`` makes one from an operation's reporter:
ConsoleProgress announces the bake with its estimate and prints a line every
tenth, others see it as BAKE_STAGE's progress.  The bake's callback
raises ``BakeCancelled`` once ``cancel()`` was called on the ConsoleProgress
(nothing of the bake is cached).
"""
import contextlib
import sys
import time

from ..precompute.core.table_cache import BakeCancelled

STAGES = ("appended fog", "lights and tables", "materials", "world", "lights")
BAKE_STAGE = "world"   # the stage a bake's progress counts in (``bake_progress``): the scene groups' build bakes


def silent(stage, done, total):
    """The default reporter: nothing."""


def overall(stage, done, total):
    """Fraction of the whole operation in [0, 1] (each stage an equal share)."""
    k = STAGES.index(stage)
    return (k + (done / total if total else 1.0)) / len(STAGES)


@contextlib.contextmanager
def window_progress(window_manager):
    """A reporter driving Blender's progress cursor (``progress_begin/update/end``), ended on exit; a bake is
    announced with its estimate and followed on the console as well (``WindowProgress``)."""
    window_manager.progress_begin(0.0, 1.0)
    try:
        yield WindowProgress(window_manager)
    finally:
        window_manager.progress_end()


def bake_progress(progress, what, seconds):
    """A bake's ``progress(done, total)`` reporting through the operation's ``progress``: its ``bake(what,
    seconds)`` if it has one (``ConsoleProgress``), else as BAKE_STAGE's ``done`` of ``total``.  ``what``: the
    table (``bakers.label``), ``seconds``: its estimate (``bakers.estimate_seconds``)."""
    bake = getattr(progress, "bake", None)
    if bake is not None:
        return bake(what, seconds)
    return lambda done, total: progress(BAKE_STAGE, done, total)


class ConsoleProgress:
    """A line per stage, and every tenth of a long stage, with the time since the start (command line); a bake
    (``bake``) announced with its estimate, then a line every tenth of it."""

    def __init__(self, out=sys.stdout, prefix="progress: "):
        self.out, self.prefix, self.t0, self.last = out, prefix, time.perf_counter(), None
        self.cancelled = False

    def __call__(self, stage, done, total):
        step = max(total // 10, 1)
        if stage != self.last or (total >= 100 and done % step == 0) or done == total:
            self.last = stage
            self._line(f"{stage} {done}/{total}")

    def _line(self, text):
        print(f"{self.prefix}{text} ({time.perf_counter() - self.t0:.1f} s)", file=self.out, flush=True)

    def cancel(self):
        """Stop the bake under way (and any later one): its callback raises ``BakeCancelled`` when next called."""
        self.cancelled = True

    def bake(self, what, seconds):
        """Announce the bake of ``what`` ("baking the spot table (...) (about 9 s)") and return its
        ``progress(done, total)``: a line at each tenth of ``total`` crossed, "done" at the end; it raises
        ``BakeCancelled`` after ``cancel``."""
        self._line(f"baking {what} (about {max(seconds, 1.0):.0f} s)")
        self.last = None
        start, tenth = time.perf_counter(), [0]

        def report(done, total):
            if self.cancelled:
                raise BakeCancelled(what)
            k = int(10 * done / total) if total else 10
            if k > tenth[0]:
                tenth[0] = k
                took = time.perf_counter() - start
                self._line(f"baking {what}: done in {took:.1f} s" if k >= 10 else f"baking {what}: {10 * k} %")

        return report


class WindowProgress(ConsoleProgress):
    """The operators' reporter: the stages on Blender's progress cursor; a bake announced on the console with its
    estimate ("Analytic Fog: baking the spot table (...) (about 4 s)"), a line each tenth, and its share on the
    cursor."""

    def __init__(self, window_manager, out=sys.stdout):
        super().__init__(out, prefix="Analytic Fog: ")
        self.window_manager = window_manager

    def __call__(self, stage, done, total):
        self.window_manager.progress_update(overall(stage, done, total))

    def bake(self, what, seconds):
        console = super().bake(what, seconds)

        def report(done, total):
            console(done, total)
            self.window_manager.progress_update(overall(BAKE_STAGE, done, total))

        return report
