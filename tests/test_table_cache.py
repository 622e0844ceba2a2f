"""The on-disk cache of baked tables (``precompute/core/bakers.py``: ``cached_bake``) never changes a result.

Expected values: a fresh bake by the baker itself.  A table read from the cache must be the same bits and
dtype; a missing, truncated, bit-flipped, foreign or unreadable entry must be baked again and rewritten;
parallel writers must leave a readable entry.
"""
import multiprocessing
import os
import pathlib
import shutil

import numpy as np
import pytest

from fog_addon.precompute.core import fingerprint, table_cache, tables
from fog_addon.precompute.model import bakers
from fog_addon.precompute.model import pixel


@pytest.fixture
def cache(tmp_path, monkeypatch):
    folder = tmp_path / "cache"
    monkeypatch.setenv(table_cache.ENV, str(folder))
    return folder


class Counting:
    """A baker (defined in ``precompute/``, so cached) that counts its calls."""

    def __init__(self, spec, bake):
        self.spec, self.bake, self.calls = spec, bake, 0
        self.__module__ = bake.__module__ if hasattr(bake, "__module__") else bakers.__name__

    def __call__(self):
        self.calls += 1
        return self.bake()


def _same(a, b):
    return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()


def _all_bakers(g):
    return [*bakers.bakers(g).values(), *pixel.FILTERS.values()]


def test_cached_tables_are_the_baked_bits(cache):
    """Every table (g = 0, and the pixel filters), baked cold, then read warm: the bits the baker returned."""
    baked = {}
    for spec, bake in _all_bakers(0.0):
        counting = Counting(spec, bake)
        baked[spec.name] = np.asarray(table_cache.cached_bake(spec, counting))   # cold: the baker's own array
        assert counting.calls == 1 and table_cache.cache_path(spec).is_file(), spec
        warm = table_cache.cached_bake(spec, counting)
        assert counting.calls == 1, f"{spec.name}: baked again although cached"
        assert _same(warm, baked[spec.name]), spec.name
    tabs = bakers.numpy_tables.__wrapped__(0.0)
    assert tabs.keys() <= baked.keys() and all(_same(tabs[k], baked[k]) for k in tabs)


def _corruptions(path):
    data = path.read_bytes()
    middle = len(data) // 2
    yield "truncated", data[:middle]
    yield "bit flipped", data[:middle] + bytes([data[middle] ^ 0x10]) + data[middle + 1:]
    yield "garbage", b"not a table"
    yield "empty", b""


def test_corrupt_entries_are_baked_again(cache):
    spec, bake = tables.LOBE_RESPONSE, bakers.bakers()[tables.LOBE_RESPONSE.name][1]
    fresh = bake()
    table_cache.cached_bake(spec, bake)
    path = table_cache.cache_path(spec)
    for what, data in list(_corruptions(path)):
        path.write_bytes(data)
        counting = Counting(spec, bake)
        assert _same(table_cache.cached_bake(spec, counting), fresh) and counting.calls == 1, what
        assert _same(table_cache.cached_bake(spec, counting), fresh) and counting.calls == 1, f"{what}: not rewritten"
    # an entry of another table at this path (a hash collision or a copied file) is not taken for this one
    other = tables.SPECULAR_ALBEDO
    table_cache._store(path, other, np.zeros((other.height, other.width), np.float32))
    counting = Counting(spec, bake)
    assert _same(table_cache.cached_bake(spec, counting), fresh) and counting.calls == 1


def test_unwritable_cache_is_not_an_error(tmp_path, monkeypatch):
    blocker = tmp_path / "file"
    blocker.write_text("")
    monkeypatch.setenv(table_cache.ENV, str(blocker / "cache"))   # a folder inside a file: mkdir fails
    spec, bake = tables.LOBE_RESPONSE, bakers.bakers()[tables.LOBE_RESPONSE.name][1]
    assert _same(table_cache.cached_bake(spec, bake), bake())


@pytest.mark.parametrize("value", ["", "off", "OFF"])
def test_cache_off(tmp_path, monkeypatch, value):
    monkeypatch.setenv(table_cache.ENV, value)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    monkeypatch.setenv("HOME", str(tmp_path))
    assert table_cache.cache_dir() is None and table_cache.cache_path(tables.LOBE_RESPONSE) is None
    spec, bake = tables.LOBE_RESPONSE, bakers.bakers()[tables.LOBE_RESPONSE.name][1]
    counting = Counting(spec, bake)
    table_cache.cached_bake(spec, counting)
    table_cache.cached_bake(spec, counting)
    assert counting.calls == 2 and not any(tmp_path.iterdir())


def test_default_location(tmp_path, monkeypatch):
    monkeypatch.delenv(table_cache.ENV, raising=False)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    assert table_cache.cache_dir() == tmp_path / "xdg" / "analytic_fog"
    monkeypatch.delenv("XDG_CACHE_HOME")
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    assert table_cache.cache_dir() == tmp_path / "home" / ".cache" / "analytic_fog"


def test_key_holds_precompute_source_and_spec(cache, tmp_path, monkeypatch):
    """Another g, size or precompute source: another entry; another source outside precompute: the same."""
    spec = tables.AIRLIGHT
    path = table_cache.cache_path(spec)
    assert path.parent.parent == cache and fingerprint.precompute_fingerprint() in path.parent.name
    assert table_cache.cache_path(tables.anisotropic(spec, 0.85)) != path
    # Blender's float32 0.85 (0.8500000238...) is the same table as Python's 0.85: one entry, one bake
    assert table_cache.cache_path(tables.anisotropic(spec, float(np.float32(0.85)))) == table_cache.cache_path(
        tables.anisotropic(spec, 0.85))
    assert table_cache.cache_path(tables.anisotropic(spec, 0.851)) != table_cache.cache_path(
        tables.anisotropic(spec, 0.85))
    assert table_cache.cache_path(tables.TableSpec(spec.name, spec.width, spec.height + 1)) != path
    copy = tmp_path / "fog_addon"
    shutil.copytree(fingerprint.PACKAGE, copy, ignore=shutil.ignore_patterns("__pycache__"))
    monkeypatch.setattr(fingerprint, "PACKAGE", copy)
    with open(copy / "nodes" / "comp_fog.py", "a", encoding="utf-8") as f:
        f.write("# edited\n")
    assert table_cache.cache_path(spec) == path
    monkeypatch.setattr(fingerprint, "PRECOMPUTE", copy / "precompute")
    with open(copy / "precompute" / "model" / "pixel.py", "a", encoding="utf-8") as f:
        f.write("# edited\n")
    assert table_cache.cache_path(spec) != path


def test_bakers_outside_precompute_are_not_cached(cache):
    spec, calls = tables.LOBE_RESPONSE, []
    bake = lambda: calls.append(1) or np.zeros((spec.height, spec.width), np.float32)  # noqa: E731
    table_cache.cached_bake(spec, bake)
    table_cache.cached_bake(spec, bake)
    assert len(calls) == 2 and not cache.exists()


def test_old_fingerprints_are_pruned(cache):
    cache.mkdir()
    old = []
    for k in range(table_cache.KEEP + 3):
        d = cache / f"{k:012x}-numpy1.0"
        d.mkdir()
        os.utime(d, (1e9 + k, 1e9 + k))
        old.append(d)
    foreign = cache / "not-ours"
    foreign.mkdir()
    os.utime(foreign, (1e8, 1e8))
    spec, bake = tables.LOBE_RESPONSE, bakers.bakers()[tables.LOBE_RESPONSE.name][1]
    table_cache.cached_bake(spec, bake)
    kept = sorted(p.name for p in cache.iterdir())
    assert foreign.exists() and table_cache.cache_path(spec).is_file()
    assert [d.exists() for d in old] == [False] * 4 + [True] * (table_cache.KEEP - 1), kept


def _write(path):
    """Bake and store the lobe response at ``path`` five times (the path comes from the parent process: a
    child computing its own would see another fingerprint if a source file changed in between)."""
    spec, bake = tables.LOBE_RESPONSE, bakers.bakers()[tables.LOBE_RESPONSE.name][1]
    for _ in range(5):
        table_cache._store(pathlib.Path(path), spec, bake())
    return True


def test_parallel_writers_leave_a_readable_entry(cache):
    spec, bake = tables.LOBE_RESPONSE, bakers.bakers()[tables.LOBE_RESPONSE.name][1]
    path = table_cache.cache_path(spec)
    with multiprocessing.get_context("spawn").Pool(3) as pool:
        assert all(pool.map(_write, [str(path)] * 3))
    counting = Counting(spec, bake)
    assert _same(table_cache.cached_bake(spec, counting), bake()) and counting.calls == 0
    assert [p.name for p in path.parent.iterdir()] == [path.name]   # no temporary file left


def test_numpy_helpers_read_the_cache(cache, monkeypatch):
    """``surface.specular_table`` (the view's albedos at Add) and ``surface.surface_table`` bake through the
    cache too: a second process reads what the first baked."""
    from fog_addon.precompute.physics.point import surface
    spec = tables.SPECULAR_ALBEDO
    monkeypatch.setattr(surface, "_TABLE_CACHE", {})
    first = surface.specular_table()
    assert table_cache.cache_path(spec).is_file()
    monkeypatch.setattr(surface, "_TABLE_CACHE", {})

    def baked_again(*args):
        pytest.fail("baked again")
    baked_again.__module__ = surface.__name__   # a baker of precompute/, so cached
    monkeypatch.setattr(surface, "bake_specular_albedo", baked_again)
    assert _same(surface.specular_table(), first)
    monkeypatch.setattr(surface, "_TABLE_CACHE", {})
    surface.surface_table()
    assert table_cache.cache_path(tables.SURFACE).is_file()


def test_a_missing_table_is_baked_once_by_parallel_bakers(cache):
    """Four bakers that miss the same table at once (a farm's processes, the tests' workers): one bakes it, the
    others wait for its lock and read it (the bake is slow enough that without the lock all four would bake)."""
    import threading
    import time
    spec, bake = tables.LOBE_RESPONSE, bakers.bakers()[tables.LOBE_RESPONSE.name][1]

    def slow():
        time.sleep(0.3)
        return bake()
    counting = Counting(spec, slow)
    counting.__module__ = bake.__module__
    out = []
    threads = [threading.Thread(target=lambda: out.append(table_cache.cached_bake(spec, counting))) for _ in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert counting.calls == 1 and len(out) == 4 and all(_same(a, out[0]) for a in out)
