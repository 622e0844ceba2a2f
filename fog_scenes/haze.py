"""Distance haze (issue 29 item 4): a valley with mountain ridges kilometres away under the sun and the sky of the
daylight city (``fog_scenes.daylight``), in aerosol haze (Mie) and clear air (Rayleigh) thinning with height, and
its Cycles single-scattering references (a mesh box of both species) with the fog-free render beside them.

The scene (:func:`build`; every number in the module's data, so the same scene can be built with the add-on's fog):

* ``GROUND``: a grey Lambertian plane at z = 0 (Principled BSDF, base colour 0.3, roughness 1, Specular IOR Level 0),
  160 km across, centred on the origin;
* ``RIDGES``: five wide axis-aligned Lambertian boxes standing on the ground across the view, their near faces
  1.5 km, 4 km, 9 km, 16 km and 22 km ahead, 1 km deep, 150 m to 4 km tall, staggered left and right so that
  every one is partly seen; albedos 0.2 to 0.5, but ``R16`` (16 km) is black: its pixels show the airlight alone.
  The 22 km ridge spans 1.2 x the view's width at its distance and rises above the top row, so no pixel sees the
  sky (:func:`pixel_hits`);
* ``SUN``, ``WORLD_COLOUR``, ``WORLD_BELOW_HORIZON``: daylight's (strength 3 W/m^2, angle 0.5 degrees, 40 degrees
  up, azimuth -50 degrees: ahead-left, behind the ridges, whose near faces are in their own shade and lit by the
  sky; a uniform sky (0.35, 0.5, 0.8) W/(m^2 sr) over the upper hemisphere, black below the horizon; the World
  is ``daylight._set_world``);
* ``CAMERA``: (0, 0, 300) m, looking along +Y and 4 degrees down, 50 mm lens on a 36 mm sensor (39.6 x 22.9
  degrees), 160 x 90 px, clip 1 mm to 200 km.

The fog (:func:`add_fog`): a mesh box ``FOG_BOX`` 2 000 km on each side of the origin, from z = -1 m (under the
ground, no face coplanar with it) to 60 km, whose volume shader adds two species:

* the haze (``HAZE``, aerosol, Mie): extinction beta_M(z) = beta0 e^{-max(z, 0)/H_M}, beta0 = 3.912 / V for a
  visibility V = 40 km (9.78e-5 /m; Koschmieder's 2 % contrast), H_M = 1200 m, albedo 0.9: Volume Scatter (Color
  white, density 0.9 beta_M, Henyey-Greenstein g = 0.76) + Volume Absorption (Color black, density 0.1 beta_M);
* the clear air (``AIR``, Rayleigh, in the ``haze_air`` case only): Volume Scatter with the Rayleigh phase
  3 (1 + cos^2)/(16 pi), density 33.1e-6 e^{-max(z, 0)/8000} /m and Color (5.8/33.1, 13.5/33.1, 1): Volume
  Scatter's Color scales its density per channel (extinction and scattering alike, for the Rayleigh phase as
  for Henyey-Greenstein), so the scattering coefficients at the ground are (5.8, 13.5, 33.1) x 1e-6 /m, the
  add-on's ``--air 1`` (Bruneton & Neyret 2008 Sec. 2.1; ``fog_addon.precompute.core.medium.RAYLEIGH_RGB``
  and ``RAYLEIGH_HEIGHT``), a pure scatterer.

Both densities come from Geometry Position z through Math nodes (a heterogeneous volume).  Left out above 60 km:
beta0 H_M e^{-50} of haze and 33.1e-6 x 8000 e^{-7.5} = 1.5e-4 of blue air (the sun's transmittance at 40 degrees
2.3e-4 too high in blue).  The box is 2 000 km wide on each side so that it stands for the add-on's flat medium
without sides: with 80 km sides the sky near the horizon reached the air through them (short paths), and the black
ridge's airlight came out 2.3 / 3.5 / 3.8 % (R, G, B) above a quadrature of the unbounded medium (the references
of that box, ``..._air1_vb0_...`` and ``..._air0_vb0_...``, are kept: docs/measurements/2026-11-27-haze-references.md).

Cases (``CASES``): ``haze_air`` (both species: the one that matters) and ``haze_only`` (the haze alone).

**One render per colour channel** (``haze_air``): Cycles 5.0 does not path-trace a mix of phase functions whose
colours differ.  At a scatter point it evaluates its phase closures as one scalar mixture, each weighted by its
channel-averaged weight (``sample_weight``), times the total spectral sigma_s; and a ray it samples from the
phase carries the pdf of the one closure it picked into multiple importance sampling against the World and the
sun (docs/measurements/2026-11-27-haze-references.md).  So a seed of the ``haze_air`` reference is three renders,
one per channel, in each of which every species' Color is that channel alone (the air's density that channel's
coefficient, the haze's absorption that channel's), the World is not sampled as a light (phase and BSDF sampling
reach it) and the sun has no MIS (next-event estimation alone): the mixture is then exact in the channel kept.
``haze_only`` and the fog-free render need none of this.

Renders (``render_reference``, ``render_clear``): daylight's conventions: Cycles CPU, path traced, single
scattering (``fog_addon.reference.set_single_scattering_integrator``: volume bounces 0, one diffuse bounce), the
ground and the ridges hidden from shadow, diffuse, glossy, transmission and volume-scatter rays (no cast shadows,
no interreflection), the fog box seen by every ray, Gaussian 0.01 px filter, no denoising, no clamping, no adaptive
sampling, clip start 1 mm; the mean of ``seeds`` renders with seeds 0, 1, ..., each kept beside it
(``dense.seed_path``).  The fog-free render is the same scene without the box.

Typical use::

    from fog_scenes import haze
    ref = haze.render_reference("haze_air", samples=1024, seeds=12)   # tests/references/haze_...exr
    clear = haze.render_clear()
    haze.build_scene("/tmp/valley.blend", "haze_air", with_fog=False) # render it with the add-on's fog:
    # python -m fog_addon render /tmp/valley.blend --density 9.78e-05 <haze.fog_flags("haze_air")> ...
    hits = haze.pixel_hits()                                           # numpy: each pixel centre's ray and surface
    T = haze.camera_transmittance(hits["dirs"][45, 80], hits["t"][45, 80])

No bpy at import: every Blender job runs in a fresh process through ``render_harness``.  As a script,
``python -m fog_scenes.haze OUT.blend --case haze_air [--fog]`` builds the scene's .blend and
``python -m fog_scenes.haze --cases`` renders the missing cached references and prints their noise.
"""
import argparse
import json
import math
import pathlib
import sys

import numpy as np

from fog_scenes import daylight as dl
from fog_scenes import dense
from fog_scenes import render_harness as h

NAME = "haze"
RESOLUTION = dl.RESOLUTION     # 160 x 90 px
SENSOR_WIDTH_MM = 36.0
CLIP_START_M = 0.001
CLIP_END_M = 200000.0

GROUND = dict(half_width_m=80000.0, albedo=0.3)
SUN = dl.SUN
WORLD_COLOUR = dl.WORLD_COLOUR
WORLD_BELOW_HORIZON = dl.WORLD_BELOW_HORIZON

# x0, x1, y0, y1, height (m), albedo: the camera at (0, 0, 300) looks along +Y.  Each ridge's x-extent is at most
# 1.2 x the view's half width there (0.36 y); R16 is black (its pixels: airlight alone).
RIDGES = [
    dict(name="R01", x0=-650.0, x1=150.0, y0=1500.0, y1=2500.0, height=150.0, albedo=0.3),
    dict(name="R04", x0=100.0, x1=1730.0, y0=4000.0, y1=5000.0, height=500.0, albedo=0.4),
    dict(name="R09", x0=-3890.0, x1=-800.0, y0=9000.0, y1=10000.0, height=1200.0, albedo=0.5),
    dict(name="R16", x0=2500.0, x1=6900.0, y0=16000.0, y1=17000.0, height=2500.0, albedo=0.0),
    dict(name="R22", x0=-9500.0, x1=9500.0, y0=22000.0, y1=23000.0, height=4000.0, albedo=0.2),
]

CAMERA = dict(location=(0.0, 0.0, 300.0), pitch_deg=-4.0, lens_mm=50.0)

# The haze (aerosol, Mie): visibility (m) -> extinction at the ground beta0 = 3.912 / V (1/m), scale height (m),
# single-scattering albedo, Henyey-Greenstein g.  The clear air (Rayleigh) at air = 1: scattering coefficients at
# the ground (1/m, R G B) and scale height (m).
VISIBILITY_M = 40000.0
HAZE = dict(beta0=3.912 / VISIBILITY_M, H=1200.0, albedo=0.9, g=0.76)
AIR = dict(rgb=(5.8e-6, 13.5e-6, 33.1e-6), H=8000.0)

FOG_BOX = dict(half_width_m=2.0e6, bottom_m=-1.0, top_m=60000.0)
FOG_NAME = "FogBox"

# case -> the clear air's density, a multiple of AIR (the add-on's --air)
CASES = {"haze_air": 1.0, "haze_only": 0.0}

# The cached references: (case, samples per render, seeds).  Render times and noise:
# docs/measurements/2026-11-27-haze-references.md.
REFERENCE_CASES = [("haze_air", 1024, 8)]
EXTRA_CASES = [("haze_only", 1024, 2)]


def _case(case):
    if case not in CASES:
        raise ValueError(f"unknown case {case!r}: {sorted(CASES)}")
    return case


def air(case):
    """The clear air's density in ``case``, a multiple of sea-level air (``AIR``)."""
    return CASES[_case(case)]


def fog_flags(case="haze_air"):
    """``python -m fog_addon render``'s flags for the add-on's fog of ``case`` (the haze's anisotropy and albedo,
    a layer of top 0 and falloff H_M: beta0 e^{-z/H_M} above the ground, and the air), besides ``--density``
    (``HAZE["beta0"]``)."""
    return ("--anisotropy", repr(HAZE["g"]), "--color", ",".join([repr(HAZE["albedo"])] * 3), "--fog-top", "0",
            "--height-falloff", repr(HAZE["H"]), "--air", repr(air(case)))


sun_direction = dl.sun_direction


def mie_extinction(z):
    """The haze's extinction beta_M(z) = beta0 e^{-max(z, 0)/H_M} (1/m) at height ``z`` (m)."""
    return HAZE["beta0"] * np.exp(-np.maximum(z, 0.0) / HAZE["H"])


def rayleigh_scattering(z, case="haze_air"):
    """The clear air's (R, G, B) scattering coefficients (1/m) at height ``z`` (m): air x AIR["rgb"]
    e^{-max(z, 0)/H_R}; shape z.shape + (3,)."""
    z = np.asarray(z, np.float64)
    return air(case) * np.array(AIR["rgb"]) * np.exp(-np.maximum(z, 0.0) / AIR["H"])[..., None]


# -- the scene (bpy, in a Blender process) ----------------------------------------------------------------------

def _profile(nt, z, scale_height, factor):
    """Math nodes: factor e^{-max(z, 0)/scale_height} from the socket ``z``."""
    m = dl._math
    return m(nt, 'MULTIPLY', m(nt, 'EXPONENT', m(nt, 'MULTIPLY', m(nt, 'MAXIMUM', z, 0.0), -1.0 / scale_height)),
             factor)


def fog_material(case):
    """The fog box's material (module doc): haze Volume Scatter (white, a beta_M(z), HG g) + Volume Absorption
    (black, (1 - a) beta_M(z)) + (with air) Rayleigh Volume Scatter (Color AIR["rgb"] / its blue, density air x
    blue e^{-z/H_R}).  Needs bpy."""
    import bpy
    mat = bpy.data.materials.new(FOG_NAME)
    if mat.node_tree is None:
        mat.use_nodes = True
    nt = mat.node_tree
    for n in list(nt.nodes):
        nt.nodes.remove(n)
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    geo = nt.nodes.new("ShaderNodeNewGeometry")
    sep = nt.nodes.new("ShaderNodeSeparateXYZ")
    nt.links.new(geo.outputs["Position"], sep.inputs["Vector"])
    z = sep.outputs["Z"]
    mie = nt.nodes.new("ShaderNodeVolumeScatter")
    mie.name = "HazeScatter"
    mie.phase = 'HENYEY_GREENSTEIN'
    mie.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)        # Color scales the density: white
    mie.inputs["Anisotropy"].default_value = HAZE["g"]
    nt.links.new(_profile(nt, z, HAZE["H"], HAZE["beta0"] * HAZE["albedo"]), mie.inputs["Density"])
    ab = nt.nodes.new("ShaderNodeVolumeAbsorption")
    ab.name = "HazeAbsorption"
    ab.inputs["Color"].default_value = (0.0, 0.0, 0.0, 1.0)         # absorbs density x (1 - Color)
    nt.links.new(_profile(nt, z, HAZE["H"], HAZE["beta0"] * (1.0 - HAZE["albedo"])), ab.inputs["Density"])
    shader = nt.nodes.new("ShaderNodeAddShader")
    nt.links.new(mie.outputs["Volume"], shader.inputs[0])
    nt.links.new(ab.outputs["Volume"], shader.inputs[1])
    if air(case) > 0.0:
        rgb = AIR["rgb"]
        ray = nt.nodes.new("ShaderNodeVolumeScatter")
        ray.name = "AirScatter"
        ray.phase = 'RAYLEIGH'
        ray.inputs["Color"].default_value = (rgb[0] / rgb[2], rgb[1] / rgb[2], 1.0, 1.0)   # per-channel density
        density = _profile(nt, z, AIR["H"], air(case) * rgb[2])
        density.node.name = "AirDensity"                                  # its input 1: the ground's density
        nt.links.new(density, ray.inputs["Density"])
        both = nt.nodes.new("ShaderNodeAddShader")
        nt.links.new(shader.outputs["Shader"], both.inputs[0])
        nt.links.new(ray.outputs["Volume"], both.inputs[1])
        shader = both
    nt.links.new(shader.outputs["Shader"], out.inputs["Volume"])
    return mat


def add_fog(scene, case):
    """Add the fog box of ``case`` (module doc) to ``scene``, seen by every ray type; needs bpy."""
    from demo_scenes import add_box_between
    w = FOG_BOX["half_width_m"]
    ob = add_box_between(scene, FOG_NAME, -w, w, -w, w, FOG_BOX["bottom_m"], FOG_BOX["top_m"], fog_material(case))
    for attr in ("visible_camera", "visible_shadow", "visible_diffuse", "visible_glossy", "visible_transmission",
                 "visible_volume_scatter"):
        setattr(ob, attr, True)
    return ob


def _add_sun(scene):
    """daylight's Sun light (SUN): shines along -sun_direction(), shadows on.  Needs bpy."""
    import bpy
    from mathutils import Vector
    ld = bpy.data.lights.new("Sun", 'SUN')
    ld.energy = SUN["strength_w_m2"]
    ld.angle = math.radians(SUN["angle_deg"])
    ld.use_shadow = True
    ld.color = (1.0, 1.0, 1.0)
    sun = bpy.data.objects.new("Sun", ld)
    sun.rotation_euler = Vector(-sun_direction()).to_track_quat('-Z', 'Y').to_euler()   # shines along local -Z
    scene.collection.objects.link(sun)
    return sun


def build(scene, case="haze_air", with_fog=True, samples=1024, resolution=RESOLUTION, cast_shadows=False,
          interreflection=False):
    """Fill ``scene`` with the valley, the sun, the sky and the camera (and ``case``'s fog box if ``with_fog``),
    set up as the single-scattering reference (module doc) at ``samples`` spp.  ``cast_shadows`` /
    ``interreflection`` False: the add-on's test conventions.  Needs bpy."""
    import bpy
    from mathutils import Vector
    from demo_scenes import add_box_between, add_camera, add_plane, material, render_settings
    from fog_addon import reference
    _case(case)
    render_settings(scene, resolution=resolution)
    dl._set_world(scene)
    g = GROUND["half_width_m"]
    ground = add_plane(scene, "Ground", -g, g, -g, g, 0.0,
                       material("Ground", (GROUND["albedo"],) * 3, roughness=1.0, specular_ior_level=0.0))
    solids = [ground]
    mats = {}
    for r in RIDGES:
        a = r["albedo"]
        if a not in mats:
            mats[a] = material(f"Ridge {a:g}", (a,) * 3, roughness=1.0, specular_ior_level=0.0)
        solids.append(add_box_between(scene, r["name"], r["x0"], r["x1"], r["y0"], r["y1"], 0.0, r["height"],
                                      mats[a]))
    sun = _add_sun(scene)
    loc = Vector(CAMERA["location"])
    cam = add_camera(scene, tuple(loc), tuple(loc + Vector(camera_basis()[0])), lens=CAMERA["lens_mm"])
    cam.data.sensor_width = SENSOR_WIDTH_MM
    cam.data.clip_start = CLIP_START_M
    cam.data.clip_end = CLIP_END_M
    scene.view_settings.view_transform = 'Standard'
    scene.view_settings.look = 'None'
    reference.set_single_scattering_integrator(scene, samples, single_scattering=True)
    for ob in solids:
        ob.visible_shadow = bool(cast_shadows)
        ob.visible_diffuse = ob.visible_glossy = ob.visible_transmission = bool(interreflection)
        ob.visible_volume_scatter = False
    if with_fog:
        add_fog(scene, case)
    scene.render.film_transparent = False
    bpy.context.view_layer.update()
    s = sun.matrix_world.to_3x3().col[2]    # local +Z: towards the sun
    assert max(abs(a - b) for a, b in zip(s.normalized(), sun_direction())) < 1e-6, s
    return scene


def build_scene(path, case="haze_air", with_fog=True, samples=1024):
    """Save the scene of ``case`` as ``path`` (.blend), with its fog box or without (``with_fog``), in a fresh
    Blender process; returns the path."""
    path = pathlib.Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    args = ["-m", "fog_scenes.haze", path, "--case", _case(case), "--samples", int(samples)]
    if with_fog:
        args.append("--fog")
    h.run(args)
    return path


def _workdir():
    d = pathlib.Path(h._env()["TMPDIR"]) / "fog_haze"
    d.mkdir(parents=True, exist_ok=True)
    return d


def blend_path(case="haze_air", with_fog=True, workdir=None):
    """Path of ``case``'s .blend (with its fog, or the fog-free scene) in ``workdir`` (default: the harness's
    scratch folder), built if missing."""
    workdir = pathlib.Path(workdir) if workdir else _workdir()
    blend = workdir / f"{NAME}_{_case(case) if with_fog else 'clear'}.blend"
    if not blend.is_file():
        build_scene(blend, case, with_fog=with_fog)
    return blend


# -- references -----------------------------------------------------------------------------------------------

_SEED_CODE = r'''
import sys, json, time
import numpy as np
import bpy
from fog_addon import imageio, measure
a = json.loads(sys.argv[1])
scene = measure.open_scene(a["blend"])
measure.set_resolution(scene, *a["resolution"])
c = scene.cycles
c.samples = a["samples"]
c.seed = a["seed"]
c.use_animated_seed = False
assert c.volume_bounces == 0 and c.max_bounces == 1 and not c.use_adaptive_sampling
assert abs(scene.camera.data.clip_start - 0.001) < 1e-9 and scene.camera.data.clip_end >= 200000.0
assert ("FogBox" in bpy.data.objects) == a["fog"]
if a["fog"]:
    phases = sorted(n.phase for n in bpy.data.objects["FogBox"].active_material.node_tree.nodes
                    if n.bl_idname == "ShaderNodeVolumeScatter")
    assert phases == a["phases"], phases
t0 = time.perf_counter()
if not a["split"]:
    measure.render_to_file(scene, a["out"])
else:
    # one render per colour channel, each fog species' Color (and the air's density) that channel's alone;
    # lights without MIS (the sun by next-event estimation only, the World by phase and BSDF sampling only)
    scene.world.cycles.sampling_method = 'NONE'
    for ob in scene.objects:
        if ob.type == 'LIGHT':
            ob.data.cycles.use_multiple_importance_sampling = False
    nodes = bpy.data.objects["FogBox"].active_material.node_tree.nodes
    out = None
    for ch in range(3):
        e = [0.0, 0.0, 0.0]
        e[ch] = 1.0
        nodes["HazeScatter"].inputs["Color"].default_value = (*e, 1.0)
        nodes["HazeAbsorption"].inputs["Color"].default_value = (*[1.0 - v for v in e], 1.0)
        nodes["AirScatter"].inputs["Color"].default_value = (*e, 1.0)
        nodes["AirDensity"].inputs[1].default_value = a["air_rgb"][ch]
        tmp = a["out"] + ".ch%d.exr" % ch
        measure.render_to_file(scene, tmp)
        img = imageio.read(tmp)
        if out is None:
            out = img.copy()
        out[..., ch] = img[..., ch]
        import os
        os.remove(tmp)
    imageio.write_exr(a["out"], out)
print("RENDER_SECONDS %.2f" % (time.perf_counter() - t0))
'''


def reference_name(case, samples, seeds, resolution=RESOLUTION):
    """File name of a cached fog reference, its parameters in it."""
    w, hh = resolution
    return (f"{NAME}_V{VISIBILITY_M / 1000:g}km_H{HAZE['H']:g}_g{HAZE['g']:g}_a{HAZE['albedo']:g}"
            f"_air{air(case):g}_box{FOG_BOX['half_width_m'] / 1000:g}km_vb0_{w}x{hh}_{int(samples)}spp"
            f"_x{int(seeds)}.exr")


def clear_name(samples, seeds, resolution=RESOLUTION):
    """File name of the cached fog-free render."""
    w, hh = resolution
    return f"{NAME}_clear_{w}x{hh}_{int(samples)}spp_x{int(seeds)}.exr"


def _render_seeds(blend, path, samples, seeds, case, regen=False, times=None, timeout=3600):
    """Render ``blend`` (``case``'s fog, or none for ``case`` None) with seeds 0 .. seeds-1 (each kept as
    ``dense.seed_path``) and write their mean to ``path`` (``render_harness.mean_of_seeds``); returns ``path``."""
    path = pathlib.Path(path)
    if path.is_file() and not regen:
        return path
    split = bool(case) and air(case) > 0.0
    phases = sorted(["HENYEY_GREENSTEIN"] + (["RAYLEIGH"] if split else []))

    def render_seed(seed, out):
        args = dict(blend=str(blend), out=str(out), samples=int(samples), seed=int(seed), resolution=list(RESOLUTION),
                    fog=case is not None, phases=phases, split=split,
                    air_rgb=[air(case) * b for b in AIR["rgb"]] if split else None)
        return h.render_seconds(h.run(["-c", _SEED_CODE, json.dumps(args)], timeout=timeout))

    return h.mean_of_seeds(path, render_seed, seeds, regen, times)


def render_reference(case="haze_air", samples=1024, seeds=2, regen=False, directory=None, times=None, timeout=3600):
    """Path of the cached single-scattering Cycles reference of ``case`` (module doc), rendering its missing
    seeds (``samples`` spp each, seeds 0 .. seeds-1, kept beside it as ``dense.seed_path``) and their mean.
    ``times``: a list to which each new render's seconds are appended."""
    directory = pathlib.Path(directory) if directory else h.REFERENCES
    path = directory / reference_name(case, samples, seeds)
    if path.is_file() and not regen:
        return path
    return _render_seeds(blend_path(case, True), path, samples, seeds, case, regen, times, timeout)


def render_clear(samples=1024, seeds=2, regen=False, directory=None, times=None, timeout=3600):
    """Path of the cached fog-free render (the same scene and settings without the fog box; the mean of ``seeds``
    renders of ``samples`` spp, each kept beside it)."""
    directory = pathlib.Path(directory) if directory else h.REFERENCES
    path = directory / clear_name(samples, seeds)
    if path.is_file() and not regen:
        return path
    return _render_seeds(blend_path("haze_air", False), path, samples, seeds, None, regen, times, timeout)


def reference_seeds(case="haze_air", samples=1024, seeds=2, **kw):
    """The seeds' renders ((H, W, 3) arrays) of the cached reference (:func:`render_reference`)."""
    from fog_addon import imageio
    path = render_reference(case, samples, seeds, **kw)
    return [imageio.read_rgb(dense.seed_path(path, i)) for i in range(int(seeds))]


seed_noise = dl.seed_noise


# -- pixels, surfaces and transmittance (numpy) ---------------------------------------------------------------

def camera_basis():
    """(forward, right, up) unit world vectors of ``CAMERA``: yaw 0 (+Y), its pitch, no roll."""
    p = math.radians(CAMERA["pitch_deg"])
    fwd = np.array([0.0, math.cos(p), math.sin(p)])
    right = np.array([1.0, 0.0, 0.0])
    return fwd, right, np.cross(right, fwd)


def pixel_rays(resolution=RESOLUTION):
    """(H, W, 3) unit world directions of the camera rays through the pixel centres (row 0 = top); the sensor
    SENSOR_WIDTH_MM wide, fit horizontally."""
    w, hh = resolution
    fwd, right, up = camera_basis()
    t = SENSOR_WIDTH_MM / (2.0 * CAMERA["lens_mm"]) / (w / 2.0)   # tan per pixel at the centre
    y, x = np.mgrid[0:hh, 0:w]
    d = fwd + ((x + 0.5 - w / 2.0) * t)[..., None] * right + ((hh / 2.0 - (y + 0.5)) * t)[..., None] * up
    return d / np.linalg.norm(d, axis=-1, keepdims=True)


def pixel_hits(resolution=RESOLUTION):
    """What each pixel centre's camera ray meets first, by ray casting the scene's data (no bpy):
    ``daylight.cast_boxes`` over the ground and RIDGES (kind i + 1: ridge RIDGES[i])."""
    return dl.cast_boxes(np.array(CAMERA["location"], np.float64), pixel_rays(resolution), GROUND, RIDGES)


def camera_transmittance(direction, distance, case="haze_air"):
    """(R, G, B) transmittance exp(-tau) of the fog between the camera and the point ``distance`` m along the unit
    ``direction``: tau = int_0^distance beta_M(z(s)) + beta_R(z(s)) ds by adaptive quadrature (scipy quad), the
    haze and the air of ``case`` (an independent check of the references' attenuation)."""
    from scipy.integrate import quad
    o = np.array(CAMERA["location"], np.float64)
    d = np.asarray(direction, np.float64)
    tau_m = quad(lambda s: float(mie_extinction(o[2] + s * d[2])), 0.0, float(distance), epsabs=0, epsrel=1e-10,
                 limit=200)[0]
    tau = []
    for c in range(3):
        tau.append(tau_m + quad(lambda s: float(rayleigh_scattering(o[2] + s * d[2], case)[c]), 0.0,
                                float(distance), epsabs=0, epsrel=1e-10, limit=200)[0])
    return np.exp(-np.array(tau))


def main(argv=None):
    p = argparse.ArgumentParser(description="build the haze valley's .blend, or render its references")
    p.add_argument("out", nargs="?", help="the .blend to write")
    p.add_argument("--case", default="haze_air", choices=sorted(CASES))
    p.add_argument("--fog", action="store_true", help="add the case's fog box")
    p.add_argument("--samples", type=int, default=1024)
    p.add_argument("--cases", action="store_true", help="render REFERENCE_CASES and the clear image if missing")
    p.add_argument("--extra", action="store_true", help="with --cases: EXTRA_CASES too")
    a = p.parse_args(argv)
    if a.cases:
        from fog_addon import imageio
        for case, samples, seeds in REFERENCE_CASES + (EXTRA_CASES if a.extra else []):
            for kind, fn in (("clear", lambda *x, **k: render_clear(*x[1:], **k)), ("fog", render_reference)):
                times = []
                ref = fn(case, samples, seeds, times=times)
                s = [imageio.read_rgb(dense.seed_path(ref, i)) for i in range(seeds)]
                print(kind, case, ref.name, "new render seconds", times, flush=True)
                print("  noise", {k: round(v, 5) for k, v in seed_noise(s).items()}, flush=True)
        return 0
    if not a.out:
        p.error("give OUT.blend or --cases")
    import bpy
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    build(scene, a.case, with_fog=a.fog, samples=a.samples)
    h.save_blend(a.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
