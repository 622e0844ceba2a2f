"""Fog every kind of material once, render what can be measured, take the fog out; report (JSON).

    python tests/scenes/material_kinds.py OUT_DIR [CYCLES|BLENDER_EEVEE]

One camera looks at a row of tiles (y = 0) in front of an emissive backdrop
(y = 4), with a point lamp above the camera ray so there is airlight; other
materials sit on objects out of frame.  Every tile shader is emission,
transparency or holdout (or black), so 1 spp renders are exact.  Per pixel:

    T = e^{-beta D} from the camera geometry (beta = DENSITY)
    A = the fog's airlight, from renders of the same scene with every material
        a fogged black emission (A_tile: tiles there, A_back: tiles hidden)

and a fogged tile must read what the physics says, e.g. an emitter E:
T E + A_tile; seen through a transparent fraction t: t (T_b E_b + A_back) + ...

Reports, per material, whether it was fogged and the reason string fog.add
gave, plus structural checks, idempotency (a second apply_fog changes
nothing; after a user edit it re-syncs only the fog's copies), and exact
restore on remove (snapshots of tests/scenes/add_remove.py; a render after
remove equals the one before the fog bit for bit).
"""
import json
import math
import os
import pathlib
import sys

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

import bpy  # noqa: E402
import numpy as np  # noqa: E402

from fog_addon import imageio, measure  # noqa: E402
from fog_addon.nodes import graph, owned  # noqa: E402
from fog_addon.ops import apply  # noqa: E402
from fog_scenes.probe_common import tiny_render  # noqa: E402
import add_remove  # noqa: E402  (snapshot, differing)

DENSITY = 0.1                 # 1/m
W, H = 64, 32                 # px
LENS, SENSOR = 35.0, 36.0     # mm
CAM_Y, TILE_Y, BACK_Y = -10.0, 0.0, 4.0
TILE = 0.8                    # m
E_BACK = (0.3, 0.35, 0.4)     # backdrop emission
COLS = [-4.2, -3.0, -1.8, -0.6, 0.6, 1.8, 3.0, 4.2]
ROWS = [1.2, -1.2]

E1 = (1.0, 0.5, 0.25)         # Emission shader colour (strength 2)
E2 = (0.2, 0.6, 1.0)          # Principled emission colour (strength 3)
E3 = (0.9, 0.8, 0.1)          # Multi Output: the CYCLES output's emission (strength 1)
E4 = (0.1, 0.9, 0.3)          # Multi Output: the ALL output's emission (strength 1)
EDIT_COLOR = (0.2, 0.5, 0.9, 1.0)
LAMP, POWER = (0.0, -5.0, 2.2), 800.0


# --- scene -------------------------------------------------------------------------

def _nodes(mat):
    return mat.node_tree.nodes, mat.node_tree.links


def _output(mat):
    return next(n for n in mat.node_tree.nodes if n.bl_idname == "ShaderNodeOutputMaterial")


def _bare(name):
    """A material whose tree holds just its Material Output (target ALL)."""
    mat = bpy.data.materials.new(name)
    nodes, _ = _nodes(mat)
    for n in [n for n in nodes if n.bl_idname != "ShaderNodeOutputMaterial"]:
        nodes.remove(n)
    return mat


def _emission(nodes, colour, strength, location=(-300, 0)):
    e = nodes.new("ShaderNodeEmission")
    e.inputs["Color"].default_value = (*colour, 1.0)
    e.inputs["Strength"].default_value = strength
    e.location = location
    return e


def mat_emission(name, colour, strength):
    mat = _bare(name)
    nodes, links = _nodes(mat)
    links.new(_emission(nodes, colour, strength).outputs[0], _output(mat).inputs["Surface"])
    return mat


def mat_principled(name, base=(0.8, 0.8, 0.8), emission=None, strength=0.0, alpha=1.0, spec=0.5, rough=0.5):
    mat = bpy.data.materials.new(name)
    p = mat.node_tree.nodes["Principled BSDF"]
    p.inputs["Base Color"].default_value = (*base, 1.0)
    p.inputs["Specular IOR Level"].default_value = spec
    p.inputs["Roughness"].default_value = rough
    p.inputs["Alpha"].default_value = alpha
    if emission is not None:
        p.inputs["Emission Color"].default_value = (*emission, 1.0)
        p.inputs["Emission Strength"].default_value = strength
    return mat


def mat_holdout(name):
    mat = _bare(name)
    nodes, links = _nodes(mat)
    links.new(nodes.new("ShaderNodeHoldout").outputs[0], _output(mat).inputs["Surface"])
    return mat


def mat_mix(name, fac, a, b, linked_fac=False):
    """Mix Shader(fac, a, b); a, b: "emission" (E1, strength 2), "transparent" or "holdout"."""
    mat = _bare(name)
    nodes, links = _nodes(mat)
    mix = nodes.new("ShaderNodeMixShader")
    if linked_fac:
        v = nodes.new("ShaderNodeValue")
        v.outputs[0].default_value = fac
        v.location = (-600, 200)
        links.new(v.outputs[0], mix.inputs[0])
    else:
        mix.inputs[0].default_value = fac
    for k, kind in ((1, a), (2, b)):
        if kind == "emission":
            src = _emission(nodes, E1, 2.0, (-300, 100 * k))
        elif kind == "transparent":
            src = nodes.new("ShaderNodeBsdfTransparent")
        else:
            src = nodes.new("ShaderNodeHoldout")
        links.new(src.outputs[0], mix.inputs[k])
    links.new(mix.outputs[0], _output(mat).inputs["Surface"])
    return mat


def mat_transparent(name):
    mat = _bare(name)
    nodes, links = _nodes(mat)
    links.new(nodes.new("ShaderNodeBsdfTransparent").outputs[0], _output(mat).inputs["Surface"])
    return mat


def mat_multi_output(name):
    """An ALL output (emission E4) and an active CYCLES output (emission E3)."""
    mat = mat_emission(name, E4, 1.0)
    nodes, links = _nodes(mat)
    out = nodes.new("ShaderNodeOutputMaterial")
    out.name = "Cycles Output"
    out.target = "CYCLES"
    out.location = (300, -300)
    links.new(_emission(nodes, E3, 1.0, (-300, -300)).outputs[0], out.inputs["Surface"])
    out.is_active_output = True
    return mat


def mat_volume(name, surface=True):
    mat = bpy.data.materials.new(name) if surface else _bare(name)
    nodes, links = _nodes(mat)
    vol = nodes.new("ShaderNodeVolumePrincipled")
    vol.location = (-300, -400)
    links.new(vol.outputs[0], _output(mat).inputs["Volume"])
    return mat


def mat_group_transparent(name):
    """A user group mixing a Principled with a Transparent BSDF inside (alpha the fog cannot weight)."""
    ng = bpy.data.node_groups.new("User Cutout", "ShaderNodeTree")
    ng.interface.new_socket("Shader", in_out="OUTPUT", socket_type="NodeSocketShader")
    gout = ng.nodes.new("NodeGroupOutput")
    mix = ng.nodes.new("ShaderNodeMixShader")
    ng.links.new(ng.nodes.new("ShaderNodeBsdfPrincipled").outputs[0], mix.inputs[1])
    ng.links.new(ng.nodes.new("ShaderNodeBsdfTransparent").outputs[0], mix.inputs[2])
    ng.links.new(mix.outputs[0], gout.inputs["Shader"])
    mat = _bare(name)
    nodes, links = _nodes(mat)
    g = nodes.new("ShaderNodeGroup")
    g.node_tree = ng
    links.new(g.outputs["Shader"], _output(mat).inputs["Surface"])
    return mat


def mat_volume_transparent(name):
    mat = mat_transparent(name)
    nodes, links = _nodes(mat)
    links.new(nodes.new("ShaderNodeVolumePrincipled").outputs[0], _output(mat).inputs["Volume"])
    return mat


def mat_group_principled(name):
    """Principled inside a user group; its Base Color from a group input fed by an RGB node outside."""
    ng = bpy.data.node_groups.new("User Shader", "ShaderNodeTree")
    ng.interface.new_socket("Colour", in_out="INPUT", socket_type="NodeSocketColor")
    ng.interface.new_socket("Shader", in_out="OUTPUT", socket_type="NodeSocketShader")
    gin, gout = ng.nodes.new("NodeGroupInput"), ng.nodes.new("NodeGroupOutput")
    p = ng.nodes.new("ShaderNodeBsdfPrincipled")
    p.inputs["Roughness"].default_value = 0.35
    p.inputs["Metallic"].default_value = 0.25
    ng.links.new(gin.outputs["Colour"], p.inputs["Base Color"])
    ng.links.new(p.outputs[0], gout.inputs["Shader"])
    mat = _bare(name)
    nodes, links = _nodes(mat)
    g = nodes.new("ShaderNodeGroup")
    g.node_tree = ng
    g.location = (-300, 0)
    rgb = nodes.new("ShaderNodeRGB")
    rgb.name = "User RGB"
    rgb.outputs[0].default_value = (0.7, 0.2, 0.1, 1.0)
    rgb.location = (-600, 0)
    links.new(rgb.outputs[0], g.inputs["Colour"])
    links.new(g.outputs["Shader"], _output(mat).inputs["Surface"])
    return mat


def mat_diffuse(name):
    mat = _bare(name)
    nodes, links = _nodes(mat)
    d = nodes.new("ShaderNodeBsdfDiffuse")
    d.inputs["Color"].default_value = (0.3, 0.6, 0.2, 1.0)
    links.new(d.outputs[0], _output(mat).inputs["Surface"])
    return mat


def mat_glossy(name):
    mat = _bare(name)
    nodes, links = _nodes(mat)
    links.new(nodes.new("ShaderNodeBsdfGlossy").outputs[0], _output(mat).inputs["Surface"])
    return mat


def mat_unlinked(name):
    mat = bpy.data.materials.new(name)
    mat.node_tree.links.remove(_output(mat).inputs["Surface"].links[0])
    return mat


def library_materials(tmp):
    """Link "Lib Linked" from a tiny library .blend, and make a library override of "Lib Override"."""
    a, b = mat_emission("Lib Linked", E1, 1.0), mat_emission("Lib Override", E2, 1.0)
    path = os.path.join(tmp, "library.blend")
    bpy.data.libraries.write(path, {a, b}, fake_user=True)
    bpy.data.materials.remove(a)
    bpy.data.materials.remove(b)
    with bpy.data.libraries.load(path, link=True) as (_, dst):
        dst.materials = ["Lib Linked", "Lib Override"]
    linked, to_override = dst.materials
    return linked, to_override.override_create(remap_local_usages=True)


def add_tile(scene, name, mat, x, z, y=TILE_Y, size=TILE):
    import bmesh
    bm = bmesh.new()
    h = 0.5 * size
    corners = ((x - h, y, z - h), (x + h, y, z - h), (x + h, y, z + h), (x - h, y, z + h))
    bm.faces.new([bm.verts.new(v) for v in corners])
    mesh = bpy.data.meshes.new(name)
    bm.to_mesh(mesh)
    bm.free()
    mesh.materials.append(mat)
    ob = bpy.data.objects.new(name, mesh)
    scene.collection.objects.link(ob)
    return ob


def build(scene, tmp, engine):
    tiny_render(scene, engine, W, H)
    measure.set_cycles_cpu(scene)
    scene.view_settings.view_transform = "Standard"
    cam = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    cam.data.lens, cam.data.sensor_width, cam.data.sensor_fit = LENS, SENSOR, "HORIZONTAL"
    cam.data.clip_start, cam.data.clip_end = 0.001, 1000.0
    cam.location = (0.0, CAM_Y, 0.0)
    cam.rotation_euler = (math.pi / 2, 0.0, 0.0)
    scene.collection.objects.link(cam)
    scene.camera = cam
    lamp = bpy.data.objects.new("Lamp", bpy.data.lights.new("Lamp", "POINT"))
    lamp.data.energy, lamp.data.shadow_soft_size = POWER, 0.0
    lamp.location = LAMP
    scene.collection.objects.link(lamp)
    world = bpy.data.worlds.new("World")
    world.node_tree.nodes["Background"].inputs["Color"].default_value = (0.004, 0.005, 0.008, 1.0)
    world.cycles.sampling_method = "NONE"   # the default importance map evaluates the fogged world shader ~20 s
    scene.world = world

    # tiles measured in the render (EEVEE: the emitters only; each material compiles a shader): (material, row, column)
    tiles = {
        "Emission": (mat_emission("Emission", E1, 2.0), 0, 0),
        "Principled Emission": (mat_principled("Principled Emission", (0, 0, 0), E2, 3.0, spec=0.0), 0, 1),
        "Holdout": (mat_holdout("Holdout"), 0, 2),
        "Holdout Mix": (mat_mix("Holdout Mix", 0.5, "emission", "holdout"), 0, 3),
        "Transparent": (mat_transparent("Transparent"), 0, 4),
        "Principled Alpha": (mat_principled("Principled Alpha", (0, 0, 0), E2, 3.0, alpha=0.5, spec=0.0), 0, 5),
        "Mix Transparent": (mat_mix("Mix Transparent", 0.3, "emission", "transparent", linked_fac=True), 0, 6),
        "Multi Output": (mat_multi_output("Multi Output"), 0, 7),
    }
    if engine == "CYCLES":
        linked, override = library_materials(tmp)
        tiles["Lib Linked"] = (linked, 1, 0)
        tiles["Lib Override"] = (override, 1, 1)
        shared = mat_principled("Shared", (0.5, 0.5, 0.5))
        tiles["Shared"] = (shared, 1, 2)
        tiles["Shared 2"] = (shared, 1, 3)
        others = [shared, mat_volume("Volume"), mat_volume("Volume Only", surface=False),
                  mat_group_principled("Group Principled"), mat_diffuse("Diffuse"), mat_glossy("Glossy"),
                  mat_group_transparent("Group Transparent"), mat_volume_transparent("Volume Transparent"),
                  mat_unlinked("No Surface Link"), mat_principled("Edit Resync", (0.6, 0.6, 0.6))]
        gp = bpy.data.materials.new("Grease Pencil")
        bpy.data.materials.create_gpencil_data(gp)
        others.append(gp)
        for k, mat in enumerate(others):   # out of frame
            add_tile(scene, f"Off {mat.name}", mat, 30.0 + 2 * k, 0.0)
    else:
        tiles = {k: v for k, v in tiles.items() if k in ("Emission", "Principled Emission")}
    for name, (mat, r, c) in tiles.items():
        add_tile(scene, f"Tile {name}", mat, COLS[c], ROWS[r])
    add_tile(scene, "Backdrop", mat_emission("Backdrop", E_BACK, 1.0), 0.0, 0.0, y=BACK_Y, size=30.0)
    return {name: (r, c) for name, (mat, r, c) in tiles.items()}


# --- measurement -------------------------------------------------------------------

def pixel_of(x, z):
    """(row from top, column) of the pixel whose centre ray passes nearest to (x, TILE_Y, z)."""
    d = TILE_Y - CAM_Y
    u = x * LENS / d / SENSOR + 0.5
    v = z * LENS / d / (SENSOR * H / W) + 0.5
    return H - 1 - int(v * H), int(u * W)


def distance(row, col, plane_y):
    """Camera-to-hit distance of that pixel's centre ray on the plane y = plane_y."""
    xs = ((col + 0.5) / W - 0.5) * SENSOR
    zs = (0.5 - (row + 0.5) / H) * SENSOR * H / W
    return (plane_y - CAM_Y) * math.sqrt(xs * xs + LENS * LENS + zs * zs) / LENS


def render(scene, path):
    measure.configure_output(scene, path)
    scene.render.film_transparent = True
    bpy.ops.render.render(write_still=True, scene=scene.name)
    return imageio.read(path)


def black_airlight(scene, tmp, tag):
    """(A_tile, A_back): renders with every material a fogged black emission; tiles there / hidden."""
    black = mat_emission("AF Black", (0.0, 0.0, 0.0), 0.0)
    saved = {}
    for ob in scene.objects:
        if ob.type == "MESH":
            saved[ob.name] = [s.material for s in ob.material_slots]
            for s in ob.material_slots:
                s.material = black
    apply.apply_fog(scene, DENSITY)
    a_tile = render(scene, os.path.join(tmp, f"{tag}_a_tile.exr"))
    tiles = [ob for ob in scene.objects if ob.name.startswith("Tile ")]
    for ob in tiles:
        ob.hide_render = True
    a_back = render(scene, os.path.join(tmp, f"{tag}_a_back.exr"))
    for ob in tiles:
        ob.hide_render = False
    apply.remove_fog(scene)
    for name, mats in saved.items():
        for s, m in zip(scene.objects[name].material_slots, mats):
            s.material = m
    bpy.data.materials.remove(black)
    return a_tile, a_back


def _ray(row, col):
    xs = ((col + 0.5) / W - 0.5) * SENSOR
    zs = (0.5 - (row + 0.5) / H) * SENSOR * H / W
    d = np.array([xs, LENS, zs])
    return d / np.linalg.norm(d)


def model_airlight():
    """(A_tile, A_back) from the numpy twin of the node groups (EEVEE: saves two renders)."""
    from fog_addon.precompute.physics.point import airlight
    cam, lamp = np.array([0.0, CAM_Y, 0.0]), np.array(LAMP)
    to = lamp - cam
    rays = np.array([[_ray(r, c) for c in range(W)] for r in range(H)])
    gamma = np.arccos(np.clip(rays @ to / np.linalg.norm(to), -1.0, 1.0))
    table = airlight.bake_airlight_table()
    out = []
    for plane in (TILE_Y, BACK_Y):
        d_vp = np.array([[distance(r, c, plane) for c in range(W)] for r in range(H)])
        a = POWER / (4 * math.pi) * airlight.airlight(DENSITY, np.linalg.norm(to), d_vp, gamma, table=table)
        out.append(np.repeat(a[..., None], 3, axis=-1))
    return out


def direct_attenuation(row, col):
    """e^{-beta D_sp} at that pixel's tile point: what EEVEE's scale also multiplies by (one lamp)."""
    p = np.array([0.0, CAM_Y, 0.0]) + distance(row, col, TILE_Y) * _ray(row, col)
    return math.exp(-DENSITY * float(np.linalg.norm(np.array(LAMP) - p)))


def expected(name, pix, a_tile, a_back):
    """(rgb, alpha) the fogged tile ``name`` must render at ``pix``, or None if not measured."""
    r, c = pix
    t = math.exp(-DENSITY * distance(r, c, TILE_Y))
    tb = math.exp(-DENSITY * distance(r, c, BACK_Y))
    at, ab = a_tile[r, c, :3].astype(float), a_back[r, c, :3].astype(float)
    back = tb * np.array(E_BACK) + ab

    def emitter(e, s):
        return t * s * np.array(e) + at

    table = {
        "Emission": (emitter(E1, 2.0), 1.0),
        "Principled Emission": (emitter(E2, 3.0), 1.0),
        "Holdout": (np.zeros(3), 0.0),
        "Holdout Mix": (0.5 * emitter(E1, 2.0), 0.5),
        "Transparent": (back, 1.0),
        "Principled Alpha": (0.5 * emitter(E2, 3.0) + 0.5 * back, 1.0),
        "Mix Transparent": (0.7 * emitter(E1, 2.0) + 0.3 * back, 1.0),
        "Multi Output": (emitter(E3 if bpy.context.scene.render.engine == "CYCLES" else E4, 1.0), 1.0),
    }
    return table.get(name)


def unfogged(name, pix):
    """(rgb, alpha) of the tile without fog (checks the set-up itself)."""
    e = {"Emission": (2.0 * np.array(E1), 1.0), "Principled Emission": (3.0 * np.array(E2), 1.0),
         "Holdout": (np.zeros(3), 0.0), "Holdout Mix": (np.array(E1), 0.5), "Transparent": (np.array(E_BACK), 1.0),
         "Principled Alpha": (1.5 * np.array(E2) + 0.5 * np.array(E_BACK), 1.0),
         "Mix Transparent": (1.4 * np.array(E1) + 0.3 * np.array(E_BACK), 1.0),
         "Multi Output": (np.array(E3 if bpy.context.scene.render.engine == "CYCLES" else E4), 1.0)}
    return e.get(name)


def rel_err(got, want):
    got, want = np.asarray(got, float), np.asarray(want, float)
    return float(np.max(np.abs(got - want) / np.maximum(np.abs(want), 1e-3)))


# --- structure ---------------------------------------------------------------------

def snapshot():
    """tests/scenes/add_remove.py's snapshot, keyed by full names (a linked and a local "X" both exist)."""
    snap = add_remove.snapshot()
    snap["materials"] = {m.name_full: add_remove.snapshot_material(m) for m in bpy.data.materials}
    snap["images"] = [n for n in snap["images"] if n != "Render Result"]
    return snap


def fog_nodes(mat, bl_idname="ShaderNodeGroup"):
    return [n for n in mat.node_tree.nodes if owned.is_ours(n) and n.bl_idname == bl_idname]


def fed_by_fog(mat, target):
    out = graph.effective_output(mat.node_tree, target)
    return bool(out is not None and out.inputs["Surface"].is_linked
                and owned.is_ours(out.inputs["Surface"].links[0].from_node))


def structure():
    m = bpy.data.materials
    res = {}
    vol = m["Volume"]
    vsrc = next(n for n in vol.node_tree.nodes if n.bl_idname == "ShaderNodeVolumePrincipled").outputs[0]
    res["volume_kept"] = all(
        (o := graph.effective_output(vol.node_tree, t)) is not None and o.inputs["Volume"].is_linked
        and o.inputs["Volume"].links[0].from_socket == vsrc for t in graph.TARGETS)
    res["volume_surface_fogged"] = all(fed_by_fog(vol, t) for t in graph.TARGETS)
    res["shared_fog_nodes"] = len(fog_nodes(m["Shared"]))
    res["shared_users"] = m["Shared"].users
    res["multi_output_fogged"] = {t: fed_by_fog(m["Multi Output"], t) for t in graph.TARGETS}
    g = m["Group Principled"]
    fog = fog_nodes(g)
    if fog:
        bc = fog[0].inputs["Base Color"]
        res["group_base_color_linked_to_rgb"] = bc.is_linked and bc.links[0].from_node.name == "User RGB"
        res["group_roughness"] = round(fog[0].inputs["Roughness"].default_value, 6)
        res["group_metallic"] = round(fog[0].inputs["Metallic"].default_value, 6)
    fog = fog_nodes(m["Diffuse"])
    if fog:
        res["diffuse_base_color"] = [round(v, 6) for v in fog[0].inputs["Base Color"].default_value[:3]]
        res["diffuse_specular"] = fog[0].inputs["Specular IOR Level"].default_value
    return res


def edit_resync(scene):
    """The user edits a fogged Principled (value and a texture link); apply_fog again must follow it."""
    mat = bpy.data.materials["Edit Resync"]
    tree = mat.node_tree
    p = tree.nodes["Principled BSDF"]
    old = tuple(p.inputs["Base Color"].default_value)
    p.inputs["Base Color"].default_value = EDIT_COLOR
    tex = tree.nodes.new("ShaderNodeTexChecker")
    tex.name = "User Checker"
    tex.location = (-600, -300)
    tree.links.new(tex.outputs["Fac"], p.inputs["Roughness"])
    edited = snapshot()
    apply.apply_fog(scene, DENSITY)
    after = snapshot()
    fog = fog_nodes(mat)[0]
    rough = fog.inputs["Roughness"]
    res = {
        "changed_by_add_after_edit": add_remove.differing(edited, after),
        "base_color_follows": all(abs(a - b) < 1e-6
                                  for a, b in zip(fog.inputs["Base Color"].default_value, EDIT_COLOR)),
        "roughness_link_follows": rough.is_linked and rough.links[0].from_socket == tex.outputs["Fac"],
    }

    def undo():
        p.inputs["Base Color"].default_value = old
        tree.nodes.remove(tree.nodes["User Checker"])

    def present():
        return (all(abs(a - b) < 1e-6 for a, b in zip(p.inputs["Base Color"].default_value, EDIT_COLOR))
                and p.inputs["Roughness"].is_linked
                and p.inputs["Roughness"].links[0].from_node.name == "User Checker")
    return res, undo, present


# --- main --------------------------------------------------------------------------

def main(tmp, engine="CYCLES"):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    placed = build(scene, tmp, engine)
    pixels = {name: pixel_of(COLS[c], ROWS[r]) for name, (r, c) in placed.items()}
    tag = engine.lower()
    cycles = engine == "CYCLES"
    res = {"engine": engine}

    before = snapshot()
    r0 = render(scene, os.path.join(tmp, f"{tag}_r0.exr")) if cycles else None
    skipped = apply.apply_fog(scene, DENSITY)
    reasons = dict(skipped)
    once = snapshot()
    used = apply.scene_materials(scene)
    res["materials"] = {m.name_full: {"fogged": owned.is_fogged(m), "reason": reasons.get(m.name),
                                      "in_scene": m in used} for m in bpy.data.materials}
    res["skipped"] = skipped
    r1 = render(scene, os.path.join(tmp, f"{tag}_r1.exr"))
    apply.apply_fog(scene, DENSITY)
    res["changed_by_second_add"] = add_remove.differing(once, snapshot())
    if cycles:
        res["structure"] = structure()
        res["library_unchanged"] = {n: once["materials"][n] == before["materials"][n]
                                    for n in once["materials"] if n.startswith("Lib ")}
        res["edit"], undo, present = edit_resync(scene)
    apply.remove_fog(scene)
    if cycles:
        res["edit"]["kept_by_remove"] = present()
        undo()
    res["not_restored"] = add_remove.differing(before, snapshot())
    if cycles:
        r2 = render(scene, os.path.join(tmp, f"{tag}_r2.exr"))
        res["render_restored_max_abs"] = float(np.max(np.abs(r2 - r0)))
        a_tile, a_back = black_airlight(scene, tmp, tag)
    else:
        a_tile, a_back = model_airlight()
    pix = {}
    for name, (r, c) in pixels.items():
        got = r1[r, c].astype(float)
        rec = {"pixel": [r, c], "got": [round(float(v), 6) for v in got]}
        want0 = unfogged(name, (r, c))
        if r0 is not None:
            rec["unfogged"] = [round(float(v), 6) for v in r0[r, c]]
        if r0 is not None and want0 is not None:
            rec["setup_err"] = max(rel_err(r0[r, c, :3], want0[0]), abs(float(r0[r, c, 3]) - want0[1]))
        want = expected(name, (r, c), a_tile, a_back)
        if want is not None:
            rec["want"] = [round(float(v), 6) for v in want[0]] + [want[1]]
            rec["rgb_err"] = rel_err(got[:3], want[0])
            rec["alpha_err"] = abs(float(got[3]) - want[1])
            if not cycles and want0 is not None:   # what EEVEE gave before emission was restored
                t = math.exp(-DENSITY * distance(r, c, TILE_Y))
                old = t * direct_attenuation(r, c) * want0[0] + a_tile[r, c, :3]
                rec["err_if_dimmed_by_direct_attenuation"] = rel_err(got[:3], old)
        rec["airlight"] = [round(float(v), 6) for v in a_tile[r, c, :3]]
        rec["transmittance"] = round(math.exp(-DENSITY * distance(r, c, TILE_Y)), 6)
        pix[name] = rec
    res["pixels"] = pix
    print(json.dumps(res))


if __name__ == "__main__":
    main(sys.argv[1], *(sys.argv[2:3] or []))
