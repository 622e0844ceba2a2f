"""The composer of a pixel's fog (fog_addon/precompute/model/compose.py) against Sun et al. 2005 Eq. 19 and 12 written
out.

Every expected value is the pixel's radiance summed by hand, channel by channel, from the terms' values: where the
pixel sees its surface (coverage c), L = T_render L_surface + (the glows to the surface) + T (the fog light the
surface reflects) (Eq. 19); where it sees the sky (1 - c), the sky seen through the fog plus the glows to the sky
(Eq. 12, ended where the ray leaves a fog layer); the lamps' and the emitters' light times the fog's albedo, the
daylight's with its albedos in.  Grey arrays have N = 5 pixels (a shape ending in 3 would be read as a colour).
"""
import types

import numpy as np
import pytest

from fog_addon.precompute.model import compose, daylight_terms
from fog_addon.precompute.physics.daylight import sunlight
from fog_addon.precompute.model.compose import (DAYLIGHT, DIMMING, EMITTERS, GLOW, LAMPS, LAYER_END, RAY, REFLECTED,
                                                RENDER, SHARE, SKY, SURFACE, Pixel, Term)
from fog_addon.precompute.core.ops import NumpyOps

N = 5
ALBEDO = np.array([0.9, 0.6, 0.3])


def _values(seed):
    """Random term values: RGB (N, 3) lights and the render's pixel, grey (N,) factors in (0, 1)."""
    rng = np.random.default_rng(seed)
    rgb = lambda: rng.uniform(0.1, 2.0, (N, 3))
    grey = lambda: rng.uniform(0.05, 0.95, N)
    return types.SimpleNamespace(
        air=rgb(), scattered=rgb(), background=rgb(), t_vp=grey(),                  # the lamps
        day_glow=rgb(), day_sky=rgb(), day_reflected=rgb(), t_day=grey(),            # the sun and the sky, no air
        emitters=rgb(), surface=rgb(), sky=rgb(), tint=grey(), dims=grey(), seen=grey(), cover=grey())


def _lamp_terms(v):
    return [Term(GLOW, SURFACE, LAMPS, v.air), Term(REFLECTED, SURFACE, LAMPS, v.scattered),
            Term(DIMMING, SURFACE, LAMPS, v.t_vp), Term(GLOW, SKY, LAMPS, v.background)]


def _day_terms(v):
    return [Term(GLOW, SURFACE, DAYLIGHT, v.day_glow), Term(REFLECTED, SURFACE, DAYLIGHT, v.day_reflected),
            Term(DIMMING, SURFACE, DAYLIGHT, v.t_day), Term(GLOW, SKY, DAYLIGHT, v.day_sky),
            Term(DIMMING, SURFACE, RENDER, v.tint), Term(DIMMING, SURFACE, RENDER, v.dims),
            Term(DIMMING, SKY, RENDER, v.seen)]


def _pixel(m, cover, terms, image):
    """The composed pixel: the render's times the composer's factor, plus the fog light."""
    out = compose.compose(m, Pixel(cover, ALBEDO), terms)
    light = 0.0 if out.light is None else out.light
    return compose.dimmed(m, image, out.factor) + light


def _col(x):
    return np.asarray(x)[:, None]


def _by_hand(v, cover, day, emitters):
    """(the fog light, the factor on the render's pixel): Eq. 19's glows and T times the reflected fog light over the
    pixel's surface (c), Eq. 12's glows over its sky (1 - c), the emitters' glows over all of it; the render's surface
    part dimmed by the layer (its materials dimmed it without one: factor 1), its sky part seen through it."""
    c = _col(cover)
    surface = ALBEDO * (v.air + _col(v.t_vp) * v.scattered)                       # lamps, Eq. 19
    sky = ALBEDO * v.background                                                   # lamps, Eq. 12
    factor = np.ones((N, 1))
    if day:
        surface = surface + v.day_glow + _col(v.t_day) * v.day_reflected
        sky = sky + v.day_sky
        factor = c * _col(v.tint * v.dims) + (1.0 - c) * _col(v.seen)
    light = c * surface + (1.0 - c) * sky
    return light + (ALBEDO * v.emitters if emitters else 0.0), factor


@pytest.mark.parametrize("day", [False, True], ids=["no_daylight", "daylight"])
@pytest.mark.parametrize("emitters", [False, True], ids=["no_emitters", "emitters"])
@pytest.mark.parametrize("coverage", ["mixed", "sky", "surface"])
def test_a_pixel_is_eq19_over_its_surface_and_eq12_over_its_sky(day, emitters, coverage):
    """Lamps alone or with a fog layer's sun and sky and glowing objects, for pixels partly covered, all sky
    (coverage 0) and all surface (coverage 1): L = T L_surface + glows + T fog light where the pixel sees its
    surface, the sky seen plus the glows to the sky where it does not."""
    m, v = NumpyOps(), _values(1)
    cover = {"mixed": v.cover, "sky": np.zeros(N), "surface": np.ones(N)}[coverage]
    image = _col(cover) * v.surface + (1.0 - _col(cover)) * v.sky   # the render's pixel
    terms = _lamp_terms(v) + (_day_terms(v) if day else []) + ([Term(GLOW, RAY, EMITTERS, v.emitters)] if emitters
                                                               else [])
    light, factor = _by_hand(v, cover, day, emitters)
    np.testing.assert_allclose(_pixel(m, cover, terms, image), factor * image + light, rtol=1e-12)
    if coverage == "surface" and day:   # Eq. 19 as the paper writes it
        t_render = _col(v.tint * v.dims)
        eq19 = (t_render * v.surface + ALBEDO * v.air + v.day_glow + ALBEDO * _col(v.t_vp) * v.scattered
                + _col(v.t_day) * v.day_reflected + (ALBEDO * v.emitters if emitters else 0.0))
        np.testing.assert_allclose(_pixel(m, cover, terms, image), eq19, rtol=1e-12)
    if coverage == "sky" and day:       # Eq. 12: the sky seen through the layer and the glows to the sky
        eq12 = _col(v.seen) * v.sky + ALBEDO * v.background + v.day_sky + (ALBEDO * v.emitters if emitters else 0.0)
        np.testing.assert_allclose(_pixel(m, cover, terms, image), eq12, rtol=1e-12)


def test_without_a_layer_the_render_is_taken_as_it_is():
    """No dimming of the render's own: the factor is None and the pixel is the render plus the fog light."""
    m, v = NumpyOps(), _values(2)
    out = compose.compose(m, Pixel(v.cover, ALBEDO), _lamp_terms(v))
    assert out.factor is None
    c = _col(v.cover)
    np.testing.assert_allclose(out.light, ALBEDO * (c * (v.air + _col(v.t_vp) * v.scattered) + (1 - c) * v.background),
                               rtol=1e-12)
    assert compose.compose(m, Pixel(v.cover, ALBEDO), []) == (None, None)


@pytest.mark.parametrize("coverage", ["sky", "mixed"])
def test_a_layer_end_bounds_the_lamps_glow_to_the_sky(coverage):
    """A ray that leaves the layer (end 1) takes the lamps' glow along the ray, which the kernel ended at the top,
    instead of their glow to infinity; a ray that never meets the layer (share 0) takes none; every combination."""
    m, v = NumpyOps(), _values(3)
    bounded = np.array([1.0, 0.0, 1.0, 0.0, 1.0])
    meets = np.array([1.0, 1.0, 0.0, 0.0, 1.0])
    cover = np.zeros(N) if coverage == "sky" else v.cover
    terms = _lamp_terms(v) + [Term(LAYER_END, SKY, LAMPS, bounded), Term(SHARE, SKY, LAMPS, meets)]
    light = compose.compose(m, Pixel(cover, ALBEDO), terms).light
    c = _col(cover)
    to_sky = _col(meets) * np.where(_col(bounded) > 0.5, v.air, v.background)
    want = ALBEDO * (c * (v.air + _col(v.t_vp) * v.scattered) + (1 - c) * to_sky)
    np.testing.assert_allclose(light, want, rtol=1e-12)
    assert np.all(light[3] == 0.0) if coverage == "sky" else True   # neither meets nor leaves: no lamp glow at all


def test_a_share_multiplies_its_sources_glows_where_it_is_taken():
    """A lit share at the surface dims the glow along the ray to the surface, not the fog light the surface
    reflects; one along the ray its glow there; another source's light is left alone."""
    m, v = NumpyOps(), _values(4)
    lit, along = v.dims, v.seen
    terms = (_lamp_terms(v) + [Term(SHARE, SURFACE, LAMPS, lit)]
             + [Term(GLOW, RAY, EMITTERS, v.emitters), Term(SHARE, RAY, EMITTERS, along)])
    light = compose.compose(m, Pixel(v.cover, ALBEDO), terms).light
    c = _col(v.cover)
    want = (ALBEDO * (c * (_col(lit) * v.air + _col(v.t_vp) * v.scattered) + (1 - c) * v.background)
            + ALBEDO * _col(along) * v.emitters)
    np.testing.assert_allclose(light, want, rtol=1e-12)


def test_daylight_with_air_dims_by_colour_and_glows_along_the_ray():
    """With air the layer's transmittance, its dimmings and the sky seen are RGB (each channel its own), and the
    daylight's glow is one along the ray (its kernel chose the surface or the sky), over the whole pixel."""
    m, v = NumpyOps(), _values(5)
    rng = np.random.default_rng(6)
    t_day, tint, dims, seen = (rng.uniform(0.05, 0.95, (N, 3)) for _ in range(4))
    terms = ([Term(GLOW, RAY, DAYLIGHT, v.day_glow), Term(REFLECTED, SURFACE, DAYLIGHT, v.day_reflected),
              Term(DIMMING, SURFACE, DAYLIGHT, t_day), Term(DIMMING, SURFACE, RENDER, tint),
              Term(DIMMING, SURFACE, RENDER, dims), Term(DIMMING, SKY, RENDER, seen)])
    c = _col(v.cover)
    image = c * v.surface + (1 - c) * v.sky
    out = compose.compose(m, Pixel(v.cover, ALBEDO), terms)
    np.testing.assert_allclose(out.factor, c * tint * dims + (1 - c) * seen, rtol=1e-12)
    np.testing.assert_allclose(_pixel(m, v.cover, terms, image),
                               (c * tint * dims + (1 - c) * seen) * image + v.day_glow + c * t_day * v.day_reflected,
                               rtol=1e-12)


@pytest.mark.parametrize("term", [
    Term(REFLECTED, SURFACE, LAMPS, 1.0),              # reflected light without its Eq. 19 T
    Term(GLOW, SURFACE, RENDER, 1.0),                  # the render gives no light
    Term(DIMMING, SKY, LAMPS, 1.0),                    # a source of light dims only what leaves the surface
    Term(LAYER_END, SURFACE, LAMPS, 1.0),              # a layer ends the glow to the sky
    Term(REFLECTED, SKY, DAYLIGHT, 1.0)])
def test_a_term_out_of_place_is_refused(term):
    with pytest.raises(ValueError):
        compose.compose(NumpyOps(), Pixel(np.ones(N), ALBEDO), [term])


@pytest.mark.parametrize("air", [False, True], ids=["no_air", "air"])
def test_daylight_terms_are_the_sun_and_the_sky_at_a_pixel(monkeypatch, air):
    """``daylight_terms.pixel_terms`` composed, with its kernels as stand-ins: without air coverage times the glow to the
    surface plus the reflected fog light dimmed by T, plus 1 - coverage times the glow to the sky; with air the glow
    to the surface where coverage is above one half, to the sky elsewhere, plus coverage times T times the fog
    light (T RGB)."""
    m, v = NumpyOps(), _values(7)
    far = 1e15
    length = np.array([3.0, 20.0, 50.0, 7.0, 1.0])
    glow = lambda mm, day, camera, direction, to, share=None: np.stack(
        [np.log1p(np.asarray(to) * (k + 1.0)) for k in range(3)], axis=-1) * (1.0 if share is None else _col(share))
    fog = lambda mm, table, day, position, normal, share=None: v.day_reflected * (1.0 if share is None else
                                                                                 _col(share))
    monkeypatch.setattr(sunlight, "ray_glow", glow)
    monkeypatch.setattr(sunlight, "fog_light", fog)
    day = types.SimpleNamespace(air=(0.1, 0.2, 0.3) if air else None)
    t = np.random.default_rng(8).uniform(0.1, 0.9, (N, 3)) if air else v.t_day
    cover = np.array([0.0, 0.3, 0.6, 1.0, 0.5])
    rho = np.array([0.5, 0.4, 0.3])
    sun_share, surface_share = v.seen, v.dims
    terms = daylight_terms.pixel_terms(m, day, None, None, None, None, None, rho, length, t, cover, sun_share, surface_share)
    light = compose.compose(m, Pixel(cover, ALBEDO), terms).light
    c, tt = _col(cover), (t if air else _col(t))
    reflected = rho * v.day_reflected * _col(surface_share)
    g = lambda to: np.stack([np.log1p(to * (k + 1.0)) for k in range(3)], axis=-1) * _col(sun_share)
    if air:
        want = g(np.where(cover > 0.5, length, far)) + c * tt * reflected
    else:
        want = c * (g(length) + tt * reflected) + (1 - c) * g(np.full(N, far))
    np.testing.assert_allclose(light, want, rtol=1e-12)


def test_daylight_on_a_surface_ray_and_a_sky_ray(monkeypatch):
    """The Surface group's daylight (``daylight_terms.surface_terms`` composed by ``compose.surface_light``): the glow to
    the surface plus the reflected fog light dimmed by T; the World's (``daylight_terms.sky_terms`` composed at coverage
    0): the glow to the sky, taken as it is (a Python coverage of 0 or 1 weighs nothing by a node)."""
    m, v = NumpyOps(), _values(9)
    length = np.array([3.0, 20.0, 50.0, 7.0, 1.0])
    glow = lambda mm, day, camera, direction, to, share=None: np.stack(
        [np.log1p(np.broadcast_to(np.asarray(to, float), (N,)) * (k + 1.0)) for k in range(3)], axis=-1)
    fog = lambda mm, table, day, position, normal, share=None: v.day_reflected
    monkeypatch.setattr(sunlight, "ray_glow", glow)
    monkeypatch.setattr(sunlight, "fog_light", fog)
    day = types.SimpleNamespace(air=None)
    rho = np.array([0.5, 0.4, 0.3])
    terms = daylight_terms.surface_terms(m, day, None, None, None, None, None, rho, length, v.t_day)
    want = glow(m, day, None, None, length) + _col(v.t_day) * rho * v.day_reflected
    np.testing.assert_allclose(compose.surface_light(m, terms), want, rtol=1e-12)
    scaled = []
    monkeypatch.setattr(m, "scale", lambda a, b: scaled.append(b) or a * b, raising=False)
    sky = compose.source_light(m, 0.0, daylight_terms.sky_terms(m, day, None, None))
    np.testing.assert_allclose(sky, glow(m, day, None, None, 1e15), rtol=1e-12)
    assert scaled == [], scaled


@pytest.mark.parametrize("shared", [False, True])
def test_a_segment_past_glass_is_its_glow_passed_on_and_dimmed(shared):
    """A light's glow along a segment past a pane (``shading.segment_terms``): albedo x weight x lit share x tail,
    dimmed by the camera segment's transmittance (Eq. 19's T on the light the pane sends on), and nothing else of
    the pixel's; the segments' light adds to the lamps' (the composition is linear)."""
    from fog_addon.precompute.model import shading
    v = _values(7)
    rng = np.random.default_rng(8)
    tail, weight, share = rng.uniform(0.1, 2.0, (N, 3)), rng.uniform(0.0, 1.0, (N, 3)), rng.uniform(0.0, 1.0, N)
    m = NumpyOps({})
    terms = shading.segment_terms(m, tail, weight, v.t_vp, share if shared else None)
    out = compose.compose(m, Pixel(1.0, ALBEDO), terms)
    lit = share[:, None] if shared else 1.0
    expected = ALBEDO * tail * weight * lit * v.t_vp[:, None]
    assert out.factor is None
    np.testing.assert_allclose(out.light, expected, rtol=1e-12)
    both = compose.compose(m, Pixel(1.0, ALBEDO), terms + _lamp_terms(v)).light
    lamps = ALBEDO * (v.air + v.t_vp[:, None] * v.scattered)
    np.testing.assert_allclose(both, expected + lamps, rtol=1e-12)
