"""The lit share of a glow (precompute/physics/shafts/shafts.py) against adaptive quadrature with exact visibility.

Occluders are spheres and boxes whose shadows are known in closed form: the expected share is scipy's
quad of the single-scattering integrand times the exact visibility over quad of the integrand (both
independent of the code under test); the map is baked from the same closed-form ray casts at the map's
grid points, as ``nodes/shafts.py`` bakes it with Blender's BVH.
"""
import math

import numpy as np
import pytest
from scipy import integrate

from fog_addon.precompute.physics.shafts import shaft_maps, shafts
from fog_addon.precompute.core.ops import NumpyOps
from fog_addon.precompute.core.tables import TableSpec
from fog_scenes.occluders import sphere_hit


def point_map(light, occluders, size=(512, 256)):
    dirs = shaft_maps.point_map_directions(*size)
    flat = dirs.reshape(-1, 3)
    depth = np.full(len(flat), shaft_maps.NO_HIT)
    for centre, radius in occluders:
        depth = np.minimum(depth, sphere_hit(light, flat, centre, radius))
    spec = TableSpec("shadow", size[0], size[1])
    return spec, depth.reshape(dirs.shape[:2])


def expected_share(camera, direction, length, light, beta, occluders, g=0.0, normal=None):
    """The lit share by quadrature; ``normal``: an area light's emitting side (world), whose fog weighs
    max(cos, 0) about it (Lambert), else a point light's."""
    camera, direction, light = (np.asarray(a, float) for a in (camera, direction, light))

    def integrand(t, visible):
        x = camera + t * direction
        u = x - light
        d = np.linalg.norm(u)
        w = 1.0
        if g:
            mu = np.dot(u / d, -direction)
            w = (1 - g * g) / (1 + g * g - 2 * g * mu) ** 1.5
        f = math.exp(-beta * (t + d)) * w / (d * d)
        if normal is not None:
            f *= max(float(np.dot(u / d, normal)), 0.0)
        if visible:
            for centre, radius in occluders:
                if sphere_hit(light, (u / d)[None], centre, radius)[0] < d:
                    return 0.0
        return f
    t_c = float(np.dot(light - camera, direction))
    points = [p for p in (t_c,) if 0 < p < length]
    lim = 400
    num = integrate.quad(integrand, 0, length, args=(True,), points=points, limit=lim, epsabs=0, epsrel=1e-7)[0]
    den = integrate.quad(integrand, 0, length, args=(False,), points=points, limit=lim, epsabs=0, epsrel=1e-9)[0]
    return num / den


def share(camera, direction, length, light, beta, spec, depth, nodes=64, shift=0.5, g=0.0, falloff=None):
    m = NumpyOps({spec.name: depth})
    light = np.asarray(light, float)

    return shafts.lit_share(m, np.asarray(camera, float), np.asarray(direction, float), length, light, beta,
                            (spec, None), nodes, shift=shift, g=g, falloff=falloff)


CAMERA = np.array([0.0, -10.0, 1.5])


def _ray(target):
    d = np.asarray(target, float) - CAMERA
    return d / np.linalg.norm(d)


def test_open_ray_is_exactly_one():
    spec, depth = point_map((0, 0, 3), [((50, 50, 50), 1.0)])
    s = share(CAMERA, _ray((0.5, 0, 2.5)), 30.0, (0, 0, 3), 0.1, spec, depth)
    assert s == 1.0


@pytest.mark.parametrize("g", [0.0, 0.7])
@pytest.mark.parametrize("target,length", [((0.3, 0.0, 0.5), 25.0), ((0.1, 4.0, 3.2), 1e6), ((0.2, 1.0, 1.0), 11.0)])
def test_sphere_shadow_matches_quadrature(target, length, g):
    light = (0.0, 0.0, 3.0)
    occluders = [((0.0, 0.0, 2.0), 0.6), ((0.0, 1.2, 3.0), 0.3)]
    spec, depth = point_map(light, occluders, (1024, 512))
    direction = _ray(target)
    got = np.mean([share(CAMERA, direction, length, light, 0.1, spec, depth, nodes=64, shift=(k + 0.5) / 16, g=g)
                   for k in range(16)])   # the 16 interleaved pixels' mean, as the blur takes it
    want = expected_share(CAMERA, direction, min(length, 400.0), light, 0.1, occluders, g=g)
    assert want < (0.999 if g else 0.97)   # the ray does cross a shadow
    assert abs(got - want) < 0.02, (got, want)


@pytest.mark.parametrize("camera,target,length", [((-2.0, -10.0, 3.1), (-2.0, 0.0, 3.1), 25.0),
                                                  ((-10.0, -1.0, 3.5), (0.0, 0.0, 3.5), 1e6)])
def test_area_light_share_weighs_its_front_side(camera, target, length):
    """An area light facing -x (its rows those of a light turned 90 degrees about y, scaled 2 x 0.5 x 1: the third
    row stays normal to the emitter): its shafts' share weighs the fog by Lambert's cosine on its front side and
    none behind (``area.shaft_falloff``), against quadrature with that weight.  The share a point light's weights
    would give differs: the ray's fog behind the emitter, lit or shadowed, counts for nothing."""
    from fog_addon.precompute.physics.area import area
    light = (0.0, 0.0, 3.0)
    occluders = [((-1.5, 0.0, 3.0), 0.5), ((1.5, 0.0, 3.0), 0.5)]   # one before it, one behind
    spec, depth = point_map(light, occluders, (1024, 512))
    turn = np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]]) @ np.diag([2.0, 0.5, 1.0])
    rows = tuple(np.linalg.inv(turn).ravel())   # its local -Z in the world: -x
    normal = -turn[:, 2] / np.linalg.norm(turn[:, 2])

    def falloff(m, u, d):
        return area.shaft_falloff(m, u, d, *rows)
    camera = np.asarray(camera, float)   # (the second ray crosses the emitter's plane x = 0)
    direction = np.subtract(target, camera) / np.linalg.norm(np.subtract(target, camera))
    got = np.mean([share(camera, direction, length, light, 0.1, spec, depth, nodes=64, shift=(k + 0.5) / 16,
                         falloff=falloff) for k in range(16)])
    want = expected_share(camera, direction, min(length, 400.0), light, 0.1, occluders, normal=normal)
    point = expected_share(camera, direction, min(length, 400.0), light, 0.1, occluders)
    print(f"area {got:.4f}, quadrature {want:.4f}, a point light's {point:.4f}")
    assert abs(got - want) < 0.02, (got, want)
    assert abs(point - want) > 0.05, (point, want)


def test_thin_pole_casts_its_shaft():
    """A 5 cm pole (a row of small spheres) 4 m from the light: a ray through its shadow loses light."""
    light = np.array([0.0, 0.0, 3.0])
    occluders = [((0.0, 4.0, z), 0.025) for z in np.arange(0.0, 6.0, 0.02)]
    spec, depth = point_map(light, occluders, shaft_maps.POINT_MAP)
    direction = np.array([1.0, 0.0, 0.0])
    camera = np.array([-10.0, 8.0, 3.0])   # the ray crosses the pole's shadow 8 m from the light
    got = share(camera, direction, 20.0, light, 0.05, spec, depth, nodes=256)
    want = expected_share(camera, direction, 20.0, light, 0.05, occluders[140:160])
    assert want < 0.999 and abs(got - want) < 0.01, (got, want)


def test_offset_is_the_bayer_pattern():
    m = NumpyOps()
    for j in range(8):
        for i in range(8):
            rank = round(float(shafts.offset(m, np.float64(i), np.float64(j))) * 4 - 0.5)
            assert rank == shafts.bayer_rank(i, j)


def test_spot_map_round_trip():
    frame = shaft_maps.spot_frame(np.array([[1, 0, 0], [0, 0, -1], [0, 1, 0]], float).T)
    half = shaft_maps.spot_half_width(math.cos(math.radians(30)))
    dirs = shaft_maps.spot_map_directions(frame, half, 9)
    m = NumpyOps()
    x, y = shaft_maps.spot_map_xy(m, dirs.reshape(-1, 3), frame, half)
    i, j = np.meshgrid(np.arange(9), np.arange(9))
    assert np.allclose(x, i.ravel() / 8) and np.allclose(y, j.ravel() / 8)


def test_point_map_round_trip():
    dirs = shaft_maps.point_map_directions(17, 9)
    m = NumpyOps()
    x, y = shaft_maps.point_map_xy(m, dirs[1:-1].reshape(-1, 3))
    i, j = np.meshgrid(np.arange(17), np.arange(1, 8))
    x_want = i.ravel() / 16
    ok = np.isclose(x, x_want) | (np.isclose(x_want, 0) & np.isclose(x, 1)) | (np.isclose(x_want, 1) & np.isclose(x, 0))
    assert ok.all() and np.allclose(y, j.ravel() / 8)


@pytest.mark.parametrize("size", [shaft_maps.POINT_MAP, (64, 33)])
def test_point_map_casts_resolve_the_equator_spacing_everywhere(size):
    """The thinned rays of a point light's map (``point_map_casts``): each grid point takes a ray within half the
    equator's grid spacing of its own direction (``point_map_directions``, the grid the compositor reads), and no
    two neighbouring rays of a row lie farther apart than that spacing, so a thin occluder the equator resolves is
    resolved at every latitude; about 2 / pi of the grid's rays are cast."""
    width, height = size
    directions, fill = shaft_maps.point_map_casts(width, height)
    grid = shaft_maps.point_map_directions(width, height)
    spacing = 2.0 * math.pi / (width - 1)   # rad between the equator's grid points
    assert fill.shape == (height, width)
    assert np.allclose(np.linalg.norm(directions, axis=-1), 1.0)
    taken = np.arccos(np.clip(np.sum(directions[fill] * grid, axis=-1), -1.0, 1.0))
    assert taken.max() <= 0.5 * spacing * (1.0 + 1e-6)
    for j in range(height):
        row = directions[np.unique(fill[j])]
        apart = np.arccos(np.clip(np.sum(row[1:] * row[:-1], axis=-1), -1.0, 1.0))
        assert apart.max(initial=0.0) <= spacing * (1.0 + 1e-6)
    assert len(directions) < (2.0 / math.pi + 4.0 / width) * width * height


@pytest.mark.parametrize("length", [5.0, 1e6])
def test_ray_through_the_light_is_finite(length):
    """A pixel whose ray passes through the lamp, to a surface or to the sky, in float32 as the compositor
    computes: the share is finite and in [0, 1] (it was NaN at the lamp's pixel of a render)."""
    light = np.array([0.0, 0.0, 3.0], np.float32)
    spec, depth = point_map(light, [((0.0, 0.0, 2.0), 0.6)], (64, 32))
    m = NumpyOps({spec.name: depth.astype(np.float32)}, dtype=np.float32)
    direction = (light - CAMERA.astype(np.float32)) / np.linalg.norm(light - CAMERA.astype(np.float32))
    s, far = shafts.lit_share(m, CAMERA.astype(np.float32), direction.astype(np.float32), np.float32(length), light,
                              np.float32(0.08), (spec, None), 24, tail_nodes=6, far=1e6)
    assert np.isfinite(s) and np.isfinite(far) and 0.0 <= s <= 1.0 and 0.0 <= far <= 1.0, (s, far)


PATTERN = 4 ** shafts.SURFACE_PATTERN_LEVELS   # pixels in the surface share's interleaving pattern


def test_surface_offset_is_the_bayer_pattern():
    m = NumpyOps()
    side = 2 ** shafts.SURFACE_PATTERN_LEVELS
    ranks = set()
    for j in range(2 * side):
        for i in range(2 * side):
            rank = round(float(shafts.surface_offset(m, np.float64(i), np.float64(j))) * PATTERN - 0.5)
            assert rank == shafts.bayer_rank_surface(i, j)
            ranks.add(rank)
    assert ranks == set(range(PATTERN))
    # a 2 x 2 block holds four ranks spread over the whole pattern (its most significant digit)
    assert sorted(shafts.bayer_rank_surface(i, j) // (PATTERN // 4) for i in (0, 1) for j in (0, 1)) == [0, 1, 2, 3]


def test_hemisphere_directions_are_cosine_weighted():
    """Over the pattern's interleaved turns, the directions are unit, over the normal, and hold cos / pi's moments:
    E[cos theta] = 2/3, E[cos^2 theta] = 1/2, and no tangent bias."""
    m = NumpyOps()
    normal = np.array([0.3, -0.2, 0.9]) / np.linalg.norm([0.3, -0.2, 0.9])
    dirs = np.array([d for k in range(PATTERN) for d in
                     shafts.hemisphere_directions(m, normal, shafts.DEFAULT_SAMPLES.surface_directions,
                                                  (k + 0.5) / PATTERN)])
    assert np.allclose(np.linalg.norm(dirs, axis=1), 1.0)
    c = dirs @ normal
    assert (c > 0).all()
    assert abs(c.mean() - 2 / 3) < 0.01 and abs((c * c).mean() - 0.5) < 0.01, (c.mean(), (c * c).mean())
    assert np.linalg.norm((dirs - np.outer(c, normal)).mean(0)) < 0.03


def expected_surface_share(point, normal, light, beta, occluders, n_u=12, n_phi=24):
    """The shadowed over the unshadowed int cos / pi L_a(omega) d omega over the hemisphere: Gauss-Legendre in
    u = sin^2 theta (d omega cos / pi = du d phi / 2 pi) and phi, scipy quad along each ray to infinity."""
    point, normal, light = (np.asarray(a, float) for a in (point, normal, light))
    t1 = np.cross(normal, [0.0, 0.0, 1.0]) + np.cross(normal, [0.0, 1.0, 0.0]) * 0.01
    t1 /= np.linalg.norm(t1)
    t2 = np.cross(normal, t1)
    x, w = np.polynomial.legendre.leggauss(n_u)
    us, wu = 0.5 * (x + 1.0), 0.5 * w
    num = den = 0.0
    for u, wi in zip(us, wu):
        for phi in (np.arange(n_phi) + 0.5) * 2 * math.pi / n_phi:
            r = math.sqrt(u)
            d = r * math.cos(phi) * t1 + r * math.sin(phi) * t2 + math.sqrt(1 - u) * normal
            t_c = float(np.dot(light - point, d))
            end = max(t_c, 0.0) + 200.0

            def f(t, visible):
                q = point + t * d - light
                dist = np.linalg.norm(q)
                if visible:
                    for centre, radius in occluders:
                        if sphere_hit(light, (q / dist)[None], centre, radius)[0] < dist:
                            return 0.0
                return math.exp(-beta * (t + dist)) / (dist * dist)
            pts = [t_c] if t_c > 0 else None
            num += wi * integrate.quad(f, 0, end, args=(True,), points=pts, limit=200, epsrel=1e-6)[0]
            den += wi * integrate.quad(f, 0, end, args=(False,), points=pts, limit=200, epsrel=1e-8)[0]
    return num / den


SURFACE_CASE = dict(point=(1.5, 0.0, 0.0), normal=(0.0, 0.0, 1.0), light=(0.0, 0.0, 3.0), beta=0.1,
                    occluders=[((0.0, 0.0, 2.0), 0.6)])


@pytest.fixture(scope="module")
def surface_want():
    return expected_surface_share(**SURFACE_CASE)


def surface_got(directions, nodes, occluders=SURFACE_CASE["occluders"]):
    """``surface_share`` over the pattern's interleaved pixels: their sums, then the ratio (as the compositor takes
    it)."""
    c = SURFACE_CASE
    spec, depth = point_map(c["light"], occluders, (1024, 512))
    m = NumpyOps({spec.name: depth})
    lit = total = 0.0
    for k in range(PATTERN):
        a, b = shafts.surface_share(m, np.array(c["point"], float), np.array(c["normal"], float),
                                    np.array([5.0, -5.0, 2.0]), np.array(c["light"], float), c["beta"], (spec, None),
                                    shift=(k + 0.5) / PATTERN, directions=directions, nodes=nodes, parts=True)
        lit, total = lit + a, total + b
    return lit / total


@pytest.mark.parametrize("quality", sorted(shafts.SAMPLES))
def test_surface_share_matches_quadrature(surface_want, quality):
    """A ground point in a sphere's shadow under a lamp: the fog over it is partly shadowed.  Many directions
    and nodes converge to the quadrature; each Quality's counts stay within 0.025 of it."""
    assert 0.2 < surface_want < 0.9, surface_want
    fine = surface_got(32, 48)
    assert abs(fine - surface_want) < 0.015, (fine, surface_want)
    got = surface_got(*shafts.samples_for(quality)[1:])
    assert abs(got - surface_want) < 0.025, (quality, got, surface_want)


def test_surface_share_in_open_air_is_exactly_one():
    got = surface_got(*shafts.DEFAULT_SAMPLES[1:], occluders=[((50.0, 50.0, 50.0), 1.0)])
    assert got == 1.0


def test_segment_ending_far_before_the_light_is_dark_behind_an_occluder():
    """A ray aimed at a lamp that ends 5 m before it, the whole segment behind a 0.3 m sphere 2 m from the lamp
    (a lamp hidden behind a wall, seen through nothing): S = 0, and S_far stays in [0, 1].  Its angles lie
    within MAX_ANGLE of -pi/2, where the nodes once sampled the stretch between the segment's end and the
    lamp (S = 1, S_far 1.001)."""
    light, camera, direction = np.array([0.0, 0.0, 3.0]), np.array([0.0, -10.0, 3.0]), np.array([0.0, 1.0, 0.0])
    spec, depth = point_map(light, [((0.0, -2.0, 3.0), 0.3)], shaft_maps.POINT_MAP)
    m = NumpyOps({spec.name: depth})
    s, far = shafts.lit_share(m, camera, direction, 5.0, light, 0.1, (spec, None), 24, g=0.7, tail_nodes=6)
    assert s < 1e-6 and 0.0 <= far <= 1.0, (s, far)


@pytest.mark.parametrize("quality", ["draft", "final", "exact", 0.02])
def test_many_shafted_lights_keep_the_per_pixel_budget(quality):
    """Up to BUDGET_LIGHTS lights take their Quality's own samples; beyond, all of them together evaluate no
    more nodes a pixel than BUDGET_LIGHTS lights at the Quality's own (Draft's is the floor), the samples never
    grow with more lights, and Exact never steps down."""
    own = shafts.samples_for(quality)
    budget = shafts.BUDGET_LIGHTS * shafts.nodes_per_pixel(own)
    last = own
    for n in range(1, 80):
        s = shafts.samples_for(quality, n)
        if quality == "exact" or n <= shafts.BUDGET_LIGHTS:
            assert s == own
        elif s != shafts.SAMPLES["draft"]:
            assert n * shafts.nodes_per_pixel(s) <= budget, (n, s)
        assert shafts.nodes_per_pixel(s) <= shafts.nodes_per_pixel(last), (n, s, last)
        last = s
    assert quality == "exact" or shafts.samples_for(quality, 79) == shafts.SAMPLES["draft"]


# --- an animation's maps (the atlas of shadow_maps.ensure_atlases) -----------------------------------------

def _tile(frame, first, stride, tiles):
    """``shaft_maps.ATLAS_TILE`` evaluated as Blender's simple expressions do (min, max, floor of floats)."""
    return eval(shaft_maps.ATLAS_TILE, {"min": min, "max": max, "floor": math.floor},
                {"frame": float(frame), "s": float(first), "k": float(stride), "n": float(tiles)})


@pytest.mark.parametrize("start,end,step,want", [(1, 10, 1, (1, 1, 10)), (1, 10, 2, (1, 2, 5)), (5, 5, 1, (5, 1, 1)),
                                                 (0, 250, 1, (0, 2, 126)), (1, 300, 1, (1, 3, 100)),
                                                 (1, 1000, 4, (1, 8, 125))])
def test_atlas_frames_hold_every_rendered_frame_up_to_the_cap(start, end, step, want):
    assert shaft_maps.atlas_frames(start, end, step) == want
    first, stride, count = want
    assert count <= shaft_maps.ATLAS_MAX_FRAMES and stride % step == 0
    for frame in range(start - 3, end + 4):   # each frame takes the latest map baked at or before it, clamped
        t = _tile(frame, first, stride, count)
        assert t == min(max((frame - first) // stride, 0), count - 1), frame


@pytest.mark.parametrize("count,size", [(1, (512, 256)), (10, (512, 256)), (100, (512, 256)), (128, (512, 256)),
                                        (37, (256, 256))])
def test_atlas_places_each_map_once_in_a_bounded_image(count, size):
    columns, rows = shaft_maps.atlas_layout(count, *size)
    places = {shaft_maps.atlas_place(t, columns) for t in range(count)}
    assert len(places) == count
    assert all(0 <= c < columns and 0 <= r < rows and 0 <= ch < shaft_maps.ATLAS_CHANNELS for c, r, ch in places)
    assert columns * rows * shaft_maps.ATLAS_CHANNELS - count < columns * shaft_maps.ATLAS_CHANNELS   # no empty row
    assert max(columns * size[0], rows * size[1]) <= shaft_maps.ATLAS_MAX_SIDE
    assert 0.5 <= columns * size[0] / (rows * size[1]) <= 4.0 or count <= shaft_maps.ATLAS_CHANNELS


def _spot_frames(turn_deg, poses=6, tilt_deg=-60.0):
    """(right, up, forward) of a spot tilted down by ``tilt_deg`` and turned about z by 0..``turn_deg``."""
    out = []
    for a in np.radians(np.linspace(0.0, turn_deg, poses)):
        rz = np.array([[math.cos(a), -math.sin(a), 0], [math.sin(a), math.cos(a), 0], [0, 0, 1]])
        t = math.radians(tilt_deg)
        rx = np.array([[1, 0, 0], [0, math.cos(t), -math.sin(t)], [0, math.sin(t), math.cos(t)]])
        out.append(shaft_maps.spot_frame(rz @ rx))
    return out


def test_spot_union_holds_every_pose_cone():
    cos_half = math.cos(math.radians(25.0))
    still = _spot_frames(0.0, poses=1)
    frame, half = shaft_maps.spot_union(still, cos_half)
    assert np.allclose(frame, still[0], atol=1e-9)
    assert half == pytest.approx(shaft_maps.spot_half_width(cos_half) * 1.01)
    frames = _spot_frames(40.0)
    frame, half = shaft_maps.spot_union(frames, cos_half)
    forward = np.asarray(frame[2])
    m = NumpyOps()
    phi = np.linspace(0.0, 2.0 * math.pi, 97)
    for pose in frames:   # every pose's cone (97 directions on its edge, the union took 64) lies inside it
        r, u, f = (np.asarray(v) for v in pose)
        edge = f + math.tan(math.radians(25.0)) * (np.cos(phi)[:, None] * r + np.sin(phi)[:, None] * u)
        x, y = shaft_maps.spot_map_xy(m, edge, frame, half)
        assert (edge @ forward > 0).all() and x.min() > 0 and x.max() < 1 and y.min() > 0 and y.max() < 1
    assert shaft_maps.spot_union(_spot_frames(170.0), cos_half) is None   # too wide: the whole sphere's map


def _random_rotation(rng):
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    return q * np.sign(np.diag(r))


def test_cone_interval_holds_the_cone_and_no_more():
    """``shafts.cone_interval`` (``spot.cone_interval`` in the light's space of ``rows``) against the cone test on
    4 001 points of each ray: every point inside the spot's cone lies in the interval, and the interval reaches no
    farther than the points inside do (one sample spacing), for 400 random spots (rows of a rotation, some scaled)
    and rays, steep and shallow ones; a ray that misses the cone gets an empty interval."""
    rng = np.random.default_rng(7)
    m = NumpyOps()
    t = np.linspace(0.0, 80.0, 4001)
    spacing = t[1] - t[0]
    checked = 0
    for case in range(400):
        rows = _random_rotation(rng) * rng.uniform(0.5, 2.0)   # any positive multiple of the light's space
        cos_half = math.cos(math.radians(rng.uniform(5.0, 80.0)))
        light = rng.uniform(-3.0, 3.0, 3)
        origin = light + rng.uniform(-8.0, 8.0, 3)
        direction = rng.normal(size=3)
        if case % 3 == 0:   # rays along the axis, steeper than the cone
            direction = -rows[2] / np.linalg.norm(rows[2]) + 0.2 * direction
        direction /= np.linalg.norm(direction)
        t_in, t_out = (float(x) for x in shafts.cone_interval(m, origin, direction, light, list(rows), cos_half,
                                                               t[-1]))
        p = (origin - light)[None, :] + t[:, None] * direction[None, :]
        local = p @ rows.T
        inside = -local[:, 2] >= cos_half * np.linalg.norm(local, axis=1)
        if not inside.any():
            assert t_out - t_in <= spacing, (case, t_in, t_out)
            continue
        checked += 1
        ts = t[inside]
        assert t_in <= ts.min() + 1e-6 and ts.max() - 1e-6 <= t_out, (case, t_in, t_out, ts.min(), ts.max())
        assert t_in >= ts.min() - spacing and t_out <= ts.max() + spacing, (case, t_in, t_out, ts.min(), ts.max())
    assert checked > 150


def test_spot_beam_towards_the_camera_matches_quadrature():
    """A spot behind a wall shines through a hole towards the camera (issue 46: dark blobs above a shaded pendant):
    the rays above the beam are lit only in their first metres, the rest of them outside the cone.  The lit share
    with the Quality's 24 nodes against adaptive quadrature with the exact visibility (the hole's square): the mean of
    the 2 x 2 pattern's four shifts within 12 % (the map's 512 grid points place the hole's edge, which these rays
    leave at a grazing angle, to half a grid point: the same integral over the map's visibility on 600 000 points
    is 6.6 % off on the first ray, 0.4 % with 2048 grid points), each shift within 35 %.  With the nodes
    spread over the whole ray (no clip) one node holds a third of the glow: a shift is 0 or 0.34, and the pattern
    shows as blobs where the interleaving's mean cannot make up for it."""
    light = np.array([4.5, 14.0, 2.4])
    forward = np.array([0.5, 4.0, 0.5]) - light
    forward /= np.linalg.norm(forward)
    up = np.array([0.0, 0.0, 1.0]) - forward * forward[2]
    up /= np.linalg.norm(up)
    right = np.cross(up, -forward)
    cos_half, blend = math.cos(math.radians(30.0)), 0.2
    frame = (tuple(right), tuple(up), tuple(forward))
    half = shaft_maps.spot_half_width(cos_half)
    dirs = shaft_maps.spot_map_directions(frame, half)

    def wall(u):   # distance along unit rays u from the light to the wall y = 11 outside the hole, else NO_HIT
        u = np.atleast_2d(u)
        s = (11.2 - light[1]) / np.minimum(u[:, 1], -1e-9)
        x, z = light[0] + s * u[:, 0], light[2] + s * u[:, 2]
        hole = (np.abs(x - 3.5) < 0.5) & (np.abs(z - 2.0) < 0.5)
        return np.where((u[:, 1] < 0) & ~hole, s, shaft_maps.NO_HIT)
    spec = TableSpec("spot", dirs.shape[1], dirs.shape[0])
    m = NumpyOps({spec.name: wall(dirs.reshape(-1, 3)).reshape(dirs.shape[:2])})
    from fog_addon.precompute.physics.spot import spot as spot_
    falloff = lambda mm, u, d: spot_.spot_falloff(mm, mm.dot(u, forward) / d, cos_half, blend)
    rows = (tuple(right), tuple(up), tuple(-forward))
    camera, beta = np.array([-2.0, -1.5, 2.2]), 0.08
    worst, worst_shift = {True: 0.0, False: 0.0}, {True: 0.0, False: 0.0}
    for target in ((1.5, 9.0, 6.0), (0.0, 9.0, 7.5), (3.0, 9.0, 6.5), (-2.0, 9.0, 5.0)):
        direction = np.asarray(target, float) - camera
        direction /= np.linalg.norm(direction)

        def integrand(t, visible):
            u = camera + t * direction - light
            d = np.linalg.norm(u)
            f = float(falloff(NumpyOps(), u, d)) * math.exp(-beta * (t + d)) / (d * d)
            return f * (wall(u / d)[0] > d) if visible else f
        want = (integrate.quad(integrand, 0, 60.0, args=(True,), limit=400, epsabs=0, epsrel=1e-7)[0]
                / integrate.quad(integrand, 0, 60.0, args=(False,), limit=400, epsabs=0, epsrel=1e-9)[0])
        assert 0.05 < want < 0.95, want   # the ray leaves the beam: partly lit
        for clip in (True, False):
            got = np.array([shafts.lit_share(m, camera, direction, 1e6, light, beta, (spec, (frame, half)), 24,
                                             shift=0.125 + 0.25 * k, falloff=falloff,
                                             clip=(lambda mm, *c: (rows, cos_half)) if clip else None)
                            for k in range(4)])
            worst[clip] = max(worst[clip], abs(got.mean() - want) / want)
            worst_shift[clip] = max(worst_shift[clip], float(np.abs(got - want).max()) / want)
    assert worst[True] < 0.12 and worst_shift[True] < 0.35, (worst, worst_shift)
    assert worst_shift[False] > 0.9, worst_shift   # (the test sees what the clip does)
