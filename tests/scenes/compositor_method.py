"""The Compositor method's set-up on the spheres demo scene, without rendering; prints one JSON line.

* ``frames``: for camera set-ups (sensor fits, landscape and portrait pictures, lens shifts), the largest
  difference between the driven image plane (``comp_fog.camera_frame``, read after the drivers ran) and
  the one Blender's ``Camera.view_frame`` gives (scaled to unit distance).
* ``splice``: on a user's compositor (Render Layers -> Glare -> Group Output, and its Image also to a
  Viewer) the fog's group node sits between Render Layers and both, Cycles' denoiser stays on, and
  Remove gives back the same links, the same nodes, no fog data-blocks and no fog AOVs.
* ``switch``: Node Groups -> Compositor -> Node Groups: the compositor's set-up and AOVs go, the
  materials' light groups come back.
* ``engines``: Cycles -> EEVEE -> Cycles -> EEVEE with the fog on: the fog group's inputs (EEVEE's read the
  Depth pass, switched on), the AOVs and the materials' lights (EEVEE's shared dimming) follow; Remove restores
  the Depth pass.
* ``dimming``: in EEVEE the materials' shared dimming holds as many of 200 lamps as EEVEE's uniform block
  does, the brightest at the camera, at step off; none in Cycles.
* ``refused``: the method refused, with nothing changed, for Workbench, the fog passes and a panoramic camera.
* ``driven``: a density, colour, light power and lamp move reach the compositor's graph without a rebuild.
* ``shared``: ``CompOps`` (and ``NodeOps`` in a shader tree) builds an operation on the same inputs once (a
  commuted product too), a different one anew; a spot's glow pair integrates three rims.
"""
import json
import math
import pathlib
import sys

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

import bpy  # noqa: E402

from demo_scenes import spheres  # noqa: E402
from fog_addon.nodes import budgets, comp_bundles, comp_fog, comp_ops, compositor, groups, images, owned  # noqa: E402
from fog_addon.precompute.physics.spot import spot  # noqa: E402
from fog_addon.nodes.sockets import NodeOps  # noqa: E402
from fog_addon.methods.compositor import dimming_lights  # noqa: E402
from fog_addon.ops import apply  # noqa: E402
from fog_addon import methods  # noqa: E402
from fog_addon.precompute.model import rungs  # noqa: E402

BETA = 0.15
DIMMING_LIGHTS = 200   # more than EEVEE's uniform block holds in the materials' shared dimming (about 170)



BUNDLES = ("AnalyticFog Surface Lights ", "AnalyticFog World Lights ")
PREVIEW_BUNDLES = ("AnalyticFog Surface Preview Lights ", "AnalyticFog World Preview Lights ")


def light_groups_in_bundles(prefixes=BUNDLES):
    """The per-light groups the materials' (or the viewport preview's) bundles hold."""
    return len({n.node_tree.name for ng in bpy.data.node_groups if ng.name.startswith(prefixes)
                for n in ng.nodes if n.bl_idname == "ShaderNodeGroup" and n.node_tree is not None
                and n.node_tree.name.startswith(("AnalyticFog Light [", "AnalyticFog Background Light ["))})

def fresh():
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    spheres.build(scene)
    scene.render.engine = "CYCLES"
    scene.cycles.use_denoising = True
    bpy.context.view_layer.update()
    return scene


def frame_error(scene, fit, size, shift):
    """Largest |driven - view_frame| over the image plane's three vectors for one camera set-up."""
    cam = scene.camera
    cam.data.sensor_fit = fit
    cam.data.sensor_height = 18.0
    cam.data.shift_x, cam.data.shift_y = shift
    scene.render.resolution_x, scene.render.resolution_y = size
    tree = bpy.data.node_groups.new("frame probe", "CompositorNodeTree")
    scene.compositing_node_group = tree
    vectors = comp_fog.camera_frame(NodeOps(tree), scene)
    scene.frame_set(scene.frame_current)
    got = [[s.default_value for s in v.sock.node.inputs[:3]] for v in vectors]
    local = [v / -v.z for v in cam.data.view_frame(scene=scene)]   # corners at unit distance
    top_right, bottom_right, bottom_left, top_left = [cam.matrix_world.to_3x3() @ v for v in local]
    want = [bottom_left, bottom_right - bottom_left, top_left - bottom_left]
    scene.compositing_node_group = None
    bpy.data.node_groups.remove(tree)
    return max(abs(g - w) for gv, wv in zip(got, want) for g, w in zip(gv, wv))


def links(tree):
    return sorted((l.from_node.name, l.from_socket.identifier, l.to_node.name, l.to_socket.identifier)
                  for l in tree.links)


def fog_data():
    """Names of the fog's node groups and table images left in the file."""
    return sorted([ng.name for ng in bpy.data.node_groups if ng.name.startswith(owned.PREFIX)]
                  + [im.name for im in bpy.data.images if im.name.startswith(owned.PREFIX)])


def shared():
    """What ``CompOps``' hash-consing keeps: nodes of a tree computing exp(2x) + sqrt(x) twice (once as
    exp(x * 2)), and exp(3x) once; the rim groups in a spot's glow pair."""
    tree = bpy.data.node_groups.new("Shared test", "CompositorNodeTree")
    tree.interface.new_socket("x", in_out="INPUT", socket_type="NodeSocketFloat")
    x = comp_ops.CompOps(tree).wrap(tree.nodes.new("NodeGroupInput").outputs[0])
    m = x.ops
    a = m.exp(2.0 * x) + m.sqrt(x)
    b = m.exp(x * 2.0) + m.sqrt(x)
    c = m.exp(3.0 * x)
    kinds = sorted(n.operation for n in tree.nodes if n.bl_idname == "ShaderNodeMath")
    shader = bpy.data.node_groups.new("Shared shader test", "ShaderNodeTree")   # the materials' builder too
    shader.interface.new_socket("x", in_out="INPUT", socket_type="NodeSocketFloat")
    y = NodeOps(shader).wrap(shader.nodes.new("NodeGroupInput").outputs[0])
    same_in_shader = y.ops.exp(2.0 * y).sock == y.ops.exp(y * 2.0).sock
    spot_tree = bpy.data.node_groups.new("Spot test", "CompositorNodeTree")
    for k in range(13):
        spot_tree.interface.new_socket(f"In {k}", in_out="INPUT", socket_type="NodeSocketFloat")
    m = comp_ops.CompOps(spot_tree, images.all_table_images())
    spot.airlight_pair(m, *(m.wrap(o) for o in spot_tree.nodes.new("NodeGroupInput").outputs[:13]))
    pair = next(n.node_tree for n in spot_tree.nodes if n.bl_idname == "CompositorNodeGroup")
    # the rims are inline in the pair (so they share what they can): each of their points has one Map Range node
    ramps = sum(n.bl_idname == "ShaderNodeMapRange" for n in pair.nodes)
    return {"same": a.sock == b.sock, "different": c.sock != a.sock, "math": kinds, "pair_rims": ramps / spot.RIM_NODES,
            "same_in_shader": same_in_shader}


def main():
    res = {}
    scene = fresh()
    res["frames"] = {f"{fit} {w}x{h} shift {sx},{sy}": frame_error(scene, fit, (w, h), (sx, sy))
                     for fit, (w, h), (sx, sy) in [("AUTO", (320, 180), (0.0, 0.0)), ("AUTO", (180, 320), (0.1, -0.2)),
                                                   ("HORIZONTAL", (200, 300), (0.0, 0.15)),
                                                   ("VERTICAL", (320, 180), (-0.1, 0.05)),
                                                   ("AUTO", (320, 180), (0.25, 0.1))]}

    scene = fresh()
    tree = bpy.data.node_groups.new("My Compositor", "CompositorNodeTree")
    tree.interface.new_socket("Image", in_out="OUTPUT", socket_type="NodeSocketColor")
    rl = tree.nodes.new("CompositorNodeRLayers")
    glare = tree.nodes.new("CompositorNodeGlare")
    viewer = tree.nodes.new("CompositorNodeViewer")
    out = tree.nodes.new("NodeGroupOutput")
    tree.links.new(rl.outputs["Image"], glare.inputs["Image"])
    tree.links.new(rl.outputs["Image"], viewer.inputs["Image"])
    tree.links.new(glare.outputs["Image"], out.inputs["Image"])
    scene.compositing_node_group = tree
    scene.render.use_compositing = True
    before = {"links": links(tree), "nodes": sorted(n.name for n in tree.nodes), "fog": fog_data(),
              "aovs": [a.name for a in scene.view_layers[0].aovs]}
    notes = apply.apply_fog(scene, BETA, method="compositor")
    fog_nodes = [n for n in tree.nodes if owned.is_ours(n)]
    fed = {l.to_node.name for l in tree.links if l.from_node in fog_nodes}
    res["splice"] = {
        "notes": notes, "fog_nodes": [n.bl_idname for n in fog_nodes],
        "group": fog_nodes[0].node_tree.name if fog_nodes else None,
        "feeds": sorted(fed), "rl_feeds": sorted({l.to_node.name for l in tree.links if l.from_node == rl}),
        "aovs_fed": sorted(l.to_socket.name for l in tree.links if l.from_node == rl and l.to_node in fog_nodes),
        "denoising": scene.cycles.use_denoising, "state": dict(scene.get(compositor.STATE, {}))}
    apply.remove_fog(scene)
    after = {"links": links(tree), "nodes": sorted(n.name for n in tree.nodes), "fog": fog_data(),
             "aovs": [a.name for a in scene.view_layers[0].aovs]}
    res["splice"]["restored"] = {k: after[k] == before[k] for k in before}
    res["splice"]["after"] = after

    scene = fresh()
    scene.cycles.use_denoising = False
    apply.apply_fog(scene, BETA, method="nodes")
    lights_in_materials = light_groups_in_bundles()
    apply.set_method(scene, "compositor")
    in_compositor = {"own_tree": getattr(scene.compositing_node_group, "name", None),
                     "aovs": [a.name for a in scene.view_layers[0].aovs],
                     "material_light_groups": light_groups_in_bundles()}
    apply.set_method(scene, "nodes")
    res["switch"] = {"nodes_light_groups": lights_in_materials, "compositor": in_compositor,
                     "back": {"tree": getattr(scene.compositing_node_group, "name", None),
                              "compositing": scene.render.use_compositing,
                              "aovs": [a.name for a in scene.view_layers[0].aovs],
                              "fog_group": bpy.data.node_groups.get(comp_fog.FOG_GROUP) is not None,
                              "material_light_groups": light_groups_in_bundles()}}

    scene = fresh()
    scene.cycles.use_denoising = False
    apply.apply_fog(scene, BETA, method="compositor")

    def engine_state():
        tree = scene.compositing_node_group
        fog = next(n for n in tree.nodes if owned.is_ours(n) and n.bl_idname == "CompositorNodeGroup")
        vl = scene.view_layers[0]
        return {"engine": scene.render.engine, "inputs_fed": sorted(l.to_socket.name for l in tree.links
                                                                    if l.to_node == fog),
                "depth_pass": vl.use_pass_z, "aovs": sorted(a.name for a in vl.aovs),
                "material_light_groups": light_groups_in_bundles(),
                "preview_light_groups": light_groups_in_bundles(PREVIEW_BUNDLES)}
    engines = [engine_state()]
    for engine in ("BLENDER_EEVEE", "CYCLES"):
        scene.render.engine = engine
        apply.refresh_lights(scene)   # what the depsgraph handler does when the engine changes
        engines.append(engine_state())
    scene.render.engine = "BLENDER_EEVEE"
    apply.refresh_lights(scene)
    apply.remove_fog(scene)
    res["engines"] = {"states": engines, "removed": {"depth_pass": scene.view_layers[0].use_pass_z,
                                                     "fog": fog_data()}}

    refused = {}
    for case in ("workbench", "backscatter", "panoramic"):
        scene = fresh()
        kwargs = {}
        if case == "workbench":
            scene.render.engine = "BLENDER_WORKBENCH"
        elif case == "backscatter":
            kwargs["anisotropy"] = -0.9
        else:   # (EEVEE: Cycles' panoramic rays reach the compositor by an AOV, EEVEE has none)
            scene.render.engine = "BLENDER_EEVEE"
            scene.camera.data.type = "PANO"
        try:
            apply.apply_fog(scene, BETA, method="compositor", **kwargs)
            refused[case] = None
        except ValueError as e:
            refused[case] = str(e)
        tagged = [m.name for m in bpy.data.materials if m.node_tree and any(owned.is_ours(n) for n in m.node_tree.nodes)]
        refused[case + " changed"] = tagged + fog_data()
    res["refused"] = refused

    scene = fresh()
    scene.cycles.use_denoising = False
    apply.apply_fog(scene, BETA, albedo=(0.9, 0.8, 0.7), method="compositor")
    lamp = next(o for o in scene.objects if o.type == "LIGHT")
    groups.set_params(0.05, (0.5, 0.6, 0.7))   # what the panel's density and colour do (apply.update_params)
    lamp.data.energy *= 2.0
    lamp.location.x += 1.25
    scene.frame_set(scene.frame_current)

    nodes = [n for ng in bpy.data.node_groups if ng.name.startswith((comp_fog.FOG_GROUP, comp_bundles.BUNDLE))
             for n in ng.nodes]

    def value(label, i=None):
        node = next(n for n in nodes if n.label == label)
        return node.outputs[0].default_value if i is None else node.inputs[i].default_value
    light_node = next(n for n in nodes if n.label.startswith("Light 0:"))
    intensity = light_node.inputs["Intensity"].links[0].from_node.inputs[0].default_value
    res["driven"] = {"beta": value("Beta"), "albedo": [value("Albedo", i) for i in range(3)],
                     "light_x": value("Light 0 Location", 0), "lamp_x": lamp.matrix_world.translation.x,
                     "intensity": intensity, "want_intensity": lamp.data.energy * lamp.data.color[0] / (4 * math.pi)}

    scene = fresh()   # EEVEE's viewport compositor on in a 3D view: it would add the fog over the preview
    scene.render.engine = "BLENDER_EEVEE"
    space = next(sp for sc in bpy.data.screens for a in sc.areas for sp in a.spaces if sp.type == "VIEW_3D")
    space.shading.use_compositor = "CAMERA"
    res["viewport_compositor"] = [n for n in apply.apply_fog(scene, BETA, method="compositor") if n[0] == "Viewport"]
    space.shading.use_compositor = "DISABLED"
    res["viewport_compositor_off"] = [n for n in apply.apply_fog(scene, BETA, method="compositor")
                                      if n[0] == "Viewport"]

    scene = fresh()
    scene.render.engine = "BLENDER_EEVEE"
    for o in [o for o in scene.objects if o.type == "LIGHT"]:
        bpy.data.objects.remove(o)
    eye = scene.camera.matrix_world.translation
    lamps = []
    for k in range(DIMMING_LIGHTS):   # a row of equal lamps going away from the camera, every 7th twice as bright
        data = bpy.data.lights.new(f"D{k:03d}", "POINT")
        data.energy = 200.0 if k % 7 == 0 else 100.0
        lamp = bpy.data.objects.new(f"D{k:03d}", data)
        lamp.location = (eye.x + 0.5, eye.y + 2.0 + k, eye.z)
        scene.collection.objects.link(lamp)
        lamps.append(lamp)
    bpy.context.view_layer.update()
    kept, models = dimming_lights(scene, apply.spec_of(scene), lamps)
    score = {o.name: o.data.energy / (o.matrix_world.translation - eye).length_squared for o in lamps}
    res["dimming"] = {"kept": len(kept), "models": sorted({m.airlight.name for m in models}),
                      "fits": budgets.eevee_budget(0.0).fits([2] * len(kept)),
                      "one_more_fits": budgets.eevee_budget(0.0).fits([2] * (len(kept) + 1)),
                      "brightest": min(score[o.name] for o in kept) >= max(
                          [score[o.name] for o in lamps if o not in kept], default=0.0)}
    # the viewport's preview in EEVEE gets the uniform block's room the dimming lights leave (their own unchanged)
    preview = methods.get("compositor").preview_budget
    spec = apply.spec_of(scene)
    full, glow, off = 0, 1, rungs.OFF   # (rungs.STEPS)
    few = lamps[:20]
    res["preview"] = {"crowded_off": preview(scene, spec, lamps).fits([off] * len(lamps)),
                      "crowded_glow": preview(scene, spec, lamps).fits([glow] + [off] * (len(lamps) - 1)),
                      "few_two_full": preview(scene, spec, few).fits([full, full] + [off] * 18),
                      "few_three_full": preview(scene, spec, few).fits([full] * 3 + [off] * 17),
                      "few_two_glows": preview(scene, spec, few).fits([glow] * 2 + [off] * 18),
                      "few_three_glows": preview(scene, spec, few).fits([glow] * 3 + [off] * 17)}
    scene.render.engine = "CYCLES"   # Cycles' lights dim their own direct light: none in the materials
    res["dimming"]["cycles"] = len(dimming_lights(scene, apply.spec_of(scene), lamps)[0])
    res["shared"] = shared()
    print("COMPOSITOR_JSON " + json.dumps(res), flush=True)


if __name__ == "__main__":
    main()
