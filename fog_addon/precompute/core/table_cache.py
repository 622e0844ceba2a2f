"""The tables' on-disk cache (numpy only).

Baking every table takes seconds (the airlight table of an anisotropic medium alone several), in every
process that needs them: the add-on's, the command line's, each test's.  ``cached_bake`` keeps each baked
array in a cache folder, keyed by what decides its values: the source of ``precompute/``
(``fingerprint.precompute_fingerprint``: the bakers import nothing from outside it), numpy's version and the
table's ``TableSpec`` (name, size, anisotropy g, channels).  An array read from the cache is the very array
the baker returned (same dtype and bits); an entry that is missing, unreadable or corrupt (each file is a
``.npz`` whose zip CRC is checked on reading, holding the spec it was baked for) is baked again and
rewritten, never an error.  Entries are written to a temporary file and renamed into place, so processes
running in parallel never see half a file, and a table missing in several processes at once is baked by one of
them while the others wait for it (``_baking``).

Where: ``$ANALYTIC_FOG_CACHE`` if set (an empty value or ``off`` turns the cache off), else
``$XDG_CACHE_HOME/analytic_fog``, else ``~/.cache/analytic_fog``; one subfolder per precompute fingerprint
and numpy version, of which the KEEP most recently used are kept.
"""
import contextlib
import hashlib
import os
import pathlib
import re
import shutil
import tempfile

import numpy as np

from . import fingerprint


class BakeCancelled(Exception):
    """Raised by a bake's ``progress(done, total)`` callback to stop it (the bakers of ``spot_multiple``,
    ``multiple``, ``emitter_glow`` call it as they go): ``cached_bake`` lets it through and stores nothing."""


ENV = "ANALYTIC_FOG_CACHE"   # the cache folder; "" or "off": no cache
KEEP = 16                    # fingerprint subfolders kept (the most recently used); older ones are deleted
_SUBFOLDER = re.compile(r"^[0-9a-f]{12}-numpy[0-9A-Za-z.+_-]+$")   # what ``cache_path`` names (and may prune)


def cache_dir():
    """The cache folder (``pathlib.Path``), or None when the cache is off (module docstring)."""
    value = os.environ.get(ENV)
    if value is not None:
        return None if value.strip().lower() in ("", "off") else pathlib.Path(value).expanduser()
    base = os.environ.get("XDG_CACHE_HOME", "")
    base = pathlib.Path(base) if os.path.isabs(base) else pathlib.Path.home() / ".cache"
    return base / "analytic_fog"


def cache_path(spec):
    """Where ``spec``'s table is cached, or None when the cache is off."""
    root = cache_dir()
    if root is None:
        return None
    folder = root / f"{fingerprint.precompute_fingerprint()}-numpy{np.__version__}"
    slug = re.sub(r"[^0-9A-Za-z+.-]+", "_", spec.name).strip("_")
    return folder / f"{slug}-{hashlib.sha256(repr(spec).encode()).hexdigest()[:8]}.npz"


def read(spec):
    """``spec``'s table as the cache holds it, or None (no readable entry: ``cached_bake`` would bake)."""
    path = cache_path(spec)
    return _load(path, spec) if path is not None and path.is_file() else None


def is_cached(spec):
    """True if ``spec``'s table is in the cache (a readable entry for it: ``cached_bake`` would not bake)."""
    return read(spec) is not None


def cached_bake(spec, bake):
    """``bake()``, ``spec``'s table, read from the cache if there, else baked and stored there (module
    docstring).  Only bakers defined in ``precompute/`` are cached: the cache key holds only its source.  A
    bake stopped by ``BakeCancelled`` (or any error) stores nothing."""
    fn = getattr(bake, "func", bake)   # a functools.partial's function
    path = cache_path(spec)
    if path is None or not getattr(fn, "__module__", "").startswith(fingerprint.PRECOMPUTE_MODULE + "."):
        return bake()
    arr = _load(path, spec)
    if arr is None:
        with _baking(path):
            arr = _load(path, spec)   # (another process may have baked it while this one waited)
            if arr is None:
                arr = bake()
                _store(path, spec, arr)
    return arr


@contextlib.contextmanager
def _baking(path):
    """Hold ``path``'s bake lock (an exclusive ``flock`` on "<path>.lock"): processes that need the same missing
    table at once (a farm's, the tests' workers) bake it once, the others wait and read it.  Without ``fcntl``
    (Windows) or a writable folder, no lock: each bakes, as before.  The system releases a lock whose process
    died."""
    try:
        import fcntl
        new = not path.parent.is_dir()
        path.parent.mkdir(parents=True, exist_ok=True)
        lock = open(f"{path}.lock", "a")
    except (ImportError, OSError):
        yield
        return
    if new:
        _prune(path.parent.parent)
    try:
        fcntl.flock(lock, fcntl.LOCK_EX)
        yield
    finally:
        lock.close()   # (closing releases the lock)


def _load(path, spec):
    """The array cached at ``path`` for ``spec``, or None (missing, unreadable, corrupt, another spec)."""
    try:
        with np.load(path, allow_pickle=False) as z:
            if str(z["spec"]) != repr(spec):
                return None
            arr = z["table"]   # reads the whole member: zipfile checks its CRC-32 at the end
    except Exception:   # noqa: BLE001 - any failure to read means: bake again
        return None
    _touch(path.parent)
    return arr


def _store(path, spec, arr):
    """Write ``arr`` to ``path`` atomically (temporary file, then ``os.replace``); failures are ignored."""
    tmp = None
    try:
        new = not path.parent.is_dir()
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=path.name + ".", suffix=".tmp")
        with os.fdopen(fd, "wb") as f:
            np.savez(f, table=arr, spec=np.array(repr(spec)))
        os.replace(tmp, path)
        tmp = None
        if new:
            _prune(path.parent.parent)
    except OSError:
        pass
    finally:
        if tmp is not None:
            try:
                os.remove(tmp)
            except OSError:
                pass


_TOUCHED = set()


def _touch(folder):
    """Mark ``folder`` used (its mtime, once per process), so ``_prune`` keeps it."""
    if folder not in _TOUCHED:
        _TOUCHED.add(folder)
        try:
            os.utime(folder)
        except OSError:
            pass


def _prune(root):
    """Delete the cache's subfolders beyond the KEEP most recently used (only folders named as ``cache_path``
    names them: the cache folder may be shared with other files)."""
    try:
        subs = [p for p in root.iterdir() if p.is_dir() and _SUBFOLDER.match(p.name)]
        subs.sort(key=lambda p: p.stat().st_mtime, reverse=True)
    except OSError:
        return
    for p in subs[KEEP:]:
        shutil.rmtree(p, ignore_errors=True)
