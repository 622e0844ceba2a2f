"""Read and write EXR / PNG images as float32 numpy arrays, without Blender.

OpenImageIO ships inside the ``bpy`` wheel (``bpy/5.0/python/lib/python3.11/
site-packages``).  It is found relative to the ``bpy`` package *without
importing bpy*, so this module is cheap and has no Blender side effects.

Conventions:

* arrays are ``(height, width, channels)`` float32, **row 0 = top row** of the
  picture (OpenImageIO's order; Blender's ``Image.pixels`` is bottom-up);
* EXR holds linear scene values as written by the renderer;
* PNG is display-referred 8-bit (or 16-bit) ``[0, 1]``; reading returns the
  values divided by the type's maximum, with no colour-space conversion.
"""
import importlib.util
import os
import pathlib
import sys

import numpy as np

_oiio = None


def _bundled_site_packages():
    spec = importlib.util.find_spec("bpy")
    if spec is None or spec.origin is None:
        return []
    root = pathlib.Path(spec.origin).parent
    return sorted(root.glob("*/python/lib/python3*/site-packages"))


def oiio():
    """The OpenImageIO module (imported on first use)."""
    global _oiio
    if _oiio is None:
        try:
            import OpenImageIO as mod
        except ImportError:
            for p in _bundled_site_packages():
                if (p / "OpenImageIO").is_dir() and str(p) not in sys.path:
                    sys.path.append(str(p))
            try:
                import OpenImageIO as mod
            except ImportError as exc:  # pragma: no cover - environment problem
                raise ImportError("OpenImageIO not found: install bpy (it bundles OIIO) "
                                  "or the OpenImageIO Python bindings") from exc
        _oiio = mod
    return _oiio


def read(path, subimage=0, channels=None):
    """Read an image as float32 ``(H, W, C)``; top row first.

    ``channels``: optional number of leading channels to keep (e.g. 3 for RGB).
    For multi-part EXRs, ``subimage`` selects the part.
    """
    o = oiio()
    path = os.fspath(path)
    if not os.path.isfile(path):
        raise FileNotFoundError(f"no such image: {path}")
    inp = o.ImageInput.open(path)
    if inp is None:
        raise IOError(f"cannot open image {path}: {o.geterror()}")
    try:
        if subimage and not inp.seek_subimage(subimage, 0):
            raise IOError(f"{path}: no subimage {subimage}")
        spec = inp.spec()
        data = inp.read_image(subimage, 0, 0, spec.nchannels, "float")   # (chbegin, chend) alone reads part 0
        if data is None:
            raise IOError(f"cannot read {path}: {inp.geterror()}")
    finally:
        inp.close()
    arr = np.asarray(data, dtype=np.float32).reshape(spec.height, spec.width, spec.nchannels)
    if channels is not None:
        arr = arr[..., :channels]
    return np.ascontiguousarray(arr)


def read_layers(path):
    """Every part of a multilayer EXR as ``{name: float32 (H, W, C)}``, e.g. "ViewLayer.Fog Light",
    "Composite.Combined" (Blender 5.0 writes one part per pass).

    Call it from a process that has not rendered: in one that has, OpenImageIO crashed (segmentation
    fault) reading multi-part files (bpy 5.0.1).
    """
    o = oiio()
    path = os.fspath(path)
    inp = o.ImageInput.open(path)
    if inp is None:
        raise IOError(f"cannot open image {path}: {o.geterror()}")
    out, k = {}, 0
    try:
        while inp.seek_subimage(k, 0):
            spec = inp.spec()
            data = inp.read_image(k, 0, 0, spec.nchannels, "float")
            name = spec.getattribute("name") or str(k)
            out[name] = np.asarray(data, np.float32).reshape(spec.height, spec.width, spec.nchannels)
            k += 1
    finally:
        inp.close()
    return out


def read_rgb(path):
    """Read the first three channels (grey images are broadcast to RGB)."""
    arr = read(path)
    if arr.shape[2] == 1:
        arr = np.repeat(arr, 3, axis=2)
    elif arr.shape[2] == 2:  # grey + alpha
        arr = np.repeat(arr[..., :1], 3, axis=2)
    return arr[..., :3].copy()


def _as_hwc(arr):
    a = np.asarray(arr, dtype=np.float32)
    if a.ndim == 2:
        a = a[..., None]
    if a.ndim != 3:
        raise ValueError(f"image array must be (H, W) or (H, W, C), got shape {a.shape}")
    return np.ascontiguousarray(a)


def _write(path, spec, data):
    """Write ``data`` (H, W, C) to ``path`` with the OIIO ImageSpec ``spec``."""
    o = oiio()
    out = o.ImageOutput.create(os.fspath(path))
    if out is None:
        raise IOError(f"cannot create {path}: {o.geterror()}")
    try:
        if not out.open(os.fspath(path), spec):
            raise IOError(f"cannot open {path} for writing: {out.geterror()}")
        if not out.write_image(np.ascontiguousarray(data)):
            raise IOError(f"cannot write {path}: {out.geterror()}")
    finally:
        out.close()


def write_exr(path, arr, half=False, compression="zip"):
    """Write a float32 (or half) EXR; ``arr`` is ``(H, W[, C])``, top row first."""
    o = oiio()
    a = _as_hwc(arr)
    h, w, c = a.shape
    fmt = "half" if half else "float"
    spec = o.ImageSpec(w, h, c, fmt)
    spec.attribute("compression", compression)
    names = {1: ["Y"], 2: ["Y", "A"], 3: ["R", "G", "B"], 4: ["R", "G", "B", "A"]}.get(c)
    if names:
        spec.channelnames = tuple(names)
    _write(path, spec, a)


def write_png(path, arr, bits=8):
    """Write a PNG from values in [0, 1] (clipped; no colour transform applied)."""
    o = oiio()
    a = np.clip(_as_hwc(arr), 0.0, 1.0)
    h, w, c = a.shape
    if bits == 8:
        data, fmt = np.round(a * 255.0).astype(np.uint8), "uint8"
    elif bits == 16:
        data, fmt = np.round(a * 65535.0).astype(np.uint16), "uint16"
    else:
        raise ValueError("bits must be 8 or 16")
    spec = o.ImageSpec(w, h, c, fmt)
    _write(path, spec, data)


def write(path, arr):
    """Write by extension: ``.exr`` (float32 linear) or ``.png`` (8-bit, clipped)."""
    ext = os.path.splitext(os.fspath(path))[1].lower()
    if ext == ".exr":
        write_exr(path, arr)
    elif ext == ".png":
        write_png(path, arr)
    else:
        raise ValueError(f"unsupported image extension {ext!r} (use .exr or .png)")
