"""A light's glow along any ray segment, over only the parts of it the light reaches.

The glow (airlight) of a light of unit radiant intensity along a segment (origin o in m, unit
direction u, length L in m; L = inf for a ray to the sky), as it arrives at the segment's origin, is
Sun et al. 2005 Eq. 5 with the visibility function H of Dobashi, Yamamoto and Nishita 2002 ("Interactive
rendering of atmospheric scattering effects using graphics hardware", Eq. 2: H(t) = 1 where the light
reaches the point at t, 0 where something stands between them):

    G = int_0^L H(t) f(t) w(t) beta e^{-beta (t + d(t))} / (4 pi d(t)^2) dt     [1/m^2]

with beta the extinction (= scattering) coefficient in 1/m, d(t) the distance in m from the point
o + t u to the light, w the Henyey-Greenstein weight 4 pi p_HG (1 for g = 0, ``model.hg_weight``) and f
Blender's spot factor (1 for a point light, ``spot.spot_falloff``).  Times the light's intensity I0 in
W/sr (and the fog's albedo) it is a radiance in W/(m^2 sr).

**Visibility: the kernel's input.**  H is given as K lit intervals [t0_k, t1_k], in m along the segment
from its origin: ``lit``, a tuple of K pairs (t0_k, t1_k), the kernel's 2 K scalar inputs t0_0, t1_0,
t0_1, t1_1, ... (K fixed when the shader is built; ``lit_from_array`` makes them from a numpy array of
shape (..., K, 2)).  A shadow source (shadow maps, OSL ``trace()``) fills them.  An interval with
t0 >= t1 is empty (a slot the source left unused); ends may be negative, beyond L or infinite.
Intervals may come in any order and may overlap: the kernel clips them to [0, L], sorts them by their
starts (a fixed sorting network, skipped with ``ordered=True`` when the source gives its non-empty
intervals in order of their starts) and merges them (each starts no earlier than the furthest end
before it), so H is the indicator of their union (``lit_pieces``).  ``lit=None`` is H = 1: today's
kernels, bit for bit.

**The glow over the lit parts** is a sum of differences of one primitive: Biri 2006 ("Real time single
scattering effects") §III.D, Eq. 14, where the lit pieces OA and BP of a view ray give
Gamma(gamma_P) - Gamma(gamma_B) + Gamma(gamma_A) - Gamma(gamma_O).  Our primitive is the normalised
tail K(Q) of ``model.airlight_tail`` (the airlight of any sub-segment, exact): over a lit piece [a, b]
the glow is e^{-beta a} times ``model.airlight_segment`` seen from the point at a,
(beta / 2 pi) e^{-beta (a + d(a))} (K(Q_a) - e^{-beta (Q_b - Q_a)} K(Q_b)) (1/m^2, Q in m as in
``model``), with its Gauss-Legendre fallback where a short piece would cancel (``spot._inner``).  A spot
light clips the segment to its cone first (``spot.cone_interval``): the inner cone's piece takes the
point light's primitive, the one or two blend rims the rim quadrature (``spot._rim``); each lit piece is
intersected with each of those, so shadow and cone compose.

**Extinction before the segment belongs to the caller.**  The kernel returns what arrives at the
segment's origin, with e^{-beta t} measured from there.  A segment that starts at a mirror or a glass
pane s0 metres from the camera is seen through e^{-beta s0} (``model.transmittance``) and the pane's or
the mirror's own weight: the caller multiplies, as it already does for the radiance of the surface at
the segment's end.  That keeps one kernel for every segment of a path (the camera is one origin among
others), and it is how the fog composes vertex by vertex (Sun et al. 2005 Eq. 19 applied recursively):
L(origin) = I0 G(segment) + e^{-beta L} L(end), the fogged shading at a pane multiplying what comes
through it by the transmittance of the segment before it.  With e^{-beta s0} inside the kernel it
would be counted twice wherever the renderer carries the path's throughput (Cycles through glass).

Every function takes an ops namespace ``m`` first (``ops.py``): the same source builds as shader nodes
and as OSL (``quadrature=True``: OSL reads no tables), and runs in numpy.
"""
import functools
from typing import Any, NamedTuple

from fog_addon.precompute.physics.point import model
from fog_addon.precompute.physics.spot import spot


class Segment(NamedTuple):
    """A ray segment in world space: from the camera, or from a mirror or a glass pane."""
    origin: Any       # m, world position where the segment starts
    direction: Any    # unit world vector
    length: Any       # m; math.inf (or anything >= model.FAR) for a ray that meets no surface


def lit_from_array(array):
    """The ``Lit`` tuple of K pairs from a numpy array of shape (..., K, 2) (t0, t1 in m on the last axis)."""
    return tuple((array[..., k, 0], array[..., k, 1]) for k in range(array.shape[-2]))


def _clamp(m, t, end):
    """t clamped to [0, end] (min and max only: an infinite t stays out of every select)."""
    return m.minimum(m.maximum(t, 0.0), end)


def _compare_swap(m, a, b):
    """(a, b) in order of their starts: pairs (t0, t1), exchanged by selects where b starts first."""
    swap = m.less(b[0], a[0])
    return ((m.select(swap, b[0], a[0]), m.select(swap, b[1], a[1])),
            (m.select(swap, a[0], b[0]), m.select(swap, a[1], b[1])))


def lit_pieces(m, lit, end, ordered=False):
    """Disjoint pieces [lo_k, hi_k] (empty where lo_k >= hi_k) in [0, ``end``] whose union is the
    union of the lit intervals ``lit`` (K pairs (t0, t1), m) clipped to [0, end]: the intervals clipped,
    sorted by their starts (a bubble network of K (K - 1) / 2 compare-swaps, none if ``ordered``), then
    each starting no earlier than the furthest end of the non-empty ones before it."""
    pairs = [(_clamp(m, t0, end), _clamp(m, t1, end)) for t0, t1 in lit]
    if not ordered:
        for top in range(len(pairs) - 1, 0, -1):
            for k in range(top):
                pairs[k], pairs[k + 1] = _compare_swap(m, pairs[k], pairs[k + 1])
    pieces, reach = [], 0.0
    for t0, t1 in pairs:
        lo = m.maximum(t0, reach)
        pieces.append((lo, t1))
        reach = m.maximum(reach, m.select(m.less(t0, t1), t1, 0.0))   # an empty interval reaches nothing
    return pieces


def _within(m, lo, hi, a, b):
    """The piece [lo, hi] intersected with [a, b]: empty where its start >= its end (as either is), where the
    piece kernels (``spot._inner``, ``spot._rim``) give 0."""
    return m.maximum(lo, a), m.minimum(hi, b)


def _inner_part(inner):
    """The point light's piece kernel as ``m.group`` name and function (the spot's inner-cone group)."""
    return spot._parts(inner, 0.0, spot.RIM_NODES)[0]


def point_lit_glow(m, beta, d_sv, along, h, seg_length, *lit, inner=model.airlight_segment, ordered=False):
    """Glow per unit intensity (1/m^2) of a point light over the lit parts of a segment (module docstring).

    (d_sv, along, h): the segment's geometry about the light from its origin (``model.ray_light_geometry``,
    m); seg_length: m (clipped at model.FAR); lit: K pairs (t0, t1) in m (``lit_pieces``); inner: the point
    light's airlight kernel over a piece, its anisotropy bound (``model.airlight_segment`` or
    ``model.airlight_quadrature``)."""
    fn = functools.partial(_point_lit_glow, inner=inner, ordered=bool(ordered))
    return m.group(f"Lit Glow [{len(lit)} intervals, {spot._kernel_name(fn)}]", fn, beta, d_sv, along, h, seg_length,
                   *(t for pair in lit for t in pair))


def _point_lit_glow(m, beta, d_sv, along, h, seg_length, *flat, inner, ordered):
    name, piece = _inner_part(inner)
    total = 0.0
    for lo, hi in lit_pieces(m, zip(flat[::2], flat[1::2]), m.minimum(seg_length, model.FAR), ordered):
        total = total + m.group(name, piece, beta, along, h, lo, hi)
    return total


def spot_lit_glow(m, beta, d_sv, along, h, seg_length, px, py, pz, dx, dy, dz, cos_half, blend, *lit,
                  inner=model.airlight_segment, g=0.0, rim_nodes=spot.RIM_NODES, ordered=False):
    """Glow per unit intensity (1/m^2) of a spot light over the lit parts of a segment: each lit piece
    (``lit_pieces``) intersected with the ray's pieces in the cone (``spot._clip``): the inner cone's by
    ``inner`` (the point light's kernel), the blend rims by the rim quadrature of ``rim_nodes`` points and
    anisotropy g.  Arguments as ``point_lit_glow`` and ``spot.airlight`` (the ray in the light's space,
    cos_half, blend)."""
    fn = functools.partial(_spot_lit_glow, inner=inner, g=float(g), rim_nodes=int(rim_nodes), ordered=bool(ordered))
    return m.group(f"Spot Lit Glow [{len(lit)} intervals, {spot._kernel_name(fn)}]", fn, beta, d_sv, along, h,
                   seg_length, px, py, pz, dx, dy, dz, cos_half, blend, *(t for pair in lit for t in pair))


def _spot_lit_glow(m, beta, d_sv, along, h, seg_length, px, py, pz, dx, dy, dz, cos_half, blend, *flat, inner, g,
                   rim_nodes, ordered):
    ray = (px, py, pz, dx, dy, dz)
    end = m.minimum(seg_length, model.FAR)
    c = spot._clip(m, ray, cos_half, blend, end)
    (inner_name, inner_fn), (rim_name, rim) = spot._parts(inner, g, rim_nodes)
    rim_args = (beta, d_sv, along, h, *spot._ray_quadratic(m, *ray))
    # the cone's pieces: [lo_in, hi_in] inner, rims [lo_out, first_end] and [hi_in, hi_out] (empty when the
    # ray misses the inner cone: then the first rim is the whole outer interval)
    second_start = m.select(c.empty_in, c.hi_out, c.hi_in)
    total = 0.0
    for lo, hi in lit_pieces(m, zip(flat[::2], flat[1::2]), end, ordered):
        total = total + m.group(inner_name, inner_fn, beta, along, h, *_within(m, lo, hi, c.lo_in, c.hi_in))
        total = total + m.group(rim_name, rim, *rim_args, *_within(m, lo, hi, c.lo_out, c.first_end), cos_half,
                                c.cos_end)
        total = total + m.group(rim_name, rim, *rim_args, *_within(m, lo, hi, second_start, c.hi_out), cos_half,
                                c.cos_end)
    return total


def _is_sky(length):
    """True if ``length`` is a build-time constant ray to the sky (then the background kernels apply)."""
    return isinstance(length, (int, float)) and length >= model.FAR


def glow(m, beta, segment, position, spot_light=None, lit=None, *, g=0.0, quadrature=False,
         rim_nodes=spot.RIM_NODES, ordered=False):
    """Glow per unit intensity, 1/m^2, of one light over a ``Segment`` (module docstring): Sun et al. 2005
    Eq. 5 with the visibility H of the lit intervals ``lit`` (Dobashi et al. 2002 Eq. 2), extinction from
    the segment's origin (the caller multiplies by the transmittance before it).

    beta: 1/m; position: the light's world position (m); spot_light: None for a point light, else its cone
    (``shading.Spot``: rows of the inverse 3x3 world matrix, cos_half, blend); lit: None (all lit: today's
    kernels, ``model.airlight_segment`` / ``model.airlight_background`` / ``spot.airlight``, bit for bit)
    or K pairs (t0, t1) in m along the segment (``lit_pieces``); g: Henyey-Greenstein anisotropy (a Python
    float, tables baked for it); quadrature: the OSL method's table-free kernels instead of the tables;
    rim_nodes: a spot rim's quadrature points (``spot.RIM_LADDER``); ordered: the non-empty intervals come
    in order of their starts (no sorting network).  A length that is the Python float inf (a sky ray
    known when the shader is built) takes the background kernel; lengths in a value are clipped at
    model.FAR (the same glow to rounding).  A segment that starts on a spot light (closer than
    model.MIN_DISTANCE) is taken to start MIN_DISTANCE from it: finite where ``spot.airlight`` gives NaN.
    """
    d_sv, along, h = model.ray_light_geometry(m, segment.origin, segment.direction, position)
    sky = _is_sky(segment.length)
    length = model.FAR if sky else m.minimum(segment.length, model.FAR)
    if quadrature:
        inner, background = model.airlight_quadrature, model.airlight_quadrature_background
    else:
        inner, background = model.airlight_segment, model.airlight_background
    inner, background = (functools.partial(k, g=g) if g else k for k in (inner, background))
    if spot_light is None:
        if lit is not None:
            return point_lit_glow(m, beta, d_sv, along, h, length, *lit, inner=inner, ordered=ordered)
        return background(m, beta, d_sv, along, h) if sky else inner(m, beta, d_sv, along, h, length)
    # a spot's rim divides by the distance from the origin to the light's line, clamped to MIN_ANGLE d_sv: an
    # origin on the light itself (d_sv = 0) is taken MIN_DISTANCE away (no change at d_sv >= MIN_DISTANCE)
    d_sv = m.maximum(d_sv, model.MIN_DISTANCE)
    ray = spot.light_space_ray(m, spot_light.rows, segment.origin, segment.direction, position)
    if lit is not None:
        return spot_lit_glow(m, beta, d_sv, along, h, length, *ray, spot_light.cos_half, spot_light.blend, *lit,
                             inner=inner, g=g, rim_nodes=rim_nodes, ordered=ordered)
    return spot.airlight(m, beta, d_sv, along, h, length, *ray, spot_light.cos_half, spot_light.blend, inner=inner,
                         g=g, rim_nodes=rim_nodes)

