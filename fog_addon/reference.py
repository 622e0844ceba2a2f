"""Configure a scene as Cycles' path-traced single-scattering fog reference (needs bpy).

The analytic model (Sun et al. 2005) is single scattering in a homogeneous,
isotropic medium of extinction = scattering coefficient beta:

* airlight along camera rays: one scatter event, light sampled directly
  (with the medium's extinction light -> scatter point -> camera);
* surfaces: direct light attenuated by the fog, plus the light the fog
  scatters onto them (Sun §4), attenuated back to the camera.

In Cycles that is a World volume (Volume Scatter, Color white, density beta)
with ``volume_bounces = 0`` (no second volume event) and ONE surface bounce
(``max_bounces = diffuse_bounces = glossy_bounces = 1``): the bounce ray leaving
a surface meets the fog, scatters once and samples the light -- the fog-lit
surface term.  The same bounce also carries surface-to-surface light (one
bounce of GI) and is occluded by other objects; the analytic model has
neither, so tests call :func:`disable_interreflection` (objects invisible to
diffuse/glossy rays) and :func:`disable_cast_shadows` (objects invisible to
shadow rays; the light keeps its shadows, which carry the fog's extinction).

Measured (tests/test_reference_setup.py, bpy 5.0.1):

* airlight vs scipy quadrature of Sun Eq. 5, per pixel (24x16, beta 0.1,
  lamp 5 m away, 30 deg past it): median ratio 1.00006, p95 |r-1| 3.5e-4
  (256 spp), 1.3e-4 (1024 spp); beta 0.3: 1.00025 / 5.6e-4;
* white Lambertian plane 2 m below a lamp, beta 0.15, 4096 spp: mean ratio
  1.0005 over 64 pixels against (direct + fog-scattered irradiance)/pi with
  the hemisphere integral by quadrature (the fog-lit term is +50 % here); the
  fog-lit term is noisy: about 1 % per pixel even at 4096 spp;
* without fog, ``disable_interreflection`` + 1 bounce is bit-identical to
  ``max_bounces = 0`` (direct light only); with interreflection the spheres
  demo gains 2.2 % overall;
* any world volume density > 0 (even 1e-6) extinguishes the World background
  completely (rays to infinity): the reference background is black, and the
  World surface only matters through density-0 renders.

Traps handled here (blender-facts.md): Volume Scatter's default Color 0.8
scales the density; light shadows off skips extinction; camera rays (and
their fog) start at the near clip; the pixel filter must sample pixel centres.
"""
import math

import bpy

from . import measure

DEFAULT_SAMPLES = 1024
REFERENCE_CLIP_START = 0.001   # m; Cycles starts camera rays (and their fog) here
VOLUME_NODE_NAME = "AnalyticFog Reference Scatter"


def _check_density(density):
    d = float(density)
    if not math.isfinite(d) or d < 0.0:
        raise ValueError(f"fog density must be a finite number >= 0, got {density!r}")
    return d


def set_world_volume(scene, density, color=(1.0, 1.0, 1.0), anisotropy=0.0):
    """Attach a homogeneous Volume Scatter (Color = white x ``color``) to the
    World's Volume output; the existing World surface is kept."""
    density = _check_density(density)
    world = scene.world
    if world is None:
        world = bpy.data.worlds.new("World")
        scene.world = world
        world.use_nodes = True
        world.node_tree.nodes.new("ShaderNodeOutputWorld")
    if world.node_tree is None:
        world.use_nodes = True
    nt = world.node_tree
    out = next((n for n in nt.nodes if n.bl_idname == "ShaderNodeOutputWorld" and n.is_active_output), None)
    if out is None:
        out = next((n for n in nt.nodes if n.bl_idname == "ShaderNodeOutputWorld"), None)
    if out is None:
        out = nt.nodes.new("ShaderNodeOutputWorld")
    for link in list(out.inputs["Volume"].links):
        nt.links.remove(link)
    old = nt.nodes.get(VOLUME_NODE_NAME)
    if old is not None:
        nt.nodes.remove(old)
    vs = nt.nodes.new("ShaderNodeVolumeScatter")
    vs.name = vs.label = VOLUME_NODE_NAME
    vs.location = (out.location[0] - 250, out.location[1] - 200)
    c = tuple(float(x) for x in color)[:3]
    # Color scales sigma_s and sigma_t (it is not an albedo): white = density as given.
    vs.inputs["Color"].default_value = (c[0], c[1], c[2], 1.0)
    vs.inputs["Density"].default_value = density
    vs.inputs["Anisotropy"].default_value = float(anisotropy)
    vs.phase = 'HENYEY_GREENSTEIN'   # 5.0 default; g = 0 is isotropic
    nt.links.new(vs.outputs["Volume"], out.inputs["Volume"])
    return vs


def add_black_absorption(scene, density):
    """Add a Volume Absorption of Color black and ``density`` (1/m) beside the World's reference Volume Scatter
    (``set_world_volume``): fog of extinction beta and albedo a is the scatter at a beta plus this at (1 - a) beta
    (Volume Absorption absorbs density x (1 - Color): with Color white it absorbs nothing)."""
    nt = scene.world.node_tree
    vs = nt.nodes[VOLUME_NODE_NAME]
    out = vs.outputs["Volume"].links[0].to_node
    ab = nt.nodes.new("ShaderNodeVolumeAbsorption")
    ab.inputs["Color"].default_value = (0.0, 0.0, 0.0, 1.0)
    ab.inputs["Density"].default_value = _check_density(density)
    add = nt.nodes.new("ShaderNodeAddShader")
    nt.links.remove(vs.outputs["Volume"].links[0])
    nt.links.new(vs.outputs["Volume"], add.inputs[0])
    nt.links.new(ab.outputs["Volume"], add.inputs[1])
    nt.links.new(add.outputs["Shader"], out.inputs["Volume"])
    return ab


def hide_from_volume_scatter(scene):
    """Objects (not lights, cameras, empties) hidden from volume-scatter rays: the references' convention."""
    for ob in scene.objects:
        if ob.type not in {"LIGHT", "CAMERA", "EMPTY"}:
            ob.visible_volume_scatter = False


def set_single_scattering_integrator(scene, samples=DEFAULT_SAMPLES, single_scattering=True):
    """Cycles integrator settings for an unbiased single-scattering reference."""
    scene.render.engine = 'CYCLES'
    c = scene.cycles
    measure.set_cycles_cpu(scene)
    c.samples = int(samples)
    c.use_adaptive_sampling = False
    c.use_denoising = False
    c.use_preview_denoising = False
    for vl in scene.view_layers:
        if hasattr(vl, "cycles"):
            vl.cycles.use_denoising = False
    c.sample_clamp_direct = 0.0
    c.sample_clamp_indirect = 0.0
    c.light_sampling_threshold = 0.0   # light tree culling threshold
    c.blur_glossy = 0.0                # "filter glossy" roughens glossy after diffuse
    c.caustics_reflective = True
    c.caustics_refractive = True
    c.use_guiding = False
    c.min_light_bounces = 0
    c.min_transparent_bounces = 0
    if single_scattering:
        c.volume_bounces = 0           # one scatter event along any ray
        c.max_bounces = 1              # one surface bounce: fog-scattered light onto surfaces
        c.diffuse_bounces = 1
        c.glossy_bounces = 1
        c.transmission_bounces = 0
    c.transparent_max_bounces = max(c.transparent_max_bounces, 8)
    scene.render.use_motion_blur = False
    measure.set_pixel_centre_filter(scene)


def configure_reference(scene, density, color=(1.0, 1.0, 1.0), anisotropy=0.0,
                        samples=DEFAULT_SAMPLES, single_scattering=True):
    """Turn ``scene`` into the Cycles path-traced reference for fog ``density`` (1/m).

    Keeps camera, lights, materials, World surface and colour management.
    Sets: World volume (see :func:`set_world_volume`), Cycles CPU, fixed
    ``samples`` with no adaptivity/denoising/clamping, single-scattering
    bounces (see module doc), light threshold 0, camera clip start 1 mm,
    Gaussian 0.01 px pixel filter.  Lights keep their shadows; lights that
    had ``use_shadow = False`` are switched back on (with shadows off Cycles
    ignores the fog's extinction towards the light).
    """
    density = _check_density(density)
    if abs(float(anisotropy)) >= 1.0:
        raise ValueError("anisotropy must be in (-1, 1)")
    set_world_volume(scene, density, color, anisotropy)
    set_single_scattering_integrator(scene, samples, single_scattering)
    if scene.camera is not None and scene.camera.type == 'CAMERA':
        scene.camera.data.clip_start = REFERENCE_CLIP_START
    for ob in scene.objects:
        if ob.type == 'LIGHT':
            ob.data.use_shadow = True
    return scene


def disable_cast_shadows(scene):
    """Hide every non-light object from shadow rays (the analytic model has no
    cast shadows).  The lights' own shadow flag stays on."""
    for ob in scene.objects:
        if ob.type not in {'LIGHT', 'CAMERA', 'EMPTY'}:
            ob.visible_shadow = False


def disable_interreflection(scene):
    """Hide every object from diffuse and glossy bounce rays: no surface-to-surface
    light and no occlusion of the fog hemisphere seen by a surface, as in the
    analytic model.  Objects stay visible to the camera."""
    for ob in scene.objects:
        if ob.type not in {'LIGHT', 'CAMERA', 'EMPTY'}:
            ob.visible_diffuse = False
            ob.visible_glossy = False
            ob.visible_transmission = False


def absorb_scattered_rays(scene):
    """Every surface black to rays that left the fog (Light Path's Is Camera Ray off): a multiply scattered
    reference keeps its surfaces in the scattered light's way, absorbing it, without the light they would reflect
    into the fog (their interreflection, which the model leaves out as :func:`disable_interreflection` does; the
    surfaces are hidden from diffuse and glossy rays, so no other ray meets them).  Camera rays see each material
    as it was.  Each material is changed in place (a reference's scene only)."""
    done = set()
    for ob in scene.objects:
        for slot in getattr(ob, "material_slots", ()):
            mat = slot.material
            if mat is None or mat.name in done or not mat.use_nodes:
                continue
            done.add(mat.name)
            tree = mat.node_tree
            out = next((n for n in tree.nodes if n.type == "OUTPUT_MATERIAL" and n.is_active_output), None)
            if out is None or not out.inputs["Surface"].links:
                continue
            source = out.inputs["Surface"].links[0].from_socket
            path = tree.nodes.new("ShaderNodeLightPath")
            black = tree.nodes.new("ShaderNodeBsdfDiffuse")
            black.inputs["Color"].default_value = (0.0, 0.0, 0.0, 1.0)
            mix = tree.nodes.new("ShaderNodeMixShader")
            tree.links.new(path.outputs["Is Camera Ray"], mix.inputs["Fac"])
            tree.links.new(black.outputs[0], mix.inputs[1])
            tree.links.new(source, mix.inputs[2])
            tree.links.new(mix.outputs[0], out.inputs["Surface"])
