"""Tables as packed 32-bit float images (one shared copy per table)."""
import bpy
import numpy as np

from ..precompute.core import fingerprint, table_cache
from ..precompute.model import bakers
from . import owned

VERSION_KEY = "analytic_fog_table_version"   # on each image: the fingerprint of the code that baked it


def table_version(spec):
    """The package's fingerprint with ``spec``: the image of a table whose baker, layout or packing (here)
    changed is made again (``fingerprint``'s docstring says why the whole package)."""
    return fingerprint.package_fingerprint(spec)


def table_image(spec, bake=None, g=None):
    """The image holding ``spec``'s table, baked and packed if missing or stale.

    A one-channel table's values go to all four channels; the node tree reads Alpha, an exact float
    output (CHANNEL_PACKED keeps it independent of RGB).  A table of ``spec.channels`` = 4 fills RGBA.
    ``use_half_precision`` is off or EEVEE would upload half floats.  The array is its kind's
    (``bakers.table_array``: the table cache, and the arrays this process already holds; ``g``: the fog's
    anisotropy, for the tables every fog reads), or ``bake()``'s if given (a baker of ``precompute/`` is read
    from the table cache if there: ``table_cache.cached_bake``).
    """
    version = table_version(spec)
    img = bpy.data.images.get(spec.name)
    if (img is not None and img.get(VERSION_KEY) == version
            and tuple(img.size) == (spec.width, spec.height) and img.packed_file is not None):
        return img
    if img is not None:
        bpy.data.images.remove(img)
    if bake is None:
        arr = bakers.table_array(spec, spec.g if g is None else g)
    else:
        arr = table_cache.cached_bake(spec, bake)   # from the table cache if there
    arr = np.asarray(arr, np.float32)
    return _fill(_new_image(spec), spec, arr)


def _new_image(spec):
    """A new float image for ``spec``'s table: non-colour data, channel-packed alpha, full precision, kept."""
    img = bpy.data.images.new(spec.name, spec.width, spec.height, alpha=True, float_buffer=True, is_data=True)
    img.colorspace_settings.name = "Non-Color"
    img.alpha_mode = "CHANNEL_PACKED"
    img.use_half_precision = False
    img.use_fake_user = True
    return img


def _fill(img, spec, arr):
    """Write ``spec``'s table ``arr`` (float32, (height, width) or (height, width, 4)) into ``img`` and pack it."""
    shape = (spec.height, spec.width) + ((spec.channels,) if spec.channels > 1 else ())
    assert arr.shape == shape and spec.channels in (1, 4), (arr.shape, spec)
    img.pixels.foreach_set((arr if spec.channels == 4 else np.repeat(arr[..., None], 4, axis=-1)).ravel())
    img.update()
    img.pack()
    img[VERSION_KEY] = table_version(spec)
    return img


BAKED_FOR_KEY = "analytic_fog_baked_for"   # on a table re-baked in place (``keyed_image``): what its texels hold


def keyed_image(spec, key, bake):
    """The image of ``spec``'s table holding the texels of ``key`` (a string: what they are baked for), re-baked
    in place when they hold another's: the node trees that read it keep the same image, so a new camera height
    needs no rebuild.  ``bake()`` returns the array (not cached: it is baked for one scene's camera)."""
    key = f"{table_version(spec)}:{key}"
    img = bpy.data.images.get(spec.name)
    sized = img is not None and tuple(img.size) == (spec.width, spec.height)
    if sized and img.get(BAKED_FOR_KEY) == key:
        return img
    arr = np.asarray(bake(), np.float32)
    if not sized:
        if img is not None:
            bpy.data.images.remove(img)
        img = _new_image(spec)
    _fill(img, spec, arr)[BAKED_FOR_KEY] = key
    return img


def all_table_images(g=0.0, extra=()):
    """{TableSpec.name: image} for every table the node groups use with Henyey-Greenstein anisotropy g.  A
    missing or stale image takes its array from ``bakers.table_array`` (the table cache, and the arrays this
    process already holds for the predictor).  ``extra``: the specs of other tables too (the multiply
    scattered field's)."""
    specs = [spec for spec, _ in bakers.bakers(g).values()] + list(extra)
    return {spec.name: table_image(spec, g=float(g)) for spec in specs}


def table_names():
    """The tables' image names: the isotropic ones and every other table image in the file (another g's)."""
    names = list(bakers.bakers())
    return names + sorted({owned.base_name(img.name) for img in bpy.data.images
                           if VERSION_KEY in img} - set(names))
