"""A Dense Fog table's bake on a worker thread, so that the user interface stays live and Esc cancels it.

The operators (``FOG_OT_add``'s invoke, ``FOG_OT_bake_tables``) hand a ``BakeJob`` the tables a build is
missing (``apply.missing_tables``: each with its estimate), poll it from a modal timer and show its
``status()`` in the status bar and on the progress cursor.  The bakes themselves are numpy only
(``precompute.model.bakers``): nothing of Blender's data is touched off the main thread.  ``cancel()`` makes the bake's
progress callback raise ``BakeCancelled`` at its next call (a fraction of a second: the bakes report often);
nothing half-baked is cached, and the scene is not changed.
"""
import threading
import time

from ..precompute.model import bakers
from ..precompute.core.table_cache import BakeCancelled


_live = []   # jobs started and not done (``running``)


def running():
    """True while a started job has not finished: a second bake is not started beside it."""
    _live[:] = [job for job in _live if not job.done]
    return bool(_live)


class BakeJob:
    """Bake ``tables`` ([(TableSpec, seconds)], ``bakers.missing``) for anisotropy ``g`` on a daemon thread.

    ``done`` once every table is baked, the job cancelled or a bake failed (``error``: its message); ``status()``
    says which table and how far, with the seconds left by the estimate."""

    def __init__(self, tables, g):
        self.tables, self.g = list(tables), float(g)
        self.total_seconds = sum(s for _, s in self.tables) or 1.0
        self.current, self.fraction, self.finished_seconds = None, 0.0, 0.0
        self.cancelled, self.error, self.done = False, None, False
        self.started = time.perf_counter()
        self._thread = threading.Thread(target=self._run, name="Analytic Fog bake", daemon=True)

    def start(self):
        _live.append(self)
        self._thread.start()
        return self

    def cancel(self):
        """Stop at the bake's next progress call; ``done`` follows (``wait`` to block until then)."""
        self.cancelled = True

    def wait(self, timeout=None):
        self._thread.join(timeout)
        return self.done

    def overall(self):
        """The share of the whole job done, by the tables' estimates, in [0, 1]."""
        if self.current is None:
            return 1.0 if self.done else 0.0
        seconds = dict((t, s) for t, s in self.tables)[self.current]
        return min((self.finished_seconds + self.fraction * seconds) / self.total_seconds, 1.0)

    def status(self):
        """One line for the status bar: what is baking, how far, about how long is left, how to cancel."""
        if self.current is None:
            return "Analytic Fog: preparing the bake"
        left = max(self.total_seconds * (1.0 - self.overall()), 0.0)
        return (f"Analytic Fog: baking {bakers.label(self.current)}: {self.fraction:.0%} "
                f"(about {left:.0f} s left; Esc cancels)")

    def _report(self, done, total):
        if self.cancelled:
            raise BakeCancelled(bakers.label(self.current))
        self.fraction = done / total if total else 1.0

    def _run(self):
        try:
            for table, seconds in self.tables:
                if self.cancelled:
                    raise BakeCancelled(bakers.label(table))
                self.current, self.fraction = table, 0.0
                print(f"Analytic Fog: baking {bakers.label(table)} (about {max(seconds, 1.0):.0f} s)", flush=True)
                bakers.table_array(table, self.g, progress=self._report)
                self.finished_seconds += seconds
        except BakeCancelled:
            self.cancelled = True
        except Exception as e:   # noqa: BLE001 - said by the operator that polls the job
            self.error = f"{type(e).__name__}: {e}"
        finally:
            self.done = True
