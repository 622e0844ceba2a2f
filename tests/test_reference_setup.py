"""The path-traced reference against quadrature of Sun et al. Eq. 5, and CLI input checks.

Probe scenes are built in a fresh Blender process (render_harness.run_bpy_code),
configured with fog_addon.reference.configure_reference, rendered with
fog_addon.measure, and each pixel is compared with scipy quadrature along its
own camera ray (pixel-centre filter).
"""
import json
import math

import numpy as np
import pytest
from scipy import integrate, special

from fog_scenes import render_harness as rh
from fog_addon import compare, imageio

pytestmark = pytest.mark.render   # every test here starts Blender (bpy) in a subprocess

# Builds a probe scene, makes it the reference, renders it, and dumps the camera.
# argv: out.exr out.json mode density samples W H
PROBE = r'''
import json, math, sys
import bpy
from mathutils import Vector
from fog_addon import measure, reference
out, meta, mode, density, samples, W, H = sys.argv[1], sys.argv[2], sys.argv[3], float(sys.argv[4]), int(sys.argv[5]), int(sys.argv[6]), int(sys.argv[7])
bpy.ops.wm.read_factory_settings(use_empty=True)
scene = bpy.context.scene
world = bpy.data.worlds.new("W"); scene.world = world
if world.node_tree is None: world.use_nodes = True
bg = world.node_tree.nodes["Background"]; bg.inputs["Color"].default_value = (0.0, 0.0, 0.0, 1.0)
light = bpy.data.lights.new("L", "POINT"); light.energy = 1000.0; light.shadow_soft_size = 0.0
lo = bpy.data.objects.new("L", light); scene.collection.objects.link(lo); lo.location = (0, 0, 0)
cam = bpy.data.cameras.new("C"); co = bpy.data.objects.new("C", cam); scene.collection.objects.link(co); scene.camera = co
info = {"power": 1000.0, "light": [0.0, 0.0, 0.0]}
if mode == "airlight":
    # camera 5 m from the lamp, looking 30 degrees past it (pure airlight, nothing behind)
    co.location = (0.0, -5.0, 0.0)
    d = Vector((math.sin(math.radians(30)), math.cos(math.radians(30)), 0.0))
    cam.lens = 50.0
elif mode == "plane":
    # white Lambertian plane 2 m below the lamp, orthographic camera 5 cm above it, looking down
    mat = bpy.data.materials.new("White")
    if mat.node_tree is None: mat.use_nodes = True
    b = mat.node_tree.nodes["Principled BSDF"]
    b.inputs["Base Color"].default_value = (1, 1, 1, 1); b.inputs["Specular IOR Level"].default_value = 0.0
    b.inputs["Roughness"].default_value = 1.0
    me = bpy.data.meshes.new("P"); me.from_pydata([(-50,-50,-2),(50,-50,-2),(50,50,-2),(-50,50,-2)], [], [(0,1,2,3)])
    me.materials.append(mat); po = bpy.data.objects.new("P", me); scene.collection.objects.link(po)
    cam.type = "ORTHO"; cam.ortho_scale = 4.0
    co.location = (2.0, 0.0, -1.95)
    d = Vector((0.0, 0.0, -1.0))
    info["plane_z"] = -2.0
co.rotation_euler = d.to_track_quat("-Z", "Y").to_euler()
measure.set_resolution(scene, W, H)
reference.configure_reference(scene, density, samples=samples)
bpy.context.view_layer.update()
measure.render_to_file(scene, out)
info.update(matrix=[list(r) for r in co.matrix_world], lens=cam.lens, sensor=cam.sensor_width,
            type=cam.type, ortho_scale=cam.ortho_scale, clip_start=cam.clip_start, W=W, H=H)
json.dump(info, open(meta, "w"))
'''


def run_probe(tmp_path, mode, density, samples, W, H):
    out, meta = tmp_path / f"{mode}.exr", tmp_path / f"{mode}.json"
    rh.run_bpy_code(PROBE, out, meta, mode, density, samples, W, H)
    return imageio.read_rgb(out), json.loads(meta.read_text())


def camera_rays(info):
    """Origins and unit directions of every pixel centre (row 0 = top), as in Cycles."""
    W, H = info["W"], info["H"]
    M = np.array(info["matrix"])
    R, C = M[:3, :3], M[:3, 3]
    u = ((np.arange(W) + 0.5) / W - 0.5)
    v = (0.5 - (np.arange(H) + 0.5) / H) * H / W
    U, V = np.meshgrid(u, v)
    if info["type"] == "ORTHO":
        s = info["ortho_scale"]
        local_o = np.stack([U * s, V * s, np.zeros_like(U)], -1)
        o = local_o @ R.T + C
        d = np.broadcast_to(-R[:, 2], o.shape)
        return o, np.array(d)
    k = info["sensor"] / info["lens"]
    local = np.stack([U * k, V * k, -np.ones_like(U)], -1)
    d = local @ R.T
    d /= np.linalg.norm(d, axis=-1, keepdims=True)
    return np.broadcast_to(C, d.shape), d


def airlight_quad(o, d, light, beta, I0, t_max=np.inf):
    """Sun Eq. 5: beta I0/(4 pi) int_0^tmax exp(-beta r(x) - beta x) / r(x)^2 dx."""
    D = o - light
    b = float(np.dot(D, d))
    c = float(np.dot(D, D))

    def f(x):
        r2 = c + 2 * b * x + x * x
        return math.exp(-beta * math.sqrt(r2) - beta * x) / r2
    # split at the closest approach so quad sees the peak
    xm = max(0.0, -b)
    pts = [0.0, xm, xm + 10.0, t_max] if math.isinf(t_max) else sorted({0.0, min(xm, t_max), t_max})
    total = 0.0
    for a, z in zip(pts[:-1], pts[1:]):
        if z > a:
            total += integrate.quad(f, a, z, limit=200, epsabs=0, epsrel=1e-10)[0]
    return beta * I0 / (4 * math.pi) * total


def fog_irradiance_on_plane(x, light, beta, I0, n_alpha=48, n_psi=48):
    """Irradiance at x (plane normal +Z) from light single-scattered by the fog
    over the upper hemisphere (no occlusion).  Directions are taken in polar
    coordinates (alpha, psi) about the direction to the light, where the
    airlight peaks like 1/alpha (cancelled by sin alpha); Gauss-Legendre in
    alpha on [0, a1] and [a1, pi], midpoint in psi, scipy quad along each ray."""
    a_dir = (light - x) / np.linalg.norm(light - x)
    t1 = np.cross(a_dir, [1.0, 0.0, 0.0] if abs(a_dir[0]) < 0.9 else [0.0, 1.0, 0.0])
    t1 /= np.linalg.norm(t1)
    t2 = np.cross(a_dir, t1)
    g, wg = special.roots_legendre(n_alpha)
    nodes, weights = [], []
    for a0, a1 in [(0.0, 0.3), (0.3, math.pi)]:
        nodes += list(a0 + (a1 - a0) * 0.5 * (g + 1))
        weights += list((a1 - a0) * 0.5 * wg)
    psi = (np.arange(n_psi) + 0.5) * 2 * math.pi / n_psi
    E = 0.0
    for al, wa in zip(nodes, weights):
        sa, ca = math.sin(al), math.cos(al)
        for p in psi:
            w = ca * a_dir + sa * (math.cos(p) * t1 + math.sin(p) * t2)
            if w[2] <= 0:
                continue
            E += wa * sa * (2 * math.pi / n_psi) * w[2] * airlight_quad(x, w, light, beta, I0)
    return E


def test_airlight_matches_quadrature(tmp_path):
    """Pure airlight (lamp 5 m away, view 30 degrees past it): every pixel vs Eq. 5."""
    beta = 0.1
    img, info = run_probe(tmp_path, "airlight", beta, 256, 24, 16)
    I0 = info["power"] / (4 * math.pi)
    o, d = camera_rays(info)
    light = np.array(info["light"])
    exp = np.array([[airlight_quad(o[j, i], d[j, i], light, beta, I0) for i in range(info["W"])]
                    for j in range(info["H"])])
    ratio = img[..., 0] / exp
    assert np.allclose(img[..., 0], img[..., 1]) and np.allclose(img[..., 0], img[..., 2])
    assert abs(np.median(ratio) - 1) < 2e-3, np.median(ratio)
    assert np.percentile(np.abs(ratio - 1), 95) < 6e-3
    assert abs(img[..., 0].sum() / exp.sum() - 1) < 2e-3


def test_plane_receives_fog_scattered_light(tmp_path):
    """A white Lambertian plane 2 m below the lamp: radiance = (direct + fog-scattered
    irradiance)/pi, attenuated, plus 5 cm of airlight.  Checks the one-bounce setup.
    Fog-lit surfaces are noisy (about 1 % per pixel at 4096 spp), so the mean ratio
    over 16 pixels is tested tightly and single pixels loosely."""
    beta = 0.15
    img, info = run_probe(tmp_path, "plane", beta, 4096, 8, 8)
    I0 = info["power"] / (4 * math.pi)
    o, d = camera_rays(info)
    light = np.array(info["light"])
    zc = info["plane_z"]
    ratios, ratios_nofog = [], []
    for j in range(0, 8, 2):
        for i in range(1, 8, 2):
            oo, dd = o[j, i], d[j, i]
            t = (zc - oo[2]) / dd[2]
            x = oo + t * dd
            r = np.linalg.norm(light - x)
            cos = (light[2] - x[2]) / r
            E_dir = I0 * cos / r**2 * math.exp(-beta * r)
            E_fog = fog_irradiance_on_plane(x, light, beta, I0, n_alpha=24, n_psi=32)
            air = airlight_quad(oo, dd, light, beta, I0, t_max=t)
            meas = float(img[j, i, 0])
            ratios.append(meas / ((E_dir + E_fog) / math.pi * math.exp(-beta * t) + air))
            ratios_nofog.append(meas / (E_dir / math.pi * math.exp(-beta * t) + air))
    ratios = np.array(ratios)
    assert abs(ratios.mean() - 1) < 0.01, ratios
    assert np.all(np.abs(ratios - 1) < 0.06), ratios
    assert np.mean(ratios_nofog) > 1.3   # the fog-lit term is really there (about +50 % here)


def _cli(*args):
    return rh.run(["-m", "fog_addon"] + list(args), check=False, timeout=120)


@pytest.fixture(scope="module")
def tiny_blend(tmp_path_factory):
    p = tmp_path_factory.mktemp("cli") / "tiny.blend"
    rh.run_bpy_code("import bpy, sys\nbpy.ops.wm.read_factory_settings()\n"
                    "bpy.ops.wm.save_as_mainfile(filepath=sys.argv[1])", p)
    return p


@pytest.mark.parametrize("args, message", [
    (["--density", "nan"], "finite"),
    (["--density", "inf"], "finite"),
    (["--density", "-0.1"], ">= 0"),
    (["--density", "abc"], "number"),
    (["--preset", "smog"], "unknown preset"),
    (["--density", "0.1", "--anisotropy", "1.3"], "anisotropy"),
    (["--density", "0.1", "--samples", "0"], "positive"),
    (["--density", "0.1", "--resolution", "64by36"], "resolution"),
    ([], "--density"),
])
def test_reference_cli_bad_input(tiny_blend, tmp_path, args, message):
    p = _cli("reference", tiny_blend, *args, "--out", tmp_path / "o.exr")
    assert p.returncode == 2, p.stderr
    assert message in p.stderr
    assert "Traceback" not in p.stderr


def test_cli_missing_files(tmp_path):
    p = _cli("reference", tmp_path / "missing.blend", "--density", "0.1", "--out", tmp_path / "o.exr")
    assert p.returncode == 2 and "not found" in p.stderr
    p = _cli("render", tmp_path / "missing.blend", "--engine", "cycles", "--density", "0.1",
             "--out", tmp_path / "o.png")
    assert p.returncode == 2 and "not found" in p.stderr
    p = _cli("compare", tmp_path / "a.exr", tmp_path / "b.exr")
    assert p.returncode == 2 and "not found" in p.stderr


def test_render_cli_bad_input(tiny_blend, tmp_path):
    p = _cli("render", tiny_blend, "--engine", "cycles", "--density", "0.1", "--anisotropy", "-1.5",
             "--out", tmp_path / "o.png")
    assert p.returncode == 2 and "anisotropy" in p.stderr
    p = _cli("render", tiny_blend, "--engine", "luxcore", "--density", "0.1", "--out", tmp_path / "o.png")
    assert p.returncode == 2 and "engine" in p.stderr
    p = _cli("render", tiny_blend, "--engine", "eevee", "--density", "0.1", "--out", tmp_path / "o.jpg")
    assert p.returncode == 2 and ".exr or .png" in p.stderr


def test_compare_cli(tmp_path):
    rng = np.random.default_rng(0)
    b = rng.uniform(0.5, 1.5, (9, 16, 3)).astype(np.float32)
    a = b * 1.01
    imageio.write_exr(tmp_path / "a.exr", a)
    imageio.write_exr(tmp_path / "b.exr", b)
    p = _cli("compare", tmp_path / "a.exr", tmp_path / "b.exr", "--diff", tmp_path / "d.png")
    assert p.returncode == 0, p.stderr
    assert "relative RMSE 0.0100" in p.stdout
    assert (tmp_path / "d.png").is_file()
    m = compare.metrics(a, b)
    assert m["rel_rmse"] == pytest.approx(0.01, rel=1e-5)
    assert m["median_rel"] == pytest.approx(0.01, rel=1e-5)
    assert m["mean_ratio"] == pytest.approx(1.01, rel=1e-6)
    imageio.write_exr(tmp_path / "c.exr", b[:4])
    p = _cli("compare", tmp_path / "c.exr", tmp_path / "b.exr")
    assert p.returncode == 2 and "sizes differ" in p.stderr


GI_PROBE = r'''
import sys
import bpy
import numpy as np
from fog_addon import measure, reference, imageio
blend, outdir = sys.argv[1], sys.argv[2]
names = []
for name, interreflection, max_bounces in [("nogi", False, 1), ("direct", False, 0), ("gi", True, 1)]:
    scene = measure.open_scene(blend)
    measure.set_resolution(scene, 48, 27)
    reference.configure_reference(scene, 0.0, samples=64)
    reference.disable_cast_shadows(scene)
    if not interreflection:
        reference.disable_interreflection(scene)
    scene.cycles.max_bounces = max_bounces
    measure.render_to_file(scene, f"{outdir}/{name}.exr")
'''


def test_interreflection_switch(tmp_path):
    """Without fog, the reference with interreflection disabled is pure direct
    lighting (= max_bounces 0), and enabling it adds sphere-to-sphere light."""
    blend = rh.scene_blend("spheres", tmp_path)
    rh.run_bpy_code(GI_PROBE, blend, tmp_path)
    nogi, direct, gi = (imageio.read_rgb(tmp_path / f"{n}.exr") for n in ("nogi", "direct", "gi"))
    assert compare.metrics(nogi, direct)["rel_rmse"] < 1e-3
    assert gi.sum() > nogi.sum() * 1.001


def test_cached_references(regen):
    """Every cached reference exists (rendered if missing / --regen-references), is
    64x36, finite and positive (the world background is extinguished by the fog,
    the airlight is everywhere > 0)."""
    for scene, density in rh.REFERENCE_CASES:
        p = rh.ensure_reference(scene, density, regen=regen)
        img = imageio.read_rgb(p)
        assert img.shape == (rh.TEST_RESOLUTION[1], rh.TEST_RESOLUTION[0], 3)
        assert np.isfinite(img).all() and img.min() > 0
