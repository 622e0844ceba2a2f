"""Versions derived from content: a short hash of the add-on's source.

Whatever the add-on builds into a .blend (node groups, compositor groups, kernel groups, table images, OSL
texts) carries the fingerprint of the code that built it (``package_fingerprint``); a saved file's copy made
by other code is rebuilt instead of hiding behind a hand-bumped version number.

**What it covers**: every ``*.py`` file under ``fog_addon/`` (the folder above ``precompute/``, whose ``core/``
holds this module), found by walking the folder, hashed in the order of their relative paths (each path, its
length and its bytes).  No list of modules is kept by hand, so a builder, kernel or table that a hand-kept list
left out cannot hide behind an old copy; a new, renamed or removed module changes it too.  It is computed once
per process (``tree_fingerprint`` is cached; a few milliseconds for the whole package) from the files around this
module, so it works the same from the source tree and from an installed extension (Blender unpacks the zip into
``extensions/<repo>/analytic_fog``; the module name, e.g. ``bl_ext.user_default.analytic_fog``, plays no
part).  A saved file rendered without the add-on (a render farm) computes no fingerprint: it renders what
the file holds.

**Table images get the package's fingerprint, the table cache that of ``precompute/``**:

* A table image's content is decided by its baker (``precompute/``) and by how ``nodes/images.py`` packs it
  (channels, precision), so stamping images with ``precompute_fingerprint`` alone would let an edited
  packing hide behind an old image.  The package's fingerprint is correct and needs no list; it rebuilds the
  images whenever any code changes, as it does the node groups that read them (the two change together).
* The baked arrays themselves (``table_cache.cached_bake``) depend only on ``precompute/`` (pure numpy, no import
  from outside the folder) and on numpy: the on-disk cache is keyed by ``precompute_fingerprint``, so an
  image rebuilt after an edit elsewhere reloads its array instead of baking it again.
"""
import functools
import hashlib
import os
import pathlib

PRECOMPUTE = pathlib.Path(__file__).resolve().parent.parent   # fog_addon/precompute (this module is in core/)
PACKAGE = PRECOMPUTE.parent                                    # fog_addon
PRECOMPUTE_MODULE = __name__.rsplit(".", 2)[0]                  # "fog_addon.precompute" or "bl_ext....precompute"


def source_files(root):
    """The ``*.py`` files under ``root`` (no ``__pycache__``), as sorted POSIX paths relative to it."""
    root = pathlib.Path(root)
    found = []
    for folder, dirs, files in os.walk(root):
        dirs[:] = [d for d in dirs if d != "__pycache__"]
        found += [(pathlib.Path(folder) / f).relative_to(root).as_posix() for f in files if f.endswith(".py")]
    return sorted(found)


@functools.lru_cache(maxsize=None)
def tree_fingerprint(root):
    """12 hex digits of SHA-256 over ``source_files(root)``: each relative path, byte count and bytes.
    Cached per process and per ``root`` (a ``pathlib.Path`` or str)."""
    root = pathlib.Path(root)
    h = hashlib.sha256()
    for rel in source_files(root):
        data = (root / rel).read_bytes()
        h.update(f"{rel}\0{len(data)}\0".encode())
        h.update(data)
    return h.hexdigest()[:12]


def package_fingerprint(*extra):
    """The fingerprint of all of the add-on's source (``fog_addon/**/*.py``), and of the reprs of ``extra``
    if given (what else decides a built thing, e.g. a table's spec or a kernel group's name)."""
    fp = tree_fingerprint(PACKAGE)
    if not extra:
        return fp
    return hashlib.sha256("\0".join([fp, *map(repr, extra)]).encode()).hexdigest()[:12]


def precompute_fingerprint():
    """The fingerprint of ``fog_addon/precompute/**/*.py``: what decides a baked table's values."""
    return tree_fingerprint(PRECOMPUTE)
