"""One pixel of the fog's light computed in the compositor, from what the pixel's samples average to.

The Compositor method (``nodes/comp_fog.py``) evaluates the fog's light once per pixel from render
passes instead of in every material on every sample.  The formulas here are written against an ``m``
ops namespace (numpy or nodes, ``ops.py``), like ``shading.py``, plus the one table they read.

* **The picture's geometry**: a pixel's camera ray and a light's position in the picture, from the
  camera's image plane (``picture_position``); in EEVEE the pixel's surface point, from the Depth pass
  (``depth_surface``).
* **Peaks**: a pixel's mean of a glow c / r about a light r px away (Sun et al. 2005 Eq. 12 as the
  angle to the light gamma -> 0: every phase function gives 1 / r there) is not its centre's value.  Cycles
  averages a pixel's samples with its Blackman-Harris filter (x and y drawn independently, support
  +-1.5 px at the default width 1.5).  ``bake_filter`` tabulates E[1 / |delta + s|] over those offsets s;
  ``peak_excess`` turns it into the factor the pixel's glow is multiplied by.  Measured against
  converged pixel means (``benchmarks/compositor_fog/peaks.py``): 1.18 % relative RMSE over the pixels
  near lights, where the centre value alone is 8.5 % off.  EEVEE's film weighs every sample within its
  filter's radius (Render > Film > Filter Size) by a Gaussian of sigma 0.284 x the radius ("fitted to
  Blackman-Harris", Blender 5.0 ``eevee_film_shared.hh``: ``film_filter_weight``), the samples jittered over
  the whole pixel: its table is ``bake_eevee_filter``'s, the same layout (EEVEE_FILTER).
"""
import numpy as np

from ..core import tables
from ..physics.point import model

FILTER_WIDTH = 3.0    # px: Cycles' default Blackman-Harris filter, width 1.5, which its filter table doubles
FILTER_REACH = 6.0    # px: the filter table covers offsets |dx|, |dy| up to this
FILTER = tables.TableSpec("AnalyticFog Pixel Filter", 97, 97)
DEFAULT_FILTER_WIDTH = 1.5   # px: Cycles' default width and EEVEE's default radius, which the tables are baked for
EEVEE_FILTER = tables.TableSpec("AnalyticFog Pixel Filter EEVEE", 97, 97)
EEVEE_SIGMA = 0.284          # EEVEE's film filter: a Gaussian of this sigma times its radius, cut at the radius
EEVEE_NODES = 96             # midpoint nodes in rho and in phi of ``bake_eevee_filter``
DEPTH_AGREE = 0.02     # EEVEE: the Depth pass is the pixel's surface where within 2 % of the mean View Z Depth


def blackman_harris(x, width=FILTER_WIDTH):
    """Cycles' Blackman-Harris pixel filter (unnormalised) at offset x px from the pixel centre."""
    t = 2.0 * np.pi * (x / width + 0.5)
    value = 0.35875 - 0.48829 * np.cos(t) + 0.14128 * np.cos(2 * t) - 0.01168 * np.cos(3 * t)
    return np.where(np.abs(x) <= width / 2, value, 0.0)


def bake_filter():
    """E[1 / |delta + s|] (1/px) over the offsets s of a pixel's samples (x and y drawn independently from
    the filter, as Cycles does), for delta = (dx, dy) on FILTER's grid (0 .. FILTER_REACH px): the pixel's
    mean of a glow c / r about a light r px away, per unit c.  In polar coordinates about the light the
    1/r cancels the area element, so the integrand is smooth: midpoint rule in (rho, phi)."""
    g = np.linspace(0.0, FILTER_REACH, FILTER.width)
    nr, nphi, reach = 240, 256, FILTER_REACH * 1.5 + FILTER_WIDTH
    rho = (np.arange(nr) + 0.5) / nr * reach
    phi = (np.arange(nphi) + 0.5) / nphi * 2 * np.pi
    x1 = np.linspace(-FILTER_WIDTH / 2, FILTER_WIDTH / 2, 20001)
    w1 = blackman_harris(x1)
    norm = (np.sum(w1[1:] + w1[:-1]) * 0.5 * (x1[1] - x1[0])) ** 2
    cr, sr = rho[None, :] * np.cos(phi)[:, None], rho[None, :] * np.sin(phi)[:, None]
    wx = blackman_harris(cr[None] - g[:, None, None]).reshape(len(g), -1)
    wy = blackman_harris(sr[None] - g[:, None, None]).reshape(len(g), -1)
    return wy @ wx.T * ((reach / nr) * (2 * np.pi / nphi) / norm)


def eevee_gaussian(r, radius=DEFAULT_FILTER_WIDTH):
    """EEVEE's film filter (unnormalised) at distance r px from the pixel centre: exp(-r^2 / (2 sigma^2)),
    sigma = EEVEE_SIGMA radius, 0 beyond the radius."""
    sigma = EEVEE_SIGMA * radius
    return np.where(r <= radius, np.exp(-0.5 * (r / sigma) ** 2), 0.0)


def bake_eevee_filter():
    """EEVEE_FILTER: E[1 / |delta + s|] (1/px) over EEVEE's film filter (``eevee_gaussian`` of radius
    DEFAULT_FILTER_WIDTH, samples spread evenly over the plane), on FILTER's grid.  The filter is radial, so the
    mean depends on |delta| only: computed once per distinct |delta| in polar coordinates about the light
    (midpoint rule over where the filter is not 0: the ring |rho - |delta|| <= radius and, seen from a light
    beyond the radius, the angles within asin(radius / |delta|); half the circle by symmetry), divided by
    the filter's integral 2 pi sigma^2 (1 - exp(-radius^2 / (2 sigma^2)))."""
    radius, sigma = DEFAULT_FILTER_WIDTH, EEVEE_SIGMA * DEFAULT_FILTER_WIDTH
    k = np.arange(EEVEE_FILTER.width)
    squared = k[:, None] ** 2 + k[None, :] ** 2
    unique, where = np.unique(squared, return_inverse=True)
    t = (np.arange(EEVEE_NODES) + 0.5) / EEVEE_NODES
    norm = 2.0 * np.pi * sigma ** 2 * -np.expm1(-0.5 * (radius / sigma) ** 2)
    mean = np.empty(len(unique))
    for lo in range(0, len(unique), 256):   # (chunks of 256 distances: 256 x nodes^2 floats)
        d = (np.sqrt(unique[lo:lo + 256]) * (FILTER_REACH / (EEVEE_FILTER.width - 1)))[:, None, None]
        r0, r1 = np.maximum(d - radius, 0.0), d + radius
        a1 = np.where(d > radius, np.arcsin(np.minimum(radius / np.maximum(d, 1e-300), 1.0)), np.pi)
        rho, phi = r0 + (r1 - r0) * t[None, None, :], a1 * t[None, :, None]          # (D, 1, n), (D, n, 1)
        w = eevee_gaussian(np.sqrt(np.maximum(rho ** 2 + d ** 2 - 2.0 * rho * d * np.cos(phi), 0.0)), radius)
        mean[lo:lo + 256] = w.mean(axis=(1, 2)) * ((r1 - r0) * 2.0 * a1)[:, 0, 0] / norm
    return mean[where].reshape(squared.shape)


def filter_scale(filter_type, filter_width):
    """What pixel offsets are multiplied by to use the filter's table (``filter_table``; baked for a width
    or radius of DEFAULT_FILTER_WIDTH: the mean of c / r scales as 1 / width, so r A(delta) depends on
    delta / width only), or None where the peak factor does not apply: another filter (Gaussian pixel-centre
    sampling needs none), a width of 0.  ``filter_type``: Cycles' pixel filter type, or "EEVEE"."""
    if filter_type not in FILTERS or not filter_width > 0.0:
        return None
    return DEFAULT_FILTER_WIDTH / filter_width


def filter_table(filter_type):
    """(TableSpec, baker) of the peak factor's table for ``filter_type`` (``filter_scale``)."""
    return FILTERS[filter_type]


def peak_excess(m, pixel, light_pixel, spec=FILTER):
    """r A(delta) - 1, tapered to 0 over the table's last pixel: how much a pixel's mean glow exceeds its
    centre's near a light seen in the picture, where the glow is c / r (r px from the light; Sun et al. 2005
    Eq. 12 as gamma -> 0, any phase function).  ``pixel``, ``light_pixel``: positions in filter-scaled px
    (``filter_scale``); ``spec``: the filter's table (``filter_table``).  One per light and pixel:
    ``peak_factor`` applies it."""
    delta = pixel - light_pixel
    dx, dy = m.abs(m.dot(delta, (1.0, 0.0, 0.0))), m.abs(m.dot(delta, (0.0, 1.0, 0.0)))
    r = m.sqrt(dx * dx + dy * dy)
    a = m.table(spec, dx * (1.0 / FILTER_REACH), dy * (1.0 / FILTER_REACH))
    return m.clamp01(FILTER_REACH - r) * (r * a - 1.0)


def peak_factor(m, excess, along, d_vp):
    """The factor on a light's glow along a ray that ends at ``d_vp`` (m): 1 + ``peak_excess`` where the
    ray passes the light (``along``, the light's distance along the ray, before ``d_vp``), 1 where a surface
    hides it."""
    return 1.0 + m.less(along, d_vp) * excess


def picture_position(m, to_light, corner, across, up, size):
    """Where the point ``to_light`` (m, from the camera) appears in the picture, in the units of ``size``
    (a vector: its width and height, then 0), from the bottom-left corner; far outside (1e6) when behind the camera.
    ``corner``, ``across``, ``up``: the image plane (the bottom-left corner's direction and the vectors to
    the bottom-right and top-left corners), which is what the camera rays are built from too."""
    normal = m.cross(across, up)
    t = m.dot(corner, normal) / m.dot(to_light, normal)
    q = m.scale(to_light, t) - corner
    u = m.dot(q, across) * m.dot(size, (1.0, 0.0, 0.0)) / m.dot(across, across)
    v = m.dot(q, up) * m.dot(size, (0.0, 1.0, 0.0)) / m.dot(up, up)
    behind = m.less(t, 0.0) * 1e6
    return m.combine(u + behind, v + behind, 0.0)


def depth_surface(m, cam, ray, depth, mean_depth):
    """EEVEE's surface point of a pixel (the Compositor method): ``cam`` + ``ray`` (the pixel's ray at unit view
    depth) times a view depth: the Depth pass's ``depth`` (float32, the sample nearest the pixel's centre) where it
    is within DEPTH_AGREE of ``mean_depth`` (the samples' mean View Z Depth, a half-float AOV; 0 where no sample met
    a surface), else ``mean_depth``.

    The Depth pass is taken at most model.FAR: EEVEE wrote +inf there where nothing was drawn once its clip end /
    clip start passed about 2^25 (a 1 mm - 200 km camera, ``caveats.clip_note``; presumably the depth linearised
    as n f / (f - d (f - n)), where f - n rounds to f in float32 and the background's d = 1 divides by 0), and the
    choice, a Mix node (1 - c) a + c b, made 0 x inf = NaN of it: NaN in every term of that pixel's fog.  Finite
    depths pass unchanged."""
    depth = m.minimum(depth, model.FAR)
    agree = m.less(m.abs(depth - mean_depth), DEPTH_AGREE * mean_depth)
    return cam + m.scale(ray, m.select(agree, depth, mean_depth))


FILTERS = {"BLACKMAN_HARRIS": (FILTER, bake_filter), "EEVEE": (EEVEE_FILTER, bake_eevee_filter)}
