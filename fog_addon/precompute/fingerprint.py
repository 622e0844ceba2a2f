"""Versions derived from content: a short hash of the source text of the modules that made something.

A node group, table image or OSL text built by one version of the model
carries the fingerprint of what built it; an edited kernel, table layout or
builder changes the fingerprint, so a saved file's stale copy is rebuilt
instead of hiding behind a hand-bumped version number.
"""
import hashlib
import pathlib


def source_fingerprint(*modules, extra=()):
    """12 hex digits of SHA-256 over the source files of ``modules`` and the reprs of ``extra``."""
    h = hashlib.sha256()
    for mod in modules:
        h.update(pathlib.Path(mod.__file__).read_bytes())
    for x in extra:
        h.update(repr(x).encode())
    return h.hexdigest()[:12]
