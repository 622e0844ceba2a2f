"""The shading of a point (precompute/model/shading.py) and the models as data (rungs.py), in numpy.

Expected values are independent of the code under test: the glow by scipy
quadrature of Sun et al. 2005 Eq. 5 (tools/airlight_reference.py), the fog
light a surface reflects by quadrature of Eq. 15 (``surface.surface_m``,
itself checked against scipy in test_surface.py), with every geometric
quantity (mirror axis, lobe angles, distances) recomputed here from the
vectors, and Eq. 19 written out by hand.
"""
import inspect
import math

import numpy as np
import pytest

from fog_addon.precompute.core import tables
from fog_addon.precompute.model import rungs, shading
from fog_addon.precompute.physics.point import airlight, surface
from fog_addon.precompute.core.medium import Medium, medium
from fog_addon.precompute.core.ops import NumpyOps, ShaderOps
from tools import airlight_reference as ref

AIRLIGHT_TOL = 2e-4    # the airlight table rung: 1.6e-4 measured (test_airlight.py)
SCATTER_TOL = 5e-3     # the scatter table rung: 0.43 % measured (test_surface.py)


@pytest.fixture(scope="module")
def m():
    return NumpyOps({tables.AIRLIGHT.name: airlight.bake_airlight_table(),
                     tables.SURFACE.name: surface.surface_table()})


def _angle(a, b):
    return math.atan2(np.linalg.norm(np.cross(a, b)), np.dot(a, b))


def _cases(n, seed):
    """Random camera, surface point, normal, light, material and beta (T_sp up to ~6)."""
    rng = np.random.default_rng(seed)
    for _ in range(n):
        camera = rng.uniform(-5, 5, 3)
        normal = rng.normal(size=3)
        normal /= np.linalg.norm(normal)
        view = rng.normal(size=3)
        view -= 1.2 * max(np.dot(view, normal), 0.0) * normal   # mostly from the front
        view /= np.linalg.norm(view)
        d_vp = math.exp(rng.uniform(math.log(0.5), math.log(30.0)))
        pos = camera + view * d_vp
        if np.dot(-view, normal) < 0:
            normal = -normal
        light = pos + rng.normal(size=3) * math.exp(rng.uniform(math.log(0.3), math.log(8.0)))
        beta = math.exp(rng.uniform(math.log(0.01), math.log(0.8)))
        n = float(2.0 ** rng.uniform(0, 10))
        yield camera, pos, normal, light, beta, n, rng.uniform(0.1, 1.0, 3), rng.uniform(0.0, 1.0, 3)


def _fog_light(pos, normal, incoming, light_pos, beta, n, rho_d, rho_s, intensity):
    """The fog light a surface reflects (Eq. 15 by quadrature, ``surface.surface_m``), its diffuse and Phong lobes
    about the normal and the mirrored view vector, recomputed here from the vectors."""
    d_sp = np.linalg.norm(light_pos - pos)
    t = beta * d_sp
    mirror = 2 * np.dot(incoming, normal) * normal - incoming
    scale = beta * math.exp(-t) / (2 * math.pi * d_sp)
    diffuse = scale * surface.surface_m([t], [_angle(normal, light_pos - pos)], 1.0)[0, 0]
    glossy = scale * surface.surface_m([t], [_angle(mirror, light_pos - pos)], n)[0, 0]
    return intensity * (rho_d * diffuse + rho_s * glossy)


@pytest.mark.parametrize("seed", range(4))
def test_shade_point_against_quadrature(m, seed):
    """Each term of one light at a surface point: glow (Eq. 5), fog light diffuse and glossy (Eq. 15), Eq. 14."""
    for camera, pos, normal, light_pos, beta, n, rho_d, rho_s in _cases(6, seed):
        intensity = np.array([3.0, 2.0, 1.0])
        incoming = (camera - pos) / np.linalg.norm(camera - pos)
        d_vp = np.linalg.norm(camera - pos)
        geo = shading.Geometry(camera, pos, incoming, np.asarray(d_vp), normal)
        mat = shading.Material(rho_d, rho_s, np.asarray(surface.exponent_level(n)))
        got = shading.shade_point(m, geo, mat, shading.Light(light_pos, intensity), Medium(beta),
                                  rungs.choose("nodes"))
        to = light_pos - camera
        gamma = _angle(to, -incoming)
        air = ref.eq5_quad(beta, np.linalg.norm(to), d_vp, gamma)[0]
        np.testing.assert_allclose(got.airlight, intensity * air, rtol=AIRLIGHT_TOL)
        np.testing.assert_allclose(got.scattered, _fog_light(pos, normal, incoming, light_pos, beta, n, rho_d, rho_s,
                                                             intensity), rtol=SCATTER_TOL)
        d_sp = np.linalg.norm(light_pos - pos)
        t = beta * d_sp
        mirror = 2 * np.dot(incoming, normal) * normal - incoming
        assert got.attenuation == pytest.approx(math.exp(-t), rel=1e-12)
        cos_n = max(np.dot(normal, light_pos - pos) / d_sp, 0.0)
        cos_r = max(np.dot(mirror, light_pos - pos) / d_sp, 0.0)
        lobe = rho_d.mean() * cos_n / math.pi + rho_s.mean() * (n + 1) / (2 * math.pi) * cos_r ** n
        assert got.weight == pytest.approx(intensity.mean() * lobe / d_sp ** 2, rel=1e-6)


@pytest.mark.parametrize("seed", range(2))
def test_sampled_light_is_unbiased(m, seed):
    """A light with ``choose(sampled_glow=True)`` (the viewport preview's sampled lights: the glow from equiangular
    points): its glow's mean over the uniform number is Eq. 5 by quadrature, and its fog light Eq. 15's two lobes
    by quadrature, to the table rung's bound."""
    u = (np.arange(8192) + 0.5) / 8192
    for camera, pos, normal, light_pos, beta, n, rho_d, rho_s in _cases(5, seed + 10):
        intensity = np.array([3.0, 2.0, 1.0])
        incoming = (camera - pos) / np.linalg.norm(camera - pos)
        d_vp = np.linalg.norm(camera - pos)
        geo = shading.Geometry(camera, pos, incoming, np.asarray(d_vp), normal)
        mat = shading.Material(rho_d, rho_s, np.asarray(surface.exponent_level(n)))
        got = shading.shade_point(m, geo, mat, shading.Light(light_pos, intensity, None, u[:, None]), Medium(beta),
                                  rungs.choose("nodes", sampled_glow=True))
        to = light_pos - camera
        air = ref.eq5_quad(beta, np.linalg.norm(to), d_vp, _angle(to, -incoming))[0]
        mean = {k: np.reshape(getattr(got, k), (-1, 3)).mean(axis=0) for k in ("airlight", "scattered")}
        np.testing.assert_allclose(mean["airlight"], intensity * air, rtol=1e-4)
        np.testing.assert_allclose(mean["scattered"], _fog_light(pos, normal, incoming, light_pos, beta, n, rho_d,
                                                                 rho_s, intensity), rtol=SCATTER_TOL)


def test_glossy_lobe_follows_the_mirror_direction(m):
    """A sharp lobe pointing at the light reflects far more fog light than one pointing away."""
    geo = shading.Geometry(np.array([0.0, -4.0, 2.0]), np.zeros(3), np.array([0.0, -2.0, 1.0]) / math.sqrt(5),
                           np.asarray(math.sqrt(20.0)), np.array([0.0, 0.0, 1.0]))
    mat = shading.Material(np.zeros(3), np.ones(3), np.asarray(surface.exponent_level(512.0)))
    on_axis = shading.Light(np.array([0.0, 2.0, 1.0]), np.ones(3))     # on the mirror ray
    off_axis = shading.Light(np.array([0.0, -2.0, 1.0]), np.ones(3))   # behind the viewer's side
    a, b = (shading.shade_point(m, geo, mat, li, Medium(0.3), rungs.choose("nodes")).scattered[0]
            for li in (on_axis, off_axis))
    assert a > 5 * b > 0


def test_shade_surface_is_eq19(m):
    """Sum over lights and Sun Eq. 19, written out by hand (including EEVEE's weighted attenuation)."""
    rng = np.random.default_rng(3)
    terms = [shading.LightTerms(rng.uniform(0, 1, 3), rng.uniform(0, 1, 3), rng.uniform(0.1, 1), rng.uniform(0, 2))
             for _ in range(3)]
    albedo, beta, d_vp = np.array([0.9, 0.8, 0.7]), 0.2, 7.0
    got = shading.shade_surface(m, terms, Medium(beta, albedo), np.asarray(d_vp), np.asarray(1.0))
    t_vp = math.exp(-beta * d_vp)
    want = albedo * (sum(t.airlight for t in terms) + t_vp * sum(t.scattered for t in terms))
    np.testing.assert_allclose(got.emission, want, rtol=1e-12)
    direct = sum(t.weight * t.attenuation for t in terms) / sum(t.weight for t in terms)
    assert got.transmittance == pytest.approx(t_vp)
    assert got.direct_attenuation == pytest.approx(direct, rel=1e-9)
    assert got.cycles_mix == pytest.approx(1 - t_vp)
    assert got.eevee_mix == pytest.approx(1 - t_vp * direct, rel=1e-9)
    other = shading.shade_surface(m, terms, Medium(beta, albedo), np.asarray(d_vp), np.asarray(0.0))
    np.testing.assert_array_equal(other.emission, 0.0)   # other rays see the material unfogged
    assert other.transmittance == 1.0 and other.cycles_mix == 0.0
    empty = shading.shade_surface(m, [], Medium(beta, albedo), np.asarray(d_vp), np.asarray(1.0))
    np.testing.assert_array_equal(empty.emission, 0.0)
    assert empty.direct_attenuation == 1.0


def test_background_against_quadrature(m):
    rng = np.random.default_rng(5)
    camera = np.zeros(3)
    for _ in range(10):
        d = rng.normal(size=3)
        d /= np.linalg.norm(d)
        light = rng.normal(size=3) * 5
        beta = math.exp(rng.uniform(math.log(0.01), math.log(0.5)))
        for pref in rungs.PREFERENCES:
            glow = shading.background_point(m, camera, d, shading.Light(light, np.ones(3)), Medium(beta),
                                            rungs.choose(pref))
            want = ref.eq5_quad(beta, np.linalg.norm(light), math.inf, _angle(light, d))[0]
            np.testing.assert_allclose(glow, want, rtol=AIRLIGHT_TOL)
    emission, transmittance = shading.shade_background(m, [np.ones(3), 2 * np.ones(3)],
                                                       Medium(0.1, np.array([0.5, 1, 1])), np.asarray(1.0))
    np.testing.assert_allclose(emission, [1.5, 3.0, 3.0])
    assert transmittance == 0.0   # the background is seen through infinite fog
    # other rays: the World's light is extinguished too, unless the artist keeps it
    for world_light, want in ((0.0, 0.0), (1.0, 1.0)):
        emission, transmittance = shading.shade_background(m, [np.ones(3)], Medium(0.1), np.asarray(0.0), world_light)
        assert transmittance == want and not emission.any()
    # a fog of no density is no fog: the World is seen and lights surfaces (the limit e^{-beta t}, beta -> 0)
    for is_camera in (0.0, 1.0):
        for world_light in (0.0, 1.0):
            _, transmittance = shading.shade_background(m, [], Medium(0.0), np.asarray(is_camera), world_light)
            assert transmittance == 1.0


# --- models as data ----------------------------------------------------------------

_SIGNATURES = {"airlight": ["beta", "d_sv", "along", "h", "d_vp"], "background": ["beta", "d_sv", "along", "h"],
               "scatter": ["beta", "d_sp", "cos_theta", "level"], "direct": ["beta", "d"]}


def test_rungs_declare_what_they_need():
    every = list(rungs.RUNGS) + list(rungs.anisotropic_rungs(0.7))
    names = [r.name for r in every]
    assert len(set(names)) == len(names)
    for r in every:
        assert r.term in rungs.TERMS and r.backends <= set(rungs.BACKENDS) and "numpy" in r.backends
        # the term's signature; anisotropy g is a keyword with a default, bound per g (rungs.anisotropic_rungs)
        params = [p.name for p in inspect.signature(r.kernel).parameters.values() if p.default is p.empty]
        assert params[0] == "m" and len(params[1:]) == len(_SIGNATURES[r.term]), (r.name, params)
        assert r.max_error >= 0 and r.predicted_error() == r.max_error and r.evidence
        if r.tables:
            assert "osl" not in r.backends, f"{r.name}: OSL cannot read packed tables"


def test_chooser_honours_the_preference():
    nodes, osl = rungs.choose("nodes"), rungs.choose("osl")
    assert not rungs.needs_osl(nodes) and rungs.needs_osl(osl)
    assert all(getattr(nodes, t).term == t for t in rungs.TERMS)
    assert osl.airlight is rungs.AIRLIGHT_QUADRATURE and osl.background is rungs.BACKGROUND_QUADRATURE
    assert rungs.tables_of(nodes) == (tables.AIRLIGHT, tables.SURFACE)
    with pytest.raises(ValueError, match="unknown method"):
        rungs.choose("magic")


@pytest.mark.parametrize("bad, msg", [(dict(beta=float("nan")), "density"), (dict(beta=-1), "density"),
                                      (dict(beta=0.1, g=0.97), "anisotropy"),
                                      (dict(beta=0.1, g=float("nan")), "anisotropy"),
                                      (dict(beta=0.1, albedo=(1, 2, 1)), "colour"),
                                      (dict(beta=0.1, scene_scale=0), "scene scale")])
def test_medium_refuses_bad_input(bad, msg):
    with pytest.raises(ValueError, match=msg):
        medium(**bad)


def test_medium_per_scene_unit():
    assert medium(0.05, scene_scale=100.0) == Medium(5.0, (1.0, 1.0, 1.0), 0.0)


def test_every_backend_completes_the_protocol():
    """NumpyOps, NodeOps and OslOps have every ShaderOps operation; the two that can't say why."""
    from fog_addon.nodes.osl import OslOps
    from fog_addon.nodes.sockets import NodeOps
    wanted = [n for n in ShaderOps.__dict__ if not n.startswith("_")]
    assert len(wanted) >= 20
    for backend in (NumpyOps, NodeOps, OslOps):
        missing = [n for n in wanted if not callable(getattr(backend, n, None))]
        assert not missing, f"{backend.__name__} lacks {missing}"
    with pytest.raises(NotImplementedError, match="no loops"):
        NodeOps(None).fori(2, lambda x: (x,), (0.0,))
    with pytest.raises(NotImplementedError, match="packed images"):
        OslOps().table(tables.AIRLIGHT, 0.5, 0.5)
