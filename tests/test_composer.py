"""The one composer (precompute/model/shading.py) and the term descriptors its builders derive sockets from
(rungs.OUTPUTS).

Expected values are Sun et al. 2005 Eq. 19 and 12 written out by hand; the socket names are the ones saved
files and farms read (a hand list on purpose: renaming one breaks every saved file).
"""
import math

import numpy as np
import pytest

from fog_addon.precompute.model import rungs, shading
from fog_addon.precompute.core.medium import Medium
from fog_addon.precompute.core.ops import NumpyOps


def test_pixel_light_is_eq19_over_the_surface_and_eq12_over_the_sky():
    """coverage * (airlight + e^{-beta D_vp} scattered) + (1 - coverage) * background, per channel, for a
    partly covered pixel; subsets of the quantities compose on their own (the composition is linear)."""
    m = NumpyOps()
    rng = np.random.default_rng(11)
    air, scat, back = (rng.uniform(0, 2, (5, 3)) for _ in range(3))
    cover, t_vp = rng.uniform(0, 1, 5), math.exp(-0.3 * 4.0)
    values = {rungs.AIRLIGHT_OUT: air, rungs.SCATTERED_OUT: scat, rungs.BACKGROUND_OUT: back}
    want = cover[:, None] * (air + t_vp * scat) + (1 - cover[:, None]) * back
    np.testing.assert_allclose(shading.pixel_light(m, values, t_vp, cover), want, rtol=1e-13)
    glow = shading.pixel_light(m, {rungs.AIRLIGHT_OUT: air, rungs.BACKGROUND_OUT: back}, t_vp, cover)
    reflected = shading.pixel_light(m, {rungs.SCATTERED_OUT: scat}, t_vp, cover)
    np.testing.assert_allclose(glow + reflected, want, rtol=1e-13)
    np.testing.assert_allclose(reflected, cover[:, None] * t_vp * scat, rtol=1e-13)
    assert shading.pixel_light(m, {}, t_vp, cover) is None
    np.testing.assert_allclose(shading.surface_light(m, values, t_vp), air + t_vp * scat, rtol=1e-13)


def test_socket_names_are_the_saved_files():
    """The per-light groups' outputs and the compositor's sockets, as saved files and farms know them."""
    point, spot = rungs.choose("nodes"), rungs.choose("nodes", kind="spot")
    names = lambda outputs, models: [(o.name, o.colour) for o in outputs if o.present(models)]
    assert names(rungs.SURFACE_OUTPUTS, point) == [("Airlight", True), ("Scattered", True), ("Attenuation", False),
                                                   ("Weight", False)]
    assert names(rungs.SURFACE_OUTPUTS, spot) == names(rungs.SURFACE_OUTPUTS, point) + [("Seen", False)]
    assert names(rungs.SKY_OUTPUTS, point) == [("Airlight", True)]
    assert names(rungs.SKY_OUTPUTS, spot) == [("Airlight", True), ("Seen", False)]
    assert names(rungs.SURFACE_OUTPUTS, rungs.choose("nodes", step=rungs.OFF, kind="spot"))[-1] == ("Weight", False)
    assert [o.compositor for o in rungs.COMPOSITOR_OUTPUTS] == ["Airlight", "Scattered", "Background"]
    for o in rungs.OUTPUTS:
        assert o.term in rungs.TERMS and o.field in (shading.LightTerms._fields if o.at == rungs.SURFACE_POINT
                                                     else shading.SkyTerms._fields)


@pytest.mark.parametrize("seen", [False, True])
def test_sum_lights_keeps_a_gated_glow_apart(seen):
    """A light with a gate (a spot's cone) gives its glow and the rest as two colours whose sum is Eq. 19's."""
    m = NumpyOps()
    albedo, t_vp = np.array([0.9, 0.5, 0.2]), 0.4
    t = shading.LightTerms(np.array([1.0, 2.0, 3.0]), np.array([0.5, 0.5, 1.0]), 0.7, 1.3, 1.0 if seen else None)
    sums = shading.sum_lights(m, [t], Medium(0.1, albedo), t_vp, 1.0)
    want = albedo * (t.airlight + t_vp * t.scattered)
    (e,) = sums.emissions
    if seen:
        assert isinstance(e, shading.Gated)
        np.testing.assert_allclose(e.glow, albedo * t.airlight, rtol=1e-14)
        np.testing.assert_allclose(e.rest, albedo * t_vp * t.scattered, rtol=1e-14)
    np.testing.assert_allclose(sums.emission, want, rtol=1e-14)
