"""Lamps seen through a glass pane and in a mirror, fogged (Node Groups or Compositor, Cycles) or path-traced.

    python tests/scenes/glass_mirror.py CASE MODE OUT.exr [SAMPLES] [METHOD]

CASE: ``glass`` (a Glass BSDF plane of IOR 1.0), ``glass_box`` (a Glass BSDF box 2 cm thick, IOR 1.5),
``principled_box`` (the same box of a Principled BSDF, Transmission 1, roughness 0), ``mixed_box`` (the box of a
Mix Shader: MIXED_GLASS of the Glass BSDF, the rest a Transparent BSDF), ``rough_box`` (the box of a Glass BSDF
of roughness ROUGH_GLASS) or
``mirror`` (a Principled BSDF, metallic 1, roughness 0, white).  MODE: ``reference`` (Cycles' World volume,
Volume Scatter white of density BETA, single scattering), ``fog`` (the add-on's fog, Method Node Groups) or
``none`` (no fog at all).  METHOD: the fog's method (default ``nodes``; ``compositor``).  Writes OUT.exr and OUT.npz (``pane``: the pixels whose centre ray meets the pane or
the mirror, by ray-plane intersection in numpy).

Camera at the origin looking along +y, 96x54 px, 35 mm.  The pane (1.6 x 1.2 m) stands 3 m away, left of
the view's centre; a 100 W point lamp 2 m behind it (glass), or beside the mirror, out of the camera's view,
where only the mirror shows it.  A grey Lambertian wall behind the lamp covers part of what the pane shows
(the rest escapes to the sky), so both a surface and the sky are seen past the pane.

The reference: Cycles path tracing, volume bounces 0 (single scattering), and enough bounces for the path
through the pane (transmission 4, glossy 2) and one diffuse bounce (the fog's light on the wall: Sun et al.
2005 Eq. 17, which the fog models); every object hidden from diffuse rays (no light from surface to surface,
as in the model) and from shadow rays (no cast shadows, as in the model); max_bounces caps every kind, so it
is set to their sum.  Traps of blender-facts.md: Volume Scatter white, lamp shadows on, clip start 1 mm,
Gaussian 0.01 px pixel filter.  The fogged render uses the same bounces: its wall's diffuse ray sees only
the World, black on rays other than the camera's.
"""
import math
import pathlib
import sys

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

import bpy  # noqa: E402
import numpy as np  # noqa: E402

from fog_addon import measure, reference  # noqa: E402
from fog_scenes import probe_common  # noqa: E402

BETA = 0.15            # 1/m
WIDTH, HEIGHT = 96, 54
PANE_CENTRE = (-0.4, 3.0, 0.0)
PANE_SIZE = (1.6, 1.2)   # m, width x height
THICKNESS = 0.02         # m, the glass box
LAMP_GLASS = (-0.3, 5.0, 0.1)
LAMP_MIRROR = (2.0, 3.2, 0.1)
ROUGH_GLASS = 0.1   # ``rough_box``'s roughness
MIXED_GLASS = 0.6   # the Glass BSDF's share in ``mixed_box``'s Mix Shader (the rest a Transparent BSDF)
MIRROR_TURN = math.pi / 4   # about z: the mirror's normal is (sin, -cos, 0) x ... reflecting +y rays to +x


def _mesh(scene, name, verts, faces, mat, location=(0, 0, 0), rotation=(0, 0, 0)):
    me = bpy.data.meshes.new(name)
    me.from_pydata(verts, [], faces)
    me.materials.append(mat)
    ob = bpy.data.objects.new(name, me)
    ob.location, ob.rotation_euler = location, rotation
    scene.collection.objects.link(ob)
    return ob


def _rect(w, h):
    """A w x h rectangle in the local xz plane, its normal -y (facing a camera at -y)."""
    return [(-w / 2, 0, -h / 2), (w / 2, 0, -h / 2), (w / 2, 0, h / 2), (-w / 2, 0, h / 2)], [(0, 1, 2, 3)]


def _box(w, h, t):
    v = [(x, y, z) for x in (-w / 2, w / 2) for y in (-t / 2, t / 2) for z in (-h / 2, h / 2)]
    faces = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    return v, faces


def _material(name, kind):
    if kind == "wall":
        return probe_common.bsdf_material(name, "ShaderNodeBsdfDiffuse", Color=(0.5, 0.5, 0.5, 1.0))
    if kind == "principled_box":   # Blender's usual glass: a Principled BSDF of Transmission 1
        return probe_common.bsdf_material(name, "ShaderNodeBsdfPrincipled", **probe_common.PRINCIPLED_GLASS)
    if kind == "mixed_box":   # dirty glass: a Glass BSDF mixed with a Transparent BSDF (MIXED_GLASS of it glass)
        mat = _material(name, "glass_box")
        nt = mat.node_tree
        glass, out = nt.nodes["Glass BSDF"], nt.nodes["Material Output"]
        clear, mix = nt.nodes.new("ShaderNodeBsdfTransparent"), nt.nodes.new("ShaderNodeMixShader")
        mix.inputs["Fac"].default_value = MIXED_GLASS
        nt.links.new(clear.outputs[0], mix.inputs[1])
        nt.links.new(glass.outputs[0], mix.inputs[2])
        nt.links.new(mix.outputs[0], out.inputs["Surface"])
        return mat
    if kind == "rough_box":   # frosted glass: a Glass BSDF of roughness ROUGH_GLASS (GGX)
        return probe_common.bsdf_material(name, "ShaderNodeBsdfGlass", Roughness=ROUGH_GLASS,
                                          Color=(1.0, 1.0, 1.0, 1.0), IOR=1.5)
    if kind.startswith("glass"):
        mat = probe_common.bsdf_material(name, "ShaderNodeBsdfGlass", Roughness=0.0, Color=(1.0, 1.0, 1.0, 1.0),
                                         IOR=1.0 if kind == "glass" else 1.5)
        bsdf = mat.node_tree.nodes["Glass BSDF"]
        bsdf.distribution = "SHARP" if "SHARP" in [i.identifier for i in bsdf.bl_rna.properties["distribution"]
                                                   .enum_items] else bsdf.distribution
        return mat
    return probe_common.bsdf_material(name, "ShaderNodeBsdfPrincipled", **{"Base Color": (1.0, 1.0, 1.0, 1.0),
                                                                           "Metallic": 1.0, "Roughness": 0.0})


def build(case):
    """The scene of ``case``; returns (scene, camera, pane plane: (centre, normal, u axis, v axis, half sizes))."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    cam = probe_common.look_at(scene, (0.0, 0.0, 0.0), (0.0, 1.0, 0.0), 35.0)
    cam.data.clip_end = 1000.0
    scene.world = bpy.data.worlds.new("World")
    scene.world.use_nodes = True
    scene.world.node_tree.nodes["Background"].inputs["Color"].default_value = (0.0, 0.0, 0.0, 1.0)
    wall = _material("Wall", "wall")
    pane_mat = _material("Pane", case)
    turn = MIRROR_TURN if case == "mirror" else 0.0
    if case in ("glass_box", "principled_box", "mixed_box", "rough_box"):
        _mesh(scene, "Pane", *_box(*PANE_SIZE, THICKNESS), pane_mat, PANE_CENTRE)
        front = (PANE_CENTRE[0], PANE_CENTRE[1] - THICKNESS / 2, PANE_CENTRE[2])
    else:
        _mesh(scene, "Pane", *_rect(*PANE_SIZE), pane_mat, PANE_CENTRE, (0.0, 0.0, turn))
        front = PANE_CENTRE
    if case == "mirror":
        # behind the lamp, facing -x, covering the upper part of what the mirror shows
        _mesh(scene, "Wall", *_rect(6.0, 3.0), wall, (4.5, 3.0, 1.3), (0.0, 0.0, math.pi / 2))
        lamp = LAMP_MIRROR
    else:
        _mesh(scene, "Wall", *_rect(3.0, 6.0), wall, (-1.4, 8.0, 0.0))
        lamp = LAMP_GLASS
    probe_common.add_point_lights(scene, [(lamp, 100.0, (1.0, 1.0, 1.0))], fog_only=False)
    c, s = math.cos(turn), math.sin(turn)
    plane = (np.array(front), np.array([s, -c, 0.0]), np.array([c, s, 0.0]), np.array([0.0, 0.0, 1.0]),
             np.array(PANE_SIZE) / 2)
    return scene, cam, plane


def pane_mask(cam, plane):
    """True where a pixel centre's ray meets the pane's front (``build``'s plane)."""
    eye, d = probe_common.camera_rays(cam, WIDTH, HEIGHT)
    centre, normal, u, v, half = plane
    t = ((centre - eye) @ normal) / (d @ normal)
    hit = eye + t[..., None] * d - centre
    return (t > 0) & (np.abs(hit @ u) <= half[0]) & (np.abs(hit @ v) <= half[1])


def configure(scene, samples):
    """The bounces and visibility of the module docstring, on the scene as built."""
    probe_common.see_through_bounces(scene, WIDTH, HEIGHT)
    reference.disable_cast_shadows(scene)
    measure.set_samples(scene, samples)


def main(case, mode, out, samples=None, method="nodes"):
    out = pathlib.Path(out)
    scene, cam, plane = build(case)
    probe_common.set_up_mode(scene, mode, BETA, samples, configure)   # (first: the casters as rendered)
    if mode == "fog":
        probe_common.add_fog(scene, BETA, method)
    measure.render_to_file(scene, str(out))
    np.savez(out.with_suffix(".npz"), pane=pane_mask(cam, plane))


if __name__ == "__main__":
    main(*sys.argv[1:])
