"""Daylight fog (issue 29): a city in the morning under a sun and a sky, in a layer of fog with a top, and its Cycles
single-scattering references (a mesh box of fog) with the fog-free renders beside them.

The scene (:func:`build`; every number in the module's data, so the same scene can be built with the add-on's fog):

* ``GROUND``: a grey Lambertian plane at z = 0 (Principled BSDF, base colour 0.3, roughness 1, Specular IOR Level 0),
  20 km across, centred on the origin;
* ``BUILDINGS``: ten axis-aligned Lambertian boxes standing on the ground, 20 m to 200 m from the inside camera,
  albedos 0.25 to 0.6; four of them (120 m to 200 m tall) rise out of either layer's top;
* ``SUN``: a Sun light of strength 3 W/m^2 (irradiance on a surface facing it), angle 0.5 degrees, 40 degrees above
  the horizon, ahead of the cameras and to their left (azimuth -50 degrees from +Y towards +X), shadows on;
* ``WORLD_COLOUR``: a uniform sky of radiance (0.35, 0.5, 0.8) W/(m^2 sr) over the upper hemisphere (World
  Background, strength 1) and black below the horizon (``WORLD_BELOW_HORIZON``).  The test conventions hide the
  ground from diffuse rays (below), so without that a wall would receive the World from under the ground through
  the fog down to the box's bottom; with it every surface sees the sky of the kernels (daylight.sky_source: a
  uniform upper hemisphere, a black ground).  World Light reaches surfaces (Cycles always lights them with the
  World).  No World volume (an unbounded one swallows the sun and the sky).
* ``CAMERAS``: ``inside`` 1.6 m above the ground, looking along +Y and 2 degrees up (24 mm lens on a 36 mm sensor:
  74 x 46 degrees); ``above``: 250 m high, 300 m behind the origin, looking along +Y and 25 degrees down (30 mm:
  62 x 37 degrees).  Clip 1 mm to 20 km (a new camera's 100 m clip end cuts the fog, the buildings and the sky).

The fog (:func:`add_fog`, ``LAYER``): a mesh box ``FOG_BOX_HALF_WIDTH_M`` = 5 km on each side of the origin, from
``FOG_BOX_BOTTOM_M`` = -1 m (under the ground, no face coplanar with it) to the layer's top, whose volume shader is
Volume Scatter (Color white, density a beta(z), Henyey-Greenstein g) plus Volume Absorption (Color black,
density (1 - a) beta(z)): extinction beta(z), albedo a.  Two profiles (``PROFILES``):

* ``hard``: beta0 = 0.01 /m up to h0 = 100 m, nothing above (the box's top is h0; a homogeneous volume);
* ``falloff``: beta0 up to h0 = 60 m, beta0 e^{-(z - h0)/H} above, H = 50 m (Geometry Position z -> Math nodes in
  the density: a heterogeneous volume); the box's top at h0 + 8 H = 460 m, so the column left out above it is
  beta0 H e^{-8} = 1.7e-4 of optical depth (1.5e-4 of the layer's 1.1; the sun's transmittance at 40 degrees is
  2.6e-4 too high, the sky's less).

The box is 5 km wide on each side so that every fog that matters lies in it: a level ray inside the layer is at
optical depth 50 when it leaves the box; the above camera's highest rays meet the ground 2.2 km ahead.

Renders (``render_reference``, ``render_clear``): Cycles CPU, path traced, single scattering in
``fog_addon.reference``'s convention: ``volume_bounces`` 0 and one diffuse bounce (``max_bounces`` =
``diffuse_bounces`` = ``glossy_bounces`` = 1), so a camera ray meeting a surface takes the sun's and the sky's
direct light through the fog and the light the fog scatters onto it (Sun et al. 2005 Sec. 4); the add-on's test
conventions (``--no-cast-shadows --no-interreflection``): the ground and the buildings are hidden from shadow,
diffuse, glossy, transmission and volume-scatter rays (no cast shadows, no shafts, no interreflection), the fog
box is seen by every ray (hidden from shadow rays, Cycles would not dim the sun through it); pixel-centre filter
(Gaussian 0.01 px), no denoising, no clamping, no adaptive sampling, clip start 1 mm; the mean of ``seeds`` renders
with Cycles seeds 0, 1, ..., each seed's render kept beside it (``dense.seed_path``).  The fog-free render of a
camera is the same scene without the box at the same settings.

Typical use::

    from fog_scenes import daylight as dl
    case = dl.Case("hard", 0.0, "inside")
    ref = dl.render_reference(case, samples=1024, seeds=2)     # tests/references/daylight_...exr
    clear = dl.render_clear(case)
    dl.build_scene("/tmp/city.blend", case, with_fog=False)    # render it with the add-on's fog
    hits = dl.pixel_hits("inside")                            # numpy: each pixel centre's ray and surface

No bpy at import: every Blender job runs in a fresh process through ``render_harness``.  As a script,
``python -m fog_scenes.daylight OUT.blend --case hard_g0_inside [--fog]`` builds the scene's .blend and
``python -m fog_scenes.daylight --cases`` renders the missing cached references and prints their noise.
"""
import argparse
import collections
import json
import math
import pathlib
import sys

import numpy as np

from fog_scenes import dense
from fog_scenes import render_harness as h

NAME = "daylight"
RESOLUTION = (160, 90)         # px
SENSOR_WIDTH_MM = 36.0
CLIP_START_M = 0.001
CLIP_END_M = 20000.0

GROUND = dict(half_width_m=10000.0, albedo=0.3)
SUN = dict(elevation_deg=40.0, azimuth_deg=-50.0, strength_w_m2=3.0, angle_deg=0.5)
# The suns of the cases: ``morning`` (SUN, the test conventions: nothing casts a shadow) and ``low`` (12 degrees up,
# ahead and 40 degrees to the right, just out of the inside camera's view, 10 W/m^2, every surface casting shadows:
# the buildings' shadows cross the street in the fog as shafts, issue 29's "shafts between buildings"; the ground
# 1 km across: with a ground kilometres wide casting shadows EEVEE 5.0 loses the sun's light on it and half the sky's,
# docs/measurements/2026-11-27-sun-shafts.md; beyond 500 m the layer hides the ground, e^-5)
SUNS = dict(morning=dict(SUN, shadows=False),
            low=dict(SUN, elevation_deg=12.0, azimuth_deg=40.0, strength_w_m2=10.0, shadows=True,
                     ground_half_width_m=500.0))
WORLD_COLOUR = (0.35, 0.5, 0.8)   # W/(m^2 sr) over the upper hemisphere (Background strength 1)
WORLD_STRENGTH = 1.0
WORLD_BELOW_HORIZON = 0.0         # the World's radiance below the horizon, over WORLD_COLOUR

# x0, x1, y0, y1, height (m), albedo: the inside camera at (0, 0) looks along +Y
BUILDINGS = [
    dict(name="B01", x0=-11.0, x1=-5.0, y0=22.0, y1=28.0, height=12.0, albedo=0.5),
    dict(name="B02", x0=6.0, x1=14.0, y0=30.0, y1=40.0, height=30.0, albedo=0.3),
    dict(name="B03", x0=-32.0, x1=-18.0, y0=53.0, y1=67.0, height=140.0, albedo=0.4),
    dict(name="B04", x0=20.0, x1=36.0, y0=64.0, y1=76.0, height=60.0, albedo=0.6),
    dict(name="B05", x0=-11.0, x1=1.0, y0=89.0, y1=101.0, height=45.0, albedo=0.25),
    dict(name="B06", x0=35.0, x1=55.0, y0=100.0, y1=120.0, height=180.0, albedo=0.35),
    dict(name="B07", x0=-70.0, x1=-50.0, y0=118.0, y1=143.0, height=80.0, albedo=0.5),
    dict(name="B08", x0=6.0, x1=24.0, y0=141.0, y1=159.0, height=120.0, albedo=0.45),
    dict(name="B09", x0=-115.0, x1=-85.0, y0=170.0, y1=190.0, height=35.0, albedo=0.3),
    dict(name="B10", x0=68.0, x1=93.0, y0=178.0, y1=203.0, height=200.0, albedo=0.55),
]

# The fog layer: extinction beta0 (1/m), albedo, the two profiles (top h0 and falloff H, m; H = 0: a hard top)
# and the Henyey-Greenstein anisotropies of the cases.
LAYER = dict(beta0=0.01, albedo=0.9, g=(0.0, 0.7),
             profiles=dict(hard=dict(h0=100.0, H=0.0), falloff=dict(h0=60.0, H=50.0)))
FALLOFF_LENGTHS = 8.0          # the box's top is h0 + this x H for a falloff
FOG_BOX_HALF_WIDTH_M = 5000.0
FOG_BOX_BOTTOM_M = -1.0
FOG_NAME = "FogBox"

# location (m), pitch (degrees above the horizon), lens (mm); all look along +Y (yaw 0), no roll
CAMERAS = dict(
    inside=dict(location=(0.0, 0.0, 1.6), pitch_deg=2.0, lens_mm=24.0),
    above=dict(location=(0.0, -300.0, 250.0), pitch_deg=-25.0, lens_mm=30.0),
)

Case = collections.namedtuple("Case", "profile g camera sun", defaults=("morning",))

# The cached references: (case, samples per render, seeds).  Render times and noise:
# docs/measurements/2026-11-27-daylight-references.md.
REFERENCE_CASES = [
    (Case("hard", 0.0, "inside"), 1024, 2),
    (Case("hard", 0.0, "above"), 1024, 2),
    (Case("falloff", 0.0, "inside"), 1024, 2),
    (Case("hard", 0.7, "inside"), 1024, 2),
]
EXTRA_CASES = [(Case("falloff", 0.7, "above"), 1024, 2)]


def as_case(case):
    """A :class:`Case` from a Case, a (profile, g, camera[, sun]) tuple or a name such as 'hard_g0.7_inside' or
    'hard_g0.7_inside_low'."""
    if isinstance(case, str):
        profile, g, camera, *sun = case.split("_")
        case = Case(profile, float(g.lstrip("g")), camera, *sun)
    case = Case(str(case[0]), float(case[1]), str(case[2]), str(case[3]) if len(case) > 3 else "morning")
    if case.profile not in LAYER["profiles"] or case.camera not in CAMERAS or case.sun not in SUNS:
        raise ValueError(f"unknown case {case}: profiles {sorted(LAYER['profiles'])}, cameras {sorted(CAMERAS)}")
    return case


def case_name(case):
    """'hard_g0_inside', 'hard_g0.7_inside_low' etc."""
    c = as_case(case)
    return f"{c.profile}_g{c.g:g}_{c.camera}" + ("" if c.sun == "morning" else f"_{c.sun}")


def layer(case):
    """The fog of ``case``: dict(beta0 1/m, albedo, g, h0 m, H m, box_top m)."""
    c = as_case(case)
    p = LAYER["profiles"][c.profile]
    top = p["h0"] + FALLOFF_LENGTHS * p["H"]
    return dict(beta0=LAYER["beta0"], albedo=LAYER["albedo"], g=c.g, h0=p["h0"], H=p["H"], box_top=top)


def fog_flags(case):
    """``python -m fog_addon render``'s flags for the add-on's fog of ``case`` (its layer, anisotropy, albedo),
    besides ``--density`` (``layer(case)["beta0"]``)."""
    c, f = as_case(case), layer(case)
    return ("--anisotropy", repr(c.g), "--color", ",".join([repr(f["albedo"])] * 3), "--fog-top", repr(f["h0"]),
            "--height-falloff", repr(f["H"]))


def sun_direction(sun="morning"):
    """Unit vector towards the sun ``sun`` of SUNS (world): (cos e sin az, cos e cos az, sin e)."""
    e, az = math.radians(SUNS[sun]["elevation_deg"]), math.radians(SUNS[sun]["azimuth_deg"])
    return np.array([math.cos(e) * math.sin(az), math.cos(e) * math.cos(az), math.sin(e)])


# -- the scene (bpy, in a Blender process) ----------------------------------------------------------------------

def _set_world(scene):
    """A World of radiance WORLD_COLOUR above the horizon and WORLD_BELOW_HORIZON x it below (Geometry
    Position is the view direction in a World shader)."""
    import bpy
    world = bpy.data.worlds.new("Daylight Sky")
    if world.node_tree is None:
        world.use_nodes = True
    nt = world.node_tree
    bg = next(n for n in nt.nodes if n.bl_idname == "ShaderNodeBackground")
    bg.inputs["Color"].default_value = (*WORLD_COLOUR, 1.0)
    geo = nt.nodes.new("ShaderNodeNewGeometry")
    sep = nt.nodes.new("ShaderNodeSeparateXYZ")
    above = nt.nodes.new("ShaderNodeMath")
    above.operation = 'GREATER_THAN'
    above.inputs[1].default_value = 0.0
    strength = nt.nodes.new("ShaderNodeMapRange")          # 0 -> below, 1 -> 1, times WORLD_STRENGTH
    strength.clamp = False
    strength.inputs["To Min"].default_value = WORLD_BELOW_HORIZON * WORLD_STRENGTH
    strength.inputs["To Max"].default_value = WORLD_STRENGTH
    nt.links.new(geo.outputs["Position"], sep.inputs["Vector"])
    nt.links.new(sep.outputs["Z"], above.inputs[0])
    nt.links.new(above.outputs["Value"], strength.inputs["Value"])
    nt.links.new(strength.outputs["Result"], bg.inputs["Strength"])
    scene.world = world
    return world


def _math(nt, op, a, b=None):
    n = nt.nodes.new("ShaderNodeMath")
    n.operation = op
    for i, v in enumerate((a, b)):
        if v is None:
            continue
        if isinstance(v, (int, float)):
            n.inputs[i].default_value = float(v)
        else:
            nt.links.new(v, n.inputs[i])
    return n.outputs["Value"]


def fog_material(case):
    """The fog box's material of ``case`` (``layer_material`` of its ``layer``).  Needs bpy."""
    return layer_material(layer(case))


def layer_material(f):
    """The material of a fog box holding the layer ``f`` (dict beta0, albedo, g, h0, H as ``layer`` gives): Volume
    Scatter (white, a beta(z), HG g) + Volume Absorption (black, (1 - a) beta(z)); beta(z) constant for a hard top,
    beta0 e^{-max(z - h0, 0)/H} for a falloff.  Needs bpy."""
    import bpy
    mat = bpy.data.materials.new(FOG_NAME)
    if mat.node_tree is None:
        mat.use_nodes = True
    nt = mat.node_tree
    for n in list(nt.nodes):
        nt.nodes.remove(n)
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    vs = nt.nodes.new("ShaderNodeVolumeScatter")
    vs.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)        # Color scales the density: white
    vs.inputs["Anisotropy"].default_value = f["g"]
    vs.phase = 'HENYEY_GREENSTEIN'
    ab = nt.nodes.new("ShaderNodeVolumeAbsorption")
    ab.inputs["Color"].default_value = (0.0, 0.0, 0.0, 1.0)        # absorbs density x (1 - Color)
    if f["H"] > 0.0:
        geo = nt.nodes.new("ShaderNodeNewGeometry")
        sep = nt.nodes.new("ShaderNodeSeparateXYZ")
        nt.links.new(geo.outputs["Position"], sep.inputs["Vector"])
        above = _math(nt, 'MAXIMUM', _math(nt, 'SUBTRACT', sep.outputs["Z"], f["h0"]), 0.0)
        shape = _math(nt, 'EXPONENT', _math(nt, 'MULTIPLY', above, -1.0 / f["H"]))
        nt.links.new(_math(nt, 'MULTIPLY', shape, f["beta0"] * f["albedo"]), vs.inputs["Density"])
        nt.links.new(_math(nt, 'MULTIPLY', shape, f["beta0"] * (1.0 - f["albedo"])), ab.inputs["Density"])
    else:
        vs.inputs["Density"].default_value = f["beta0"] * f["albedo"]
        ab.inputs["Density"].default_value = f["beta0"] * (1.0 - f["albedo"])
    add = nt.nodes.new("ShaderNodeAddShader")
    nt.links.new(vs.outputs["Volume"], add.inputs[0])
    nt.links.new(ab.outputs["Volume"], add.inputs[1])
    nt.links.new(add.outputs["Shader"], out.inputs["Volume"])
    return mat


def add_fog(scene, case):
    """Add the fog box of ``case`` (module doc) to ``scene``, seen by every ray type; needs bpy."""
    from demo_scenes import add_box_between
    f = layer(case)
    w = FOG_BOX_HALF_WIDTH_M
    ob = add_box_between(scene, FOG_NAME, -w, w, -w, w, FOG_BOX_BOTTOM_M, f["box_top"], fog_material(case))
    for attr in ("visible_camera", "visible_shadow", "visible_diffuse", "visible_glossy", "visible_transmission",
                 "visible_volume_scatter"):
        setattr(ob, attr, True)
    return ob


def build(scene, case, with_fog=True, samples=1024, resolution=RESOLUTION, cast_shadows=False,
          interreflection=False):
    """Fill ``scene`` with the city, the sun, the sky and ``case``'s camera (and its fog box if ``with_fog``), set
    up as the single-scattering reference (module doc) at ``samples`` spp.  ``cast_shadows`` / ``interreflection``
    False: the add-on's test conventions.  Needs bpy."""
    import bpy
    from mathutils import Vector
    from demo_scenes import add_box_between, add_camera, add_plane, material, render_settings
    from fog_addon import reference
    c = as_case(case)
    render_settings(scene, resolution=resolution)
    _set_world(scene)
    g = SUNS[c.sun].get("ground_half_width_m", GROUND["half_width_m"])
    ground = add_plane(scene, "Ground", -g, g, -g, g, 0.0,
                       material("Ground", (GROUND["albedo"],) * 3, roughness=1.0, specular_ior_level=0.0))
    solids = [ground]
    mats = {}
    for b in BUILDINGS:
        a = b["albedo"]
        if a not in mats:
            mats[a] = material(f"Facade {a:g}", (a,) * 3, roughness=1.0, specular_ior_level=0.0)
        solids.append(add_box_between(scene, b["name"], b["x0"], b["x1"], b["y0"], b["y1"], 0.0, b["height"],
                                      mats[a]))
    ld = bpy.data.lights.new("Sun", 'SUN')
    ld.energy = SUNS[c.sun]["strength_w_m2"]
    ld.angle = math.radians(SUN["angle_deg"])
    ld.use_shadow = True
    ld.color = (1.0, 1.0, 1.0)
    sun = bpy.data.objects.new("Sun", ld)
    sun.rotation_euler = Vector(-sun_direction(c.sun)).to_track_quat('-Z', 'Y').to_euler()   # shines along -Z
    scene.collection.objects.link(sun)
    cast_shadows = cast_shadows or SUNS[c.sun]["shadows"]
    cam_spec = CAMERAS[c.camera]
    loc = Vector(cam_spec["location"])
    p = math.radians(cam_spec["pitch_deg"])
    cam = add_camera(scene, tuple(loc), tuple(loc + Vector((0.0, math.cos(p), math.sin(p)))),
                     lens=cam_spec["lens_mm"])
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
        add_fog(scene, c)
    scene.render.film_transparent = False
    bpy.context.view_layer.update()
    s = sun.matrix_world.to_3x3().col[2]    # local +Z: towards the sun
    assert max(abs(a - b) for a, b in zip(s.normalized(), sun_direction(c.sun))) < 1e-6, s
    return scene


def build_scene(path, case, with_fog=True, samples=1024):
    """Save the scene of ``case`` as ``path`` (.blend), with its fog box or without (``with_fog``), in a fresh
    Blender process; returns the path."""
    path = pathlib.Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    args = ["-m", "fog_scenes.daylight", path, "--case", case_name(case), "--samples", int(samples)]
    if with_fog:
        args.append("--fog")
    h.run(args)
    return path


def _workdir():
    d = pathlib.Path(h._env()["TMPDIR"]) / "fog_daylight"
    d.mkdir(parents=True, exist_ok=True)
    return d


def blend_path(case, with_fog=True, workdir=None):
    """Path of ``case``'s .blend (with its fog, or the camera's fog-free scene) in ``workdir`` (default: the
    harness's scratch folder), built if missing."""
    c = as_case(case)
    workdir = pathlib.Path(workdir) if workdir else _workdir()
    tag = case_name(c) if with_fog else f"clear_{c.camera}" + ("" if c.sun == "morning" else f"_{c.sun}")
    blend = workdir / f"{NAME}_{tag}.blend"
    if not blend.is_file():
        build_scene(blend, c, with_fog=with_fog)
    return blend


# -- references -----------------------------------------------------------------------------------------------

_SEED_CODE = r'''
import sys, json, time
import bpy
from fog_addon import measure
a = json.loads(sys.argv[1])
scene = measure.open_scene(a["blend"])
measure.set_resolution(scene, *a["resolution"])
c = scene.cycles
c.samples = a["samples"]
c.seed = a["seed"]
c.use_animated_seed = False
assert c.volume_bounces == 0 and c.max_bounces == 1 and not c.use_adaptive_sampling
assert abs(scene.camera.data.clip_start - 0.001) < 1e-9 and scene.camera.data.clip_end >= 20000.0
assert ("FogBox" in bpy.data.objects) == a["fog"]
t0 = time.perf_counter()
measure.render_to_file(scene, a["out"])
print("RENDER_SECONDS %.2f" % (time.perf_counter() - t0))
'''


def reference_name(case, samples, seeds, resolution=RESOLUTION):
    """File name of a cached fog reference, its parameters in it."""
    f, c = layer(case), as_case(case)
    w, hh = resolution
    return (f"{NAME}_{c.profile}_beta{f['beta0']:g}_h{f['h0']:g}_H{f['H']:g}_g{c.g:g}_a{f['albedo']:g}"
            f"_{c.camera}{'' if c.sun == 'morning' else '_' + c.sun}_vb0_{w}x{hh}_{int(samples)}spp_x{int(seeds)}.exr")


def clear_name(case, samples, seeds, resolution=RESOLUTION):
    """File name of the cached fog-free render of ``case``'s camera."""
    w, hh = resolution
    c = as_case(case)
    return f"{NAME}_clear_{c.camera}{'' if c.sun == 'morning' else '_' + c.sun}_{w}x{hh}_{int(samples)}spp_x{int(seeds)}.exr"


def _render_seeds(blend, path, samples, seeds, fog, regen=False, times=None, timeout=3600):
    """Render ``blend`` with seeds 0 .. seeds-1 (each kept as ``dense.seed_path``) and write their mean to
    ``path`` (``render_harness.mean_of_seeds``); returns ``path``."""
    path = pathlib.Path(path)
    if path.is_file() and not regen:
        return path

    def render_seed(seed, out):
        args = dict(blend=str(blend), out=str(out), samples=int(samples), seed=int(seed), resolution=list(RESOLUTION),
                    fog=bool(fog))
        return h.render_seconds(h.run(["-c", _SEED_CODE, json.dumps(args)], timeout=timeout))

    return h.mean_of_seeds(path, render_seed, seeds, regen, times)


def render_reference(case, samples=1024, seeds=2, regen=False, directory=None, times=None, timeout=3600):
    """Path of the cached single-scattering Cycles reference of ``case`` (module doc), rendering its missing
    seeds (``samples`` spp each, seeds 0 .. seeds-1, kept beside it as ``dense.seed_path``) and their mean.
    ``times``: a list to which each new render's seconds are appended."""
    directory = pathlib.Path(directory) if directory else h.REFERENCES
    path = directory / reference_name(case, samples, seeds)
    if path.is_file() and not regen:
        return path
    return _render_seeds(blend_path(case, True), path, samples, seeds, True, regen, times, timeout)


def render_clear(case, samples=1024, seeds=2, regen=False, directory=None, times=None, timeout=3600):
    """Path of the cached fog-free render of ``case``'s camera (the same scene and settings without the fog
    box; the mean of ``seeds`` renders of ``samples`` spp, each kept beside it)."""
    directory = pathlib.Path(directory) if directory else h.REFERENCES
    path = directory / clear_name(case, samples, seeds)
    if path.is_file() and not regen:
        return path
    return _render_seeds(blend_path(case, False), path, samples, seeds, False, regen, times, timeout)


def reference_seeds(case, samples=1024, seeds=2, **kw):
    """The seeds' renders ((H, W, 3) arrays) of the cached reference (:func:`render_reference`)."""
    from fog_addon import imageio
    path = render_reference(case, samples, seeds, **kw)
    return [imageio.read_rgb(dense.seed_path(path, i)) for i in range(int(seeds))]


# -- pixels and surfaces (numpy) ------------------------------------------------------------------------------

def camera_basis(camera):
    """(forward, right, up) unit world vectors of ``camera`` (CAMERAS key): yaw 0 (+Y), pitch, no roll."""
    p = math.radians(CAMERAS[camera]["pitch_deg"])
    fwd = np.array([0.0, math.cos(p), math.sin(p)])
    right = np.array([1.0, 0.0, 0.0])
    return fwd, right, np.cross(right, fwd)


def pixel_rays(camera, resolution=RESOLUTION):
    """(H, W, 3) unit world directions of the camera rays through the pixel centres (row 0 = top); the sensor
    SENSOR_WIDTH_MM wide, fit horizontally."""
    w, hh = resolution
    fwd, right, up = camera_basis(camera)
    t = SENSOR_WIDTH_MM / (2.0 * CAMERAS[camera]["lens_mm"]) / (w / 2.0)   # tan per pixel at the centre
    y, x = np.mgrid[0:hh, 0:w]
    d = fwd + ((x + 0.5 - w / 2.0) * t)[..., None] * right + ((hh / 2.0 - (y + 0.5)) * t)[..., None] * up
    return d / np.linalg.norm(d, axis=-1, keepdims=True)


def project(camera, points, resolution=RESOLUTION):
    """[(x, y)] pixels (x from the left, y from the top; pixel i's centre at i + 0.5) of world ``points``."""
    w, hh = resolution
    fwd, right, up = camera_basis(camera)
    t = SENSOR_WIDTH_MM / (2.0 * CAMERAS[camera]["lens_mm"]) / (w / 2.0)
    out = []
    for pt in points:
        d = np.asarray(pt, np.float64) - np.array(CAMERAS[camera]["location"])
        z = d @ fwd
        out.append((w / 2.0 + (d @ right) / z / t, hh / 2.0 - (d @ up) / z / t))
    return out


def pixel_hits(camera, resolution=RESOLUTION):
    """What each pixel centre's camera ray meets first, by ray casting the scene's data (no bpy): ``cast_boxes``
    of the camera's pixel rays over the ground and BUILDINGS (kind i + 1: building BUILDINGS[i])."""
    return cast_boxes(np.array(CAMERAS[camera]["location"], np.float64), pixel_rays(camera, resolution), GROUND,
                      BUILDINGS)


def cast_boxes(o, d, ground, boxes):
    """What each ray from ``o`` along the unit directions ``d`` (H, W, 3) meets first among a ground plane at z = 0
    (dict half_width_m, albedo) and axis-aligned boxes standing on it (dicts x0, x1, y0, y1, height, albedo):
    dict(origin (3,), dirs (H, W, 3), t (H, W) metres (inf: the sky), point (H, W, 3), normal (H, W, 3),
    kind (H, W) int: -1 the sky, 0 the ground, i + 1 box i, albedo (H, W))."""
    shape = d.shape[:2]
    t_best = np.full(shape, np.inf)
    kind = np.full(shape, -1, int)
    normal = np.zeros(d.shape)
    albedo = np.zeros(shape)
    with np.errstate(divide="ignore", invalid="ignore"):
        tg = np.where(d[..., 2] < 0.0, -o[2] / d[..., 2], np.inf)
        pg = o + tg[..., None] * d
        gw = ground["half_width_m"]
        ok = np.isfinite(tg) & (np.abs(pg[..., 0]) <= gw) & (np.abs(pg[..., 1]) <= gw)
        t_best = np.where(ok, tg, t_best)
        kind[ok] = 0
        normal[ok] = (0.0, 0.0, 1.0)
        albedo[ok] = ground["albedo"]
        for i, b in enumerate(boxes):
            lo = np.array([b["x0"], b["y0"], 0.0])
            hi = np.array([b["x1"], b["y1"], b["height"]])
            t1, t2 = (lo - o) / d, (hi - o) / d
            tmin, tmax = np.minimum(t1, t2), np.maximum(t1, t2)
            t_in = np.max(np.nan_to_num(tmin, nan=-np.inf), axis=-1)
            t_out = np.min(np.nan_to_num(tmax, nan=np.inf), axis=-1)
            axis = np.argmax(np.nan_to_num(tmin, nan=-np.inf), axis=-1)
            hit = (t_in <= t_out) & (t_in > 0.0) & (t_in < t_best)
            t_best = np.where(hit, t_in, t_best)
            kind[hit] = i + 1
            albedo[hit] = b["albedo"]
            n = np.zeros(d.shape)
            np.put_along_axis(n, axis[..., None], -np.sign(np.take_along_axis(d, axis[..., None], -1)), -1)
            normal[hit] = n[hit]
    point = np.where(np.isfinite(t_best)[..., None], o + np.nan_to_num(t_best, posinf=0.0)[..., None] * d, np.nan)
    return dict(origin=o, dirs=d, t=t_best, point=point, normal=normal, kind=kind, albedo=albedo)


def seed_noise(seed_images, mask=None):
    """Noise of a reference from its seeds' renders (``area_lights.seed_noise``): {"rel_rmse_mean": the cached
    mean's expected relative RMSE against the noiseless picture, "rel_rmse_seed": one seed's, "p50", "p95": the
    mean's per-pixel relative noise}; the seed-to-seed relative RMSE is sqrt(2) x rel_rmse_seed."""
    from fog_scenes import area_lights
    return area_lights.seed_noise(seed_images, mask)


def main(argv=None):
    p = argparse.ArgumentParser(description="build the daylight city's .blend, or render its references")
    p.add_argument("out", nargs="?", help="the .blend to write")
    p.add_argument("--case", default="hard_g0_inside", help="profile_gG_camera, e.g. falloff_g0.7_above")
    p.add_argument("--fog", action="store_true", help="add the case's fog box")
    p.add_argument("--samples", type=int, default=1024)
    p.add_argument("--cases", action="store_true", help="render REFERENCE_CASES and the clear images if missing")
    p.add_argument("--extra", action="store_true", help="with --cases: EXTRA_CASES too")
    a = p.parse_args(argv)
    if a.cases:
        from fog_addon import imageio
        for case, samples, seeds in REFERENCE_CASES + (EXTRA_CASES if a.extra else []):
            for kind, fn in (("clear", render_clear), ("fog", render_reference)):
                times = []
                ref = fn(case, samples, seeds, times=times)
                s = [imageio.read_rgb(dense.seed_path(ref, i)) for i in range(seeds)]
                print(kind, case_name(case), ref.name, "new render seconds", times, flush=True)
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
