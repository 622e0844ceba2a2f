"""The fog passes (AOVs) and the compositor set-up that keeps Cycles' denoiser off the fog.

    python tests/scenes/passes_probe.py OUT_DIR MODE

MODE
  denoise    the one-lamp scene: Cycles 64x48, 16 spp, Gaussian 0.01 px filter, the scene's own denoiser
             settings LEFT ON; fog added (the set-up is built); renders OUT/denoise.exr (multilayer:
             composite and passes) and saves OUT/denoise.blend
  nosetup    the same, then the set-up taken off again (``compositor.teardown``: Cycles' denoiser back on,
             as before the fog had a set-up): OUT/nosetup.exr
  strays     how far each pixel's 16 samples strayed from its centre (see ``strays``): OUT/strays.exr
  passes     ENGINE (CYCLES or BLENDER_EEVEE): a grey plane lit by two lamps; render A as it is, render B
             with the lamps lighting no surface (Cycles: light ray visibility; EEVEE: diffuse and specular
             factors 0), so B's Combined is the fog's part alone: OUT/passes_<engine>_{lit,unlit}.exr
  passes_blend ENGINE: the same two scenes saved without the fog, OUT/passes_<engine>_{lit,unlit}.blend
  compositor_farm  the lit Cycles scene with the Compositor method's fog and passes (its render output in
             OUT/frames/), saved as OUT/compositor_passes.blend for a farm
  remove     add and remove the fog on scenes with and without a user's compositor graph, with a save
             and reopen in between; prints snapshots (see ``snapshot``); and the Opacity that weights
             the passes of an opaque, a half-transparent and a texture-mixed transparent material

The one-lamp scene: camera at (0, -6, 1) looking along +y, a black plane 20 m wide (no reflection:
base colour 0, specular 0), so every pixel off the sphere is pure airlight; the lamp
(1000 W, beta = 0.2 /m) is 0.09 px from a pixel centre, a sharp glow; a grey sphere lit by the lamp and
by a grey World (which camera rays do not see once fogged: they see the fog; the fog's World Light is on,
so the World keeps lighting the sphere through the fog) is the noisy part the denoiser has to clean.
Multilayer EXRs are read by the test (OpenImageIO crashed reading multi-part files in a process that had rendered).
The last line of stdout is one JSON object describing the scene.
"""
import json
import math
import pathlib
import sys

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

import bpy  # noqa: E402

from fog_addon.nodes import compositor, owned, passes  # noqa: E402
from fog_addon.ops import apply  # noqa: E402

BETA, POWER, W, H, SPP = 0.2, 1000.0, 64, 48, 16
CAMERA, LENS, SENSOR = (0.0, -6.0, 1.0), 35.0, 36.0
LAMP_PIXEL = (37.57, 21.56)   # where the lamp is seen, in pixels (x right, y down; centres at j + 0.5)
LAMP_DEPTH = 6.0              # m in front of the camera
PLANE = 20.0
SPHERE = ((-1.0, -2.0, 0.7), 0.6)
SKY = (0.8, 0.8, 0.8)   # the user's World: camera rays see only the fog, other rays this (World Light on)


def lamp_location():
    px, py = LAMP_PIXEL
    sx = (px / W - 0.5) * SENSOR
    sy = (0.5 - py / H) * SENSOR * H / W
    return (sx / LENS * LAMP_DEPTH, CAMERA[1] + LAMP_DEPTH, CAMERA[2] + sy / LENS * LAMP_DEPTH)


def multilayer(scene, path):
    im = scene.render.image_settings
    im.media_type = "MULTI_LAYER_IMAGE"
    im.file_format = "OPEN_EXR_MULTILAYER"
    im.color_depth = "32"
    im.exr_codec = "ZIP"
    scene.render.filepath = str(path)
    scene.render.use_file_extension = False
    bpy.ops.render.render(write_still=True, scene=scene.name)


def camera(scene):
    cam = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    scene.collection.objects.link(cam)
    scene.camera = cam
    cam.location = CAMERA
    cam.rotation_euler = (math.radians(90), 0, 0)
    cam.data.clip_start = 0.001
    cam.data.lens = LENS
    cam.data.sensor_width = SENSOR
    return cam


def world(scene, colour=(0.0, 0.0, 0.0)):
    scene.world = bpy.data.worlds.new("World")
    scene.world.node_tree.nodes["Background"].inputs["Color"].default_value = (*colour, 1)


def cycles_settings(scene):
    """64x48, 16 spp, pixel centres (Gaussian 0.01 px), seed 0; the denoiser is not touched."""
    scene.render.engine = "CYCLES"
    r = scene.render
    r.resolution_x, r.resolution_y, r.resolution_percentage = W, H, 100
    c = scene.cycles
    c.device = "CPU"
    c.samples = SPP
    c.use_adaptive_sampling = False
    c.pixel_filter_type = "GAUSSIAN"
    c.filter_width = 0.01
    c.seed = 0
    c.use_animated_seed = False
    r.film_transparent = False


def one_lamp(scene):
    """The one-lamp scene (module docstring); returns its description."""
    camera(scene)
    lamp = bpy.data.objects.new("Lamp", bpy.data.lights.new("Lamp", "POINT"))
    lamp.data.energy = POWER
    lamp.data.shadow_soft_size = 0.0
    lamp.location = lamp_location()
    scene.collection.objects.link(lamp)
    bpy.ops.mesh.primitive_plane_add(size=PLANE, location=(0, 0, 0))
    black = bpy.data.materials.new("Black")
    bpy.context.object.data.materials.append(black)
    bsdf = black.node_tree.nodes["Principled BSDF"]
    bsdf.inputs["Base Color"].default_value = (0, 0, 0, 1)
    bsdf.inputs["Specular IOR Level"].default_value = 0.0
    bpy.ops.mesh.primitive_uv_sphere_add(radius=SPHERE[1], location=SPHERE[0], segments=48, ring_count=24)
    bpy.ops.object.shade_smooth()
    grey = bpy.data.materials.new("Grey")
    bpy.context.object.data.materials.append(grey)
    grey.node_tree.nodes["Principled BSDF"].inputs["Base Color"].default_value = (0.6, 0.6, 0.6, 1)
    world(scene, SKY)
    cycles_settings(scene)
    return {"beta": BETA, "power": POWER, "width": W, "height": H, "spp": SPP, "camera": CAMERA,
            "rotation": [list(r) for r in scene.camera.matrix_world.to_3x3()], "lens": LENS, "sensor": SENSOR,
            "lamp": list(lamp.location), "lamp_pixel": LAMP_PIXEL, "plane": PLANE, "sphere": SPHERE}


def denoise(out, keep_setup=True):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    info = one_lamp(scene)
    info["denoiser_before"] = scene.cycles.use_denoising
    info["notes"] = apply.apply_fog(scene, BETA, with_passes=True, world_light=True)
    info["set_up"] = compositor.is_set_up(scene)
    if not keep_setup:
        compositor.teardown(scene)
    info["denoiser"] = scene.cycles.use_denoising
    tree = scene.compositing_node_group
    info["compositor"] = None if tree is None else sorted(owned.role_of(n) for n in tree.nodes)
    name = "denoise" if keep_setup else "nosetup"
    multilayer(scene, out / f"{name}.exr")
    if keep_setup:
        bpy.ops.wm.save_as_mainfile(filepath=str(out / f"{name}.blend"))
    return info


def strays(out):
    """Where each pixel's samples went: the mean over its samples of (x - centre)^2, (y - centre)^2 in px^2.

    Cycles' Gaussian 0.01 px filter keeps almost every sample within 0.015 px of the pixel centre, but
    about 0.15 % of them land up to 0.5 px away (measured: 74 of 64 x 48 x 16), which moves a pixel on
    a steep glow by up to 0.8 %.  Same camera, resolution, seed and sample count as ``denoise``; a World
    emitting each sample's squared offset: OUT/strays.exr.
    """
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    camera(scene)
    world(scene)
    cycles_settings(scene)
    scene.cycles.use_denoising = False
    t = scene.world.node_tree
    coords = t.nodes.new("ShaderNodeTexCoord")
    split = t.nodes.new("ShaderNodeSeparateXYZ")
    join = t.nodes.new("ShaderNodeCombineXYZ")
    t.links.new(coords.outputs["Window"], split.inputs[0])
    for axis, size in ((0, W), (1, H)):
        px = t.nodes.new("ShaderNodeMath")
        px.operation = "MULTIPLY_ADD"   # window * size - 0.5: the sample's offset from the centre is its fraction
        px.inputs[1].default_value, px.inputs[2].default_value = size, -0.5
        t.links.new(split.outputs[axis], px.inputs[0])
        rnd = t.nodes.new("ShaderNodeMath")
        rnd.operation = "ROUND"
        t.links.new(px.outputs[0], rnd.inputs[0])
        dev = t.nodes.new("ShaderNodeMath")
        dev.operation = "SUBTRACT"
        t.links.new(px.outputs[0], dev.inputs[0])
        t.links.new(rnd.outputs[0], dev.inputs[1])
        sq = t.nodes.new("ShaderNodeMath")
        sq.operation = "MULTIPLY"
        t.links.new(dev.outputs[0], sq.inputs[0])
        t.links.new(dev.outputs[0], sq.inputs[1])
        t.links.new(sq.outputs[0], join.inputs[axis])
    t.links.new(join.outputs[0], t.nodes["Background"].inputs["Color"])
    scene.world.cycles.sampling_method = "NONE"
    multilayer(scene, out / "strays.exr")
    return {"samples": SPP}


def passes_scene(out, engine, save=False):
    """A grey plane lit by two lamps, rendered lit and unlit (see the module docstring); ``save``: saved as
    OUT/passes_<engine>_{lit,unlit}.blend without the fog instead, for the command line to render."""
    res = {}
    for lit in (True, False):
        bpy.ops.wm.read_factory_settings(use_empty=True)
        scene = bpy.context.scene
        cam = camera(scene)
        cam.location, cam.rotation_euler = (0, -5, 2.5), (math.radians(65), 0, 0)
        for k, (loc, power, colour) in enumerate((((0.5, 1.5, 0.6), 600.0, (1.0, 0.8, 0.6)),
                                                  ((-2.0, 4.0, 1.0), 1500.0, (0.5, 0.7, 1.0)))):
            ob = bpy.data.objects.new(f"L{k}", bpy.data.lights.new(f"L{k}", "POINT"))
            ob.data.energy, ob.data.color, ob.data.shadow_soft_size = power, colour, 0.0
            if not lit:
                ob.data.diffuse_factor = ob.data.specular_factor = 0.0
                ob.visible_diffuse = ob.visible_glossy = False
            ob.location = loc
            scene.collection.objects.link(ob)
        bpy.ops.mesh.primitive_plane_add(size=40, location=(0, 0, 0))
        mat = bpy.data.materials.new("Ground")
        bpy.context.object.data.materials.append(mat)
        bsdf = mat.node_tree.nodes["Principled BSDF"]
        bsdf.inputs["Base Color"].default_value = (0.6, 0.5, 0.4, 1)
        bsdf.inputs["Roughness"].default_value = 0.35
        world(scene)
        scene.render.engine = engine
        r = scene.render
        r.resolution_x, r.resolution_y = (64, 48) if engine == "CYCLES" else (32, 24)
        r.resolution_percentage = 100
        r.filter_size = 0.0
        scene.cycles.samples, scene.cycles.use_adaptive_sampling = 1, False
        scene.cycles.pixel_filter_type, scene.cycles.filter_width = "GAUSSIAN", 0.01
        scene.cycles.use_denoising = False
        scene.cycles.max_bounces = 0
        scene.eevee.taa_render_samples = 1
        scene.eevee.light_threshold = 1e-4
        name = f"passes_{engine.lower()}_{'lit' if lit else 'unlit'}"
        if save:
            bpy.ops.wm.save_as_mainfile(filepath=str(out / f"{name}.blend"))
            res[name] = {"blend": str(out / f"{name}.blend")}
            continue
        apply.apply_fog(scene, BETA, albedo=(0.9, 0.8, 0.7), with_passes=True)
        multilayer(scene, out / f"{name}.exr")
        res[name] = {"camera": list(cam.location), "rotation": [list(v) for v in cam.matrix_world.to_3x3()],
                     "lens": cam.data.lens, "sensor": cam.data.sensor_width,
                     "width": r.resolution_x, "height": r.resolution_y}
    return {"beta": BETA, "renders": res}


# --- Remove restores the scene exactly ---------------------------------------------------------------

def _value(v):
    if hasattr(v, "name") and isinstance(v, bpy.types.ID):
        return f"ID:{v.name}"
    if hasattr(v, "__len__") and not isinstance(v, str):
        return [round(float(x), 6) if isinstance(x, float) else x for x in v]
    return round(v, 6) if isinstance(v, float) else v


def _plain(v):
    if isinstance(v, bpy.types.ID):
        return f"ID:{v.name}"
    if hasattr(v, "to_dict"):
        return {k: _plain(x) for k, x in v.to_dict().items()}
    if isinstance(v, dict):
        return {k: _plain(x) for k, x in v.items()}
    if hasattr(v, "to_list"):
        return [_plain(x) for x in v.to_list()]
    if isinstance(v, (list, tuple)):
        return [_plain(x) for x in v]
    return v


def _props(idblock):
    """``idblock``'s custom properties as plain data."""
    return {k: _plain(idblock[k]) for k in idblock.keys()}


def tree_dump(tree):
    """Nodes (type, their RNA properties and input values, custom properties) and links of ``tree``."""
    if tree is None:
        return None
    nodes = {}
    for n in tree.nodes:
        props = {p.identifier: _value(getattr(n, p.identifier)) for p in n.bl_rna.properties
                 if not p.is_readonly and p.type in ("BOOLEAN", "INT", "FLOAT", "STRING", "ENUM", "POINTER")
                 and p.identifier not in ("select", "show_options", "show_preview", "show_texture")}
        inputs = {s.identifier: _value(s.default_value) for s in n.inputs if hasattr(s, "default_value")}
        nodes[n.name] = {"type": n.bl_idname, "props": props, "inputs": inputs, "custom": _props(n)}
    links = sorted((l.from_node.name, l.from_socket.identifier, l.to_node.name, l.to_socket.identifier,
                    l.is_muted) for l in tree.links)
    iface = [(i.name, i.in_out, i.socket_type) for i in tree.interface.items_tree if i.item_type == "SOCKET"]
    return {"name": tree.name, "nodes": nodes, "links": links, "interface": iface, "custom": _props(tree)}


def snapshot(scene):
    """What the fog's passes and compositor set-up may touch, for before/after comparison."""
    c = scene.cycles
    layers = {vl.name: {"aovs": [(a.name, a.type) for a in vl.aovs], "active_aov": vl.active_aov_index,
                        "store_passes": vl.cycles.denoising_store_passes,
                        "emit_env": [vl.use_pass_emit, vl.use_pass_environment], "use_denoising": vl.cycles.use_denoising,
                        "custom": _props(vl)} for vl in scene.view_layers}
    return {"use_denoising": c.use_denoising, "denoiser": c.denoiser, "input_passes": c.denoising_input_passes,
            "use_compositing": scene.render.use_compositing, "engine": scene.render.engine,
            "osl": bool(c.shading_system), "custom": _props(scene), "layers": layers,
            "compositor": tree_dump(scene.compositing_node_group),
            "compositor_groups": sorted(g.name for g in bpy.data.node_groups if g.bl_idname == "CompositorNodeTree"),
            "node_groups": sorted(g.name for g in bpy.data.node_groups)}


def _user_compositor(scene):
    """A user's graph: Render Layers -> Multiply 0.5 -> Group Output, a Viewer on the Image, a user AOV."""
    tree = bpy.data.node_groups.new("My Compositing", "CompositorNodeTree")
    tree.interface.new_socket("Image", in_out="OUTPUT", socket_type="NodeSocketColor")
    rl = tree.nodes.new("CompositorNodeRLayers")
    rl.name = "My Layers"
    rl.location = (-300, 100)
    mul = tree.nodes.new("ShaderNodeMix")
    mul.data_type, mul.blend_type = "RGBA", "MULTIPLY"
    mul.name = "AnalyticFog Halve"   # a user's node with the fog's name prefix: still the user's
    mul.inputs[0].default_value = 1.0
    b = next(s for s in mul.inputs if s.identifier == "B_Color")
    b.default_value = (0.5, 0.5, 0.5, 1.0)
    out = tree.nodes.new("NodeGroupOutput")
    view = tree.nodes.new("CompositorNodeViewer")
    tree.links.new(rl.outputs["Image"], next(s for s in mul.inputs if s.identifier == "A_Color"))
    tree.links.new(next(s for s in mul.outputs if s.identifier == "Result_Color"), out.inputs["Image"])
    tree.links.new(rl.outputs["Image"], view.inputs["Image"])
    scene.compositing_node_group = tree
    aov = scene.view_layers[0].aovs.add()
    aov.name, aov.type = "My Mask", "VALUE"
    aov = scene.view_layers[0].aovs.add()
    aov.name, aov.type = passes.FOG_LIGHT, "COLOR"   # the user's own AOV of the fog's name: used and kept
    scene.view_layers[0].active_aov_index = 0
    return tree


def remove(out):
    """Add and remove the fog: no compositor, a user's compositor; snapshots before, during and after."""
    res = {}
    for case in ("own", "user", "user_compositing_off", "eevee_then_cycles", "osl"):
        bpy.ops.wm.read_factory_settings(use_empty=True)
        scene = bpy.context.scene
        one_lamp(scene)
        if case.startswith("user"):
            _user_compositor(scene)
        if case == "user_compositing_off":
            scene.render.use_compositing = False
        if case == "eevee_then_cycles":
            scene.render.engine = "BLENDER_EEVEE"
        before = snapshot(scene)
        notes = apply.apply_fog(scene, BETA, method="osl" if case == "osl" else "nodes", with_passes=True)
        during = snapshot(scene)
        follow = {}
        if case == "eevee_then_cycles":   # the engine switched: what the depsgraph handler does
            scene.render.engine = "CYCLES"
            apply.refresh_lights(scene)
            follow["cycles"] = snapshot(scene)
            scene.render.engine = "BLENDER_EEVEE"
            apply.refresh_lights(scene)
            follow["eevee_again"] = snapshot(scene)
            scene.render.engine = "CYCLES"
            apply.refresh_lights(scene)
        again = apply.apply_fog(scene, BETA, method="osl" if case == "osl" else "nodes", with_passes=True)   # adding twice
        twice = snapshot(scene)
        path = out / f"remove_{case}.blend"
        bpy.ops.wm.save_as_mainfile(filepath=str(path))
        bpy.ops.wm.open_mainfile(filepath=str(path))
        scene = bpy.context.scene
        reopened = snapshot(scene)
        apply.remove_fog(scene)
        after = snapshot(scene)
        res[case] = {"before": before, "during": during, "twice": twice, "reopened": reopened, "after": after,
                     "follow": follow, "notes": [list(n) for n in notes], "notes_again": [list(n) for n in again]}
    return res


def opacity():
    """The Opacity each fogged material gives its Surface node (what weights the passes): an opaque
    Principled, Principled Alpha 0.4, and a Transparent BSDF mixed in by a texture."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    one_lamp(scene)
    plane = scene.objects["Plane"]
    mats = {}
    for name in ("Opaque", "Alpha", "Textured"):
        mat = bpy.data.materials.new(name)
        plane.data.materials.append(mat)
        mats[name] = mat
    mats["Alpha"].node_tree.nodes["Principled BSDF"].inputs["Alpha"].default_value = 0.4
    t = mats["Textured"].node_tree
    mix = t.nodes.new("ShaderNodeMixShader")
    tex = t.nodes.new("ShaderNodeTexNoise")
    clear = t.nodes.new("ShaderNodeBsdfTransparent")
    t.links.new(tex.outputs["Fac"], mix.inputs[0])
    t.links.new(t.nodes["Principled BSDF"].outputs[0], mix.inputs[1])
    t.links.new(clear.outputs[0], mix.inputs[2])
    t.links.new(mix.outputs[0], t.nodes["Material Output"].inputs["Surface"])
    apply.apply_fog(scene, BETA, with_passes=True)
    res = {}
    for name, mat in mats.items():
        fog = owned.find(mat.node_tree, "Surface")
        sock = fog.inputs[passes.OPACITY]
        res[name] = {"linked": sock.is_linked, "value": [round(v, 6) for v in sock.default_value]}
    # the World group: which light-group instances the Emission output and the Fog Light AOV read
    world = bpy.data.node_groups["AnalyticFog World"]
    aov = next(n for n in world.nodes if n.bl_idname == "ShaderNodeOutputAOV" and n.aov_name == passes.FOG_LIGHT)
    out = next(n for n in world.nodes if n.bl_idname == "NodeGroupOutput")
    res["world_reads"] = {"emission": _upstream_groups(out.inputs["Emission"]),
                          "fog_light_pass": _upstream_groups(aov.inputs["Color"])}
    return res


def _upstream_groups(sock):
    """Names of the group nodes that input ``sock`` depends on, inside the light bundles too (a bundle's
    output is followed into the bundle, whose light instances are named by the light's index)."""
    seen, todo, found = set(), [("", sock)], set()
    while todo:
        where, s = todo.pop()
        for link in s.links:
            n = link.from_node
            key = where + n.name
            if n.bl_idname == "NodeGroupInput":   # a bundle's input: what feeds it outside is followed already
                continue
            if n.bl_idname == "ShaderNodeGroup" and " Lights " in n.node_tree.name:
                out = next(o for o in n.node_tree.nodes if o.bl_idname == "NodeGroupOutput")
                todo.append((f"{key}/", out.inputs[link.from_socket.name]))
                todo.extend((where, i) for i in n.inputs)
                continue
            if key in seen:
                continue
            seen.add(key)
            if n.bl_idname == "ShaderNodeGroup":
                found.add(n.name)
            todo.extend((where, i) for i in n.inputs)
    return sorted(found)


def main(out, mode, *args):
    out = pathlib.Path(out)
    out.mkdir(parents=True, exist_ok=True)
    if mode == "denoise":
        res = denoise(out)
    elif mode == "nosetup":
        res = denoise(out, keep_setup=False)
    elif mode == "strays":
        res = strays(out)
    elif mode == "passes":
        res = passes_scene(out, *args)
    elif mode == "passes_blend":   # the same scenes saved without the fog (the command line renders them)
        res = passes_scene(out, *args, save=True)
    elif mode == "compositor_farm":   # the lit scene with the Compositor's fog and passes, saved for a farm
        res = passes_scene(out, "CYCLES", save=True)
        bpy.ops.wm.open_mainfile(filepath=res["renders"]["passes_cycles_lit"]["blend"])
        scene = bpy.context.scene
        scene.render.filepath = str(out / "frames") + "/"   # the passes go beside the render's output
        apply.apply_fog(scene, BETA, albedo=(0.9, 0.8, 0.7), method="compositor", with_passes=True)
        bpy.ops.wm.save_as_mainfile(filepath=str(out / "compositor_passes.blend"))
        res["directories"] = [n.directory for n in compositor.passes_outputs(scene)]
    elif mode == "remove":
        res = remove(out)
        res["opacity"] = opacity()
    else:
        raise SystemExit(f"unknown mode {mode!r}")
    sys.stdout.flush()
    print(json.dumps(res, default=str))


if __name__ == "__main__":
    main(*sys.argv[1:])
