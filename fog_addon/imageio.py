"""Read and write EXR / PNG images as float32 numpy arrays, without Blender.

OpenImageIO ships inside the ``bpy`` wheel (``bpy/5.0/python/lib/python3.11/
site-packages``).  It is found relative to the ``bpy`` package *without
importing bpy*, so this module is cheap and has no Blender side effects.

Conventions:

* arrays are ``(height, width, channels)`` float32, **row 0 = top row** of the
  picture (OpenImageIO's order; Blender's ``Image.pixels`` is bottom-up);
* EXR holds linear scene values as written by the renderer;
* PNG is display-referred 8-bit (or 16-bit) ``[0, 1]``; reading returns the
  values divided by the type's maximum, with no colour-space conversion
  (``srgb_to_linear`` decodes them when linear light is wanted);
* a multilayer EXR names each channel ``<layer>.<pass>.<channel>`` (Blender 5.0:
  "ViewLayer.Combined.R", "ViewLayer.Depth.Z") and Blender 5.0 writes it as a
  multi-part file, one part (OIIO subimage) per pass; ``channels`` lists every
  channel of every part and ``read_channels`` reads chosen ones by name.
"""
import importlib.util
import os
import pathlib
import sys
from typing import NamedTuple

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


def _open(path):
    """An OIIO ImageInput of ``path``; FileNotFoundError or IOError saying why not."""
    o = oiio()
    if not os.path.isfile(path):
        raise FileNotFoundError(f"no such image: {path}")
    inp = o.ImageInput.open(path)
    if inp is None:
        raise IOError(f"cannot open image {path}: {o.geterror()}")
    return inp


def read(path, subimage=0, channels=None):
    """Read an image as float32 ``(H, W, C)``; top row first.

    ``channels``: optional number of leading channels to keep (e.g. 3 for RGB).
    For multi-part EXRs, ``subimage`` selects the part.
    """
    path = os.fspath(path)
    inp = _open(path)
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
    path = os.fspath(path)
    inp = _open(path)
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


class Channel(NamedTuple):
    """One channel of an image file: its full ``name`` ("R", "Z", "ViewLayer.Depth.Z"), the ``subimage`` (EXR
    part) and ``index`` within it that hold it, its stored ``format`` ("uint8", "half", "float", ...), whether
    that is a floating-point type (``is_float``: integer types hold display-referred levels, not scene values),
    and the colour space OIIO reports for its part ("sRGB" for a PNG or JPEG; "" when the file says none)."""
    name: str
    subimage: int
    index: int
    format: str
    is_float: bool
    colorspace: str

    @property
    def pass_name(self):
        """The name without its last component: "ViewLayer.Depth" for "ViewLayer.Depth.Z", "" for "R"."""
        return self.name.rpartition(".")[0]

    @property
    def suffix(self):
        """The last component of the name: "Z" for "ViewLayer.Depth.Z"."""
        return self.name.rpartition(".")[2]


def channels(path):
    """Every channel of every part (subimage) of ``path``, in file order, as ``Channel``s; nothing is read but
    the headers."""
    o = oiio()
    path = os.fspath(path)
    inp = _open(path)
    out, k = [], 0
    floats = (o.HALF, o.FLOAT, o.DOUBLE)
    try:
        while inp.seek_subimage(k, 0):
            spec = inp.spec()
            cs = spec.getattribute("oiio:ColorSpace") or ""
            for i in range(spec.nchannels):
                fmt = spec.channelformat(i)
                name = spec.channelnames[i] if i < len(spec.channelnames) else f"channel{i}"
                out.append(Channel(name, k, i, str(fmt), fmt.basetype in floats, str(cs)))
            k += 1
    finally:
        inp.close()
    return out


def read_channels(path, chans):
    """The ``Channel``s ``chans`` of ``path`` (from ``channels``) as float32 ``(H, W, len(chans))`` in that order,
    top row first; integer types are divided by their maximum (as ``read``).  Each part is read once, only the
    range of channels asked of it."""
    path = os.fspath(path)
    inp = _open(path)
    planes = {}
    try:
        for sub in sorted({c.subimage for c in chans}):
            if not inp.seek_subimage(sub, 0):
                raise IOError(f"{path}: no subimage {sub}")
            spec = inp.spec()
            idx = [c.index for c in chans if c.subimage == sub]
            lo, hi = min(idx), max(idx) + 1
            data = inp.read_image(sub, 0, lo, hi, "float")
            if data is None:
                raise IOError(f"cannot read {path}: {inp.geterror()}")
            arr = np.asarray(data, np.float32).reshape(spec.height, spec.width, hi - lo)
            for i in idx:
                planes[(sub, i)] = arr[..., i - lo]
    finally:
        inp.close()
    shapes = {planes[(c.subimage, c.index)].shape for c in chans}
    if len(shapes) != 1:
        raise IOError(f"{path}: the channels {', '.join(c.name for c in chans)} differ in size ({sorted(shapes)})")
    return np.ascontiguousarray(np.stack([planes[(c.subimage, c.index)] for c in chans], axis=-1))


def srgb_to_linear(v):
    """Linear light from sRGB-encoded values in [0, 1] (IEC 61966-2-1: v / 12.92 up to 0.04045, else
    ((v + 0.055) / 1.055)^2.4): what an 8-bit PNG or JPEG stores is this curve of the light, not the light."""
    v = np.asarray(v, np.float32)
    return np.where(v <= 0.04045, v / 12.92, ((np.maximum(v, 0.04045) + 0.055) / 1.055) ** 2.4).astype(np.float32)


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


def write_layers(path, layers, half=False):
    """A multi-part EXR as Blender 5.0 writes a multilayer one: ``layers`` is ``{part name: (array (H, W[, C]),
    channel suffixes)}``, e.g. ``{"ViewLayer.Combined": (rgba, "RGBA"), "ViewLayer.Depth": (z, "Z")}``; each part
    is named as given and its channels "<part>.<suffix>" ("ViewLayer.Depth.Z").  The inverse of ``read_layers``."""
    o = oiio()
    path = os.fspath(path)
    specs, datas = [], []
    for name, (arr, suffixes) in layers.items():
        a = _as_hwc(arr)
        h, w, c = a.shape
        if len(suffixes) != c:
            raise ValueError(f"part {name!r} has {c} channels but {len(suffixes)} names")
        spec = o.ImageSpec(w, h, c, "half" if half else "float")
        spec.channelnames = tuple(f"{name}.{x}" for x in suffixes)
        spec.attribute("name", name)
        spec.attribute("compression", "zip")
        specs.append(spec)
        datas.append(a)
    out = o.ImageOutput.create(path)
    if out is None:
        raise IOError(f"cannot create {path}: {o.geterror()}")
    try:
        if not out.open(path, specs):
            raise IOError(f"cannot open {path} for writing: {out.geterror()}")
        for k, (spec, a) in enumerate(zip(specs, datas)):
            if k and not out.open(path, spec, "AppendSubimage"):
                raise IOError(f"cannot add part {k} to {path}: {out.geterror()}")
            if not out.write_image(a):
                raise IOError(f"cannot write {path}: {out.geterror()}")
    finally:
        out.close()


def add_parts(dest, source, prefix):
    """Add every part of the multilayer EXR ``source`` to the multilayer EXR ``dest`` (rewritten), each named
    "<prefix>.<its name>": the Compositor method's fog passes ("Fog Light", written by a File Output node) into the
    render's file ("ViewLayer.Fog Light", beside "ViewLayer.Combined").  A part of ``dest`` of the same name is
    replaced where it stands (the view layer's own Fog Transmittance AOV, the materials' alone, by the compositor's,
    which holds the factor it puts on the render too).  Reads multi-part files: call it from a process that has not
    rendered (``read_layers``)."""
    parts = {}
    for path, pre in ((dest, ""), (source, f"{prefix}.")):
        suffixes = {}
        for c in channels(path):
            suffixes.setdefault(c.subimage, []).append(c.suffix)
        for k, (name, arr) in enumerate(read_layers(path).items()):
            parts[pre + name] = (arr, suffixes[k])
    write_layers(dest, parts)


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


if __name__ == "__main__":   # python imageio.py add-parts DEST SOURCE PREFIX (``render.add_compositor_passes``)
    if len(sys.argv) != 5 or sys.argv[1] != "add-parts":
        sys.exit("usage: python imageio.py add-parts DEST.exr SOURCE.exr PREFIX")
    add_parts(*sys.argv[2:])
