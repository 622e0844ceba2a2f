"""Helpers of the shared_*.py scene scripts: what fog data exists, and which copies the fogged data uses."""
import pathlib
import re
import sys

ROOT = pathlib.Path(__file__).resolve().parents[2]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

import bpy  # noqa: E402

from fog_addon import caveats  # noqa: E402
from fog_addon.nodes import compositor, groups, images, light_bundles, osl, owned  # noqa: E402
from fog_addon.precompute.model import rungs  # noqa: E402
from fog_addon.precompute.physics.point import multiple  # noqa: E402
from fog_addon.ops import apply  # noqa: E402

PREFIX = "AnalyticFog"
SUFFIXED = re.compile(r"\.\d{3,}$")


def fog_ids():
    """{"groups"|"images"|"texts": sorted names of every AnalyticFog data-block}."""
    return {
        "groups": sorted(g.name for g in bpy.data.node_groups if g.name.startswith(PREFIX)),
        "images": sorted(i.name for i in bpy.data.images if i.name.startswith(PREFIX)),
        "texts": sorted(t.name for t in bpy.data.texts if t.name.startswith(PREFIX)),
    }


def copies(ids=None):
    """{name: count} of the fog data-blocks by base name (the ``.NNN`` suffix stripped), and the suffixed names."""
    ids = fog_ids() if ids is None else ids
    count, suffixed = {}, []
    for names in ids.values():
        for n in names:
            base = SUFFIXED.sub("", n)
            count[base] = count.get(base, 0) + 1
            if base != n:
                suffixed.append(n)
    return count, sorted(suffixed)


def expected_names(method, scene=None, texts_of=None):
    """What one fogged file holds: the scene groups, the per-light groups of the method's models, every
    table (apply_fog bakes both) and the OSL texts of the models that run in OSL (or of ``texts_of``'s
    models: a text stays when the method switches back); and ``scene``'s own compositor group where
    the fog set one up (``nodes/compositor.py``: Cycles with its denoiser on)."""
    # Dense Fog by the Quality (on by default): the lights' groups hold its rungs where a light got it
    choice = apply.stored_choice() if scene is not None else None
    spec = apply.spec_of(scene) if scene is not None else None
    dense = (spec is not None and choice is not None and spec.multiple_scattering
             and len(choice.get("thin", {})) < len(choice["lights"]))
    albedo = spec.multiple_albedo if dense else None
    # (beside surfaces each light's Dense Fog takes its scale: ``escape.field_scales``; one group per scale)
    scales = ((choice or {}).get("dense") or {}).get("scales") or {}
    lights = apply.fog_lights(scene)[0] if scene is not None else []
    names = [groups.PARAMS, groups.SURFACE, groups.WORLD]
    for scale in sorted({scales.get(o.name, 1.0) for o in lights} if albedo is not None and lights else {1.0}):
        models = rungs.choose(method, multiple_albedo=albedo, multiple_scale=scale)
        names += [groups.light_group_name(models), groups.background_group_name(models)]
    if albedo is not None and method != "osl":   # (its table: OSL has no Dense Fog)
        names.append(multiple.table_spec(spec.anisotropy, albedo).name)
    if scene is not None:   # the lights' bundles: every light full (these files' Quality keeps them all)
        n = len(apply.fog_lights(scene)[0])
        names += [f"{prefix} {k + 1}-{min(k + light_bundles.BUNDLE, n)}"
                  for prefix in (groups.SURFACE_LIGHTS, groups.WORLD_LIGHTS) for k in range(0, n, light_bundles.BUNDLE)]
        if method in ("nodes", "osl") and caveats.specular_paths(bpy.data.materials):   # past glass and mirrors
            names += [f"{groups.SURFACE_TAILS} {k + 1}-{min(k + light_bundles.BUNDLE, n)}"
                      for k in range(0, n, light_bundles.BUNDLE)]
    names += images.table_names()
    names += [osl.text_name(r) for r in rungs.choose(texts_of or method) if r.backends == {"numpy", "osl"}]
    tree = scene.compositing_node_group if scene is not None and compositor.is_set_up(scene) else None
    if tree is not None and tree.get(owned.TAG) is not None:
        names.append(compositor.GROUP)
    return sorted(set(names))


def _group_nodes(tree):
    return [n for n in tree.nodes if n.bl_idname == "ShaderNodeGroup" and n.node_tree is not None]


def fog_references():
    """Every (user, fog data-block name) reference: group nodes in materials, worlds, lights and groups; images; texts."""
    refs = []
    owners = [(f"material {m.name}", m.node_tree) for m in bpy.data.materials if m.node_tree]
    owners += [(f"world {w.name}", w.node_tree) for w in bpy.data.worlds if w.node_tree]
    owners += [(f"light {l.name}", l.node_tree) for l in bpy.data.lights if l.node_tree]
    owners += [(f"group {g.name}", g) for g in bpy.data.node_groups]
    for who, tree in owners:
        for n in tree.nodes:
            if n.bl_idname == "ShaderNodeGroup" and n.node_tree is not None and n.node_tree.name.startswith(PREFIX):
                refs.append((who, n.node_tree.name))
            img = getattr(n, "image", None)
            if img is not None and img.name.startswith(PREFIX):
                refs.append((who, img.name))
            script = getattr(n, "script", None)
            if script is not None and script.name.startswith(PREFIX):
                refs.append((who, script.name))
    return sorted(set(refs))


def driver_targets(idblock):
    ad = idblock.animation_data if idblock is not None else None
    if ad is None:
        return []
    return sorted({t.id.name for fc in ad.drivers for v in fc.driver.variables for t in v.targets if t.id})


def bundle_driver_targets(name):
    """What the drivers of the scene group ``name`` and of the light bundles it holds read from."""
    ng = bpy.data.node_groups.get(name)
    if ng is None:
        return []
    trees = [ng] + [n.node_tree for n in _group_nodes(ng) if n.node_tree.name.startswith(name + " Lights")]
    return sorted(set().union(*(driver_targets(t) for t in trees)))


def fog_groups_of(mat):
    return sorted(n.node_tree.name for n in _group_nodes(mat.node_tree) if n.node_tree.name.startswith(PREFIX))


def beta(params_name=groups.PARAMS):
    ng = bpy.data.node_groups.get(params_name)
    return None if ng is None else ng.nodes["Beta"].outputs[0].default_value
