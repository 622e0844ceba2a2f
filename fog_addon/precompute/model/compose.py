"""The composer: a pixel's fog from its terms, written once for every backend (Sun et al. 2005 Eq. 19 and 12).

A camera ray that meets a surface at D_vp sees (Sun et al. 2005 Eq. 19)

    L = T L_surface + (the glows along the ray) + T (the fog light the surface reflects),

T = e^{-beta D_vp} (through a fog layer, the layer's and the air's transmittance); a ray that meets no surface sees
the glows along the whole ray (Eq. 12: to infinity, or to where it leaves a fog layer) and the sky through the fog.
A pixel whose rays meet a surface over a fraction ``coverage`` of its area and go on to the sky over the rest (the
Compositor's pixel, its AOVs averaged over its samples) takes ``coverage`` of the first and 1 - ``coverage`` of the
second.

Each source of fog light (the lamps, a fog layer's sun and sky, glowing objects) evaluates its kernels where that is
cheapest (a lamp in its per-light group, the emitters' glows by Blur nodes) and hands the composer its values as
terms (``Term``): what a value is (its kind), where along the pixel's ray it is taken (``at``) and whose it is (its
``Source``).  ``compose`` applies each term's gate and sums the terms, in this one place:

* a GLOW at SURFACE (Eq. 11, the glow up to D_vp) counts where the pixel sees its surface, a GLOW at SKY (Eq. 12)
  where it sees the sky, a GLOW along the RAY (its kernel chose where the ray ends: a daylight glow with air, the
  emitters' blurred glows) over the whole pixel;
* REFLECTED fog light (Eq. 17-18, leaving the surface; the fog light of a segment past glass or a mirror, which the
  pane or the mirror sends on to the camera) is dimmed by its source's DIMMING at SURFACE (Eq. 19's T);
* a SHARE (a shaft's lit share; a 0/1 gate) multiplies its source's glows where it is taken;
* a LAYER_END (1 where the ray leaves a fog layer before any surface) makes the glow to the sky the glow along the
  ray, which the kernel ended at the layer's top (``sunlight.lamp_glow_span``); a SHARE at SKY then keeps it to the
  rays that meet the layer at all;
* the RENDER's pixel (the surface's own shading, the sky behind the fog) takes the RENDER source's DIMMINGs: at
  SURFACE (the layer's dimming of the sun's and the sky's direct light, the camera segment's transmittance where the
  materials applied a stand-in), at SKY (the sky seen through the layer).

A source's kernels give light either per unit albedo (Sun et al.'s: the lamps', the emitters'; ``Source.per_albedo``,
the fog's albedo is applied once to their composed sum) or with their albedos in (the daylight kernels', which carry
the layer's and the air's).  Sources are summed in the order of their first term, each source's parts in the order
written here: the order of a builder's terms fixes the arithmetic, to the rounding.

Every backend runs it through ``m``: the Compositor's per-pixel sum (``nodes/comp_fog.py``, ``CompOps``), the
materials' and the error predictor's Eq. 19 (``shading.surface_light``, ``shading.pixel_light``), numpy in the tests.
The composition is linear in each source's light, so any subset of the terms composes on its own (the predictor
judges what a ladder step drops).  A value is RGB or grey; in numpy an RGB value's last axis has length 3, so a grey
array's shape must not end in 3 (the predictor's are (P, 1)).
"""
from typing import Any, NamedTuple

import numpy as np

from . import rungs

# What a term's value is (``Term.kind``); the first three are the lamps' ``rungs.OUTPUTS`` kinds
GLOW = rungs.GLOW             # RGB radiance gathered along the ray, W/(m^2 sr): added as it is
REFLECTED = rungs.REFLECTED   # RGB radiance leaving the surface point (reflected, or passed on by glass or a
#                               mirror): dimmed on its way by its source's DIMMING
DIMMING = rungs.DIMMING       # grey or RGB factor on the light its source leaves the surface (or the sky) with
SHARE = "share"               # grey factor in [0, 1] on its source's glows taken at the same place
LAYER_END = "layer end"       # grey 0/1: 1 where the ray leaves a fog layer: the glow to the sky ends there

# Where along the pixel's ray a term is taken (``Term.at``)
SURFACE, SKY = rungs.SURFACE_POINT, rungs.SKY   # the ray to the pixel's surface; the ray to the sky
RAY = "ray"                                     # the pixel's ray to whatever it meets (its kernel chose)

PLACES = {GLOW: (SURFACE, SKY, RAY), REFLECTED: (SURFACE,), DIMMING: (SURFACE, SKY), SHARE: (SURFACE, SKY, RAY),
          LAYER_END: (SKY,)}   # each kind's places


class Source(NamedTuple):
    """Whose light a term is."""
    name: str
    per_albedo: bool   # its kernels give light per unit albedo: the composer multiplies their sum by the fog's


LAMPS = Source("lamps", True)               # point, spot and area lights (``shading.shade_point``, ``glow_pair``)
DAYLIGHT = Source("sun and sky", False)     # a fog layer's sun and sky (``daylight_terms.pixel_terms``)
EMITTERS = Source("glowing objects", True)  # the emitters' glows (``emitter_glow.py``)
SEGMENTS = Source("segments past glass", True)   # the glows of the segments past glass panes and sharp mirrors
#                                                  (``shading.segment_terms``, ``nodes/glass_tails.py``)
RENDER = Source("render", False)            # the render's own pixel: only DIMMINGs, the factor ``compose`` returns


class Term(NamedTuple):
    """One value a source hands the composer."""
    kind: str       # GLOW, REFLECTED, DIMMING, SHARE or LAYER_END
    at: str         # SURFACE, SKY or RAY (PLACES[kind])
    source: Source
    value: Any      # a backend value (``m``'s), already evaluated by the source's kernels


class Pixel(NamedTuple):
    """What the composer takes of the pixel itself."""
    coverage: Any   # grey: the fraction of the pixel's area whose rays meet a surface (0: the sky, 1: a surface)
    albedo: Any     # RGB: the fog's single-scattering albedo (``Source.per_albedo``)


class Composed(NamedTuple):
    """A pixel's fog (``compose``): its light is added to the render's pixel times its factor (``dimmed``)."""
    light: Any      # RGB, W/(m^2 sr); None if no term carries light
    factor: Any     # grey or RGB factor on the render's pixel; None if the render is taken as it is


def compose(m, pixel, terms):
    """A pixel's fog from its ``terms`` (``Term``): Composed(the fog light, the factor on the render's pixel).

    Each source's light is ``source_light`` (Eq. 19 over ``pixel.coverage``, Eq. 12 over the rest), times the fog's
    albedo for a source whose kernels are per unit albedo; the lights are summed over the sources.  The factor is
    coverage times the product of the RENDER's DIMMINGs at SURFACE plus (1 - coverage) times that of its DIMMINGs at
    SKY (a missing product is 1): Eq. 19's T L_surface and the sky seen through the fog, where the render's light was
    not dimmed by the materials already."""
    for t in terms:   # the render's terms are its dimmings; a source of light dims only what leaves the surface
        if t.at not in PLACES.get(t.kind, ()) or (
                t.kind != DIMMING if t.source == RENDER else (t.kind == DIMMING and t.at != SURFACE)):
            raise ValueError(f"the composer takes no {t.kind} at {t.at} from {t.source.name}")
    light = None
    for source in dict.fromkeys(t.source for t in terms if t.source != RENDER):
        part = source_light(m, pixel.coverage, [t for t in terms if t.source == source])
        if part is None:
            continue
        if source.per_albedo:
            part = pixel.albedo * part
        light = part if light is None else light + part
    own = [t for t in terms if t.source == RENDER]
    surface, sky = (_values(own, DIMMING, at) for at in (SURFACE, SKY))
    factor = None
    if surface or sky:
        factor = (_times(m, _product(m, surface), pixel.coverage)
                  + _times(m, _product(m, sky), 1.0 - pixel.coverage))
    return Composed(light, factor)


def source_light(m, coverage, terms):
    """One source's light at a pixel before its albedo (RGB; None if its terms carry none): ``coverage`` times its
    light at the surface (``surface_light``, Eq. 19's fog light) plus (1 - ``coverage``) times its glow to the sky
    (Eq. 12; bounded by its LAYER_END, times its SHARE at SKY) plus its glow along the RAY (times its SHARE there)."""
    surface = surface_light(m, terms)
    sky = _values(terms, GLOW, SKY)
    sky = total(sky) if sky else None
    if sky is not None:
        along = _values(terms, GLOW, SURFACE)
        for end in _values(terms, LAYER_END, SKY):   # the ray leaves the layer: its glow ends at the top
            if along:
                sky = m.scale(total(along), end) + m.scale(sky, 1.0 - end)
        sky = _shared(m, sky, _values(terms, SHARE, SKY))
    ray = _values(terms, GLOW, RAY)
    parts = (_weighted(m, surface, coverage) + _weighted(m, sky, 1.0 - coverage)
             + ([_shared(m, total(ray), _values(terms, SHARE, RAY))] if ray else []))
    return total(parts) if parts else None


def _weighted(m, value, weight):
    """[``value`` times a coverage ``weight``], or [] for no value; a Python weight of 1 (a surface ray, a sky ray)
    takes the value as it is, one of 0 leaves it out."""
    if value is None or (isinstance(weight, (int, float)) and weight == 0.0):
        return []
    return [value if isinstance(weight, (int, float)) and weight == 1.0 else m.scale(value, weight)]


def surface_light(m, terms):
    """Eq. 19's fog light at the pixel's surface, W/(m^2 sr) (RGB; None if the terms hold none there): the glows
    along the ray to the surface (times their SHAREs) plus the fog light the surface reflects times its DIMMINGs at
    SURFACE, Eq. 19's T on its way to the camera (a source with REFLECTED light must give its T)."""
    glow = _values(terms, GLOW, SURFACE)
    reflected = _values(terms, REFLECTED, SURFACE)
    parts = [_shared(m, total(glow), _values(terms, SHARE, SURFACE))] if glow else []
    if reflected:
        dims = _values(terms, DIMMING, SURFACE)
        if not dims:
            raise ValueError("reflected fog light needs its DIMMING at the surface (Eq. 19's T)")
        parts.append(_times(m, total(reflected), _product(m, dims)))
    return total(parts) if parts else None


def output_terms(values, source=LAMPS):
    """Terms of ``source`` from a lamp's (or lamps' summed) quantities of ``rungs.OUTPUTS``: ``values`` a dict or
    pairs Output -> value, None values left out; the ones that carry light (GLOW, REFLECTED) at their place (the
    EEVEE materials' dimming and weight of direct light, and the spots' gates, are not the pixel's)."""
    pairs = values.items() if isinstance(values, dict) else values
    return [Term(o.kind, o.at, source, v) for o, v in pairs if v is not None and o.kind in (GLOW, REFLECTED)]


def dimmed(m, image, factor):
    """The render's pixel (RGB) times ``Composed.factor`` (grey or RGB; None: the pixel as it is)."""
    if factor is None:
        return image
    return image * factor if _rgb(factor) else m.scale(image, factor)


def total(values):
    """The sum of a non-empty list of values, left to right."""
    result = values[0]
    for v in values[1:]:
        result = result + v
    return result


def _values(terms, kind, at):
    return [t.value for t in terms if t.kind == kind and t.at == at]


def _rgb(value):
    """True for an RGB value: a node backend's vector, or an array whose last axis is 3."""
    if hasattr(value, "vector"):
        return bool(value.vector)
    return np.ndim(value) > 0 and np.shape(value)[-1] == 3


def _times(m, a, b):
    """a times b, each RGB or grey (RGB by grey scales the colour); a Python 1.0 leaves the other as it is."""
    if isinstance(a, (int, float)) and a == 1.0:
        return b
    if isinstance(b, (int, float)) and b == 1.0:
        return a
    if _rgb(a) == _rgb(b):
        return a * b
    return m.scale(a, b) if _rgb(a) else m.scale(b, a)


def _product(m, factors):
    """The product of ``factors`` left to right (1.0 for none)."""
    result = 1.0
    for f in factors:
        result = _times(m, result, f)
    return result


def _shared(m, value, shares):
    """``value`` times each of ``shares``."""
    for share in shares:
        value = _times(m, value, share)
    return value
