"""What the fog does not model in a scene yet, said plainly (the panel, the operator's report, ``render``).

* **Light shafts.** The glow of a light integrates every camera ray as if nothing stood between the light and
  the fog (Sun et al. 2005 Eq. 5 without a visibility term; Dobashi et al. 2002 Eq. 2's H = 1): objects cast
  no shadow into the fog, and a lamp under an opaque hood lights the fog above it.  ``shadow_note`` names
  the lights with an object in their glow: an object whose bounding box comes within the distance at which
  the light's glow has fallen by e^-3 (``GLOW_OPTICAL_DEPTH`` / beta, at most the scene's size).
* **Glass and mirrors.** A camera ray that passes through a see-through material or reflects off a mirror gets
  the fog of its first segment only: the fog behind the pane is not seen through it (``see_through``).
"""
import numpy as np

from .precompute import footprint

GLOW_OPTICAL_DEPTH = 3.0   # beta x distance within which a light's glow is worth a shadow (e^-3 = 5 %)
_SEE_THROUGH = ("ShaderNodeBsdfTransparent", "ShaderNodeBsdfGlass", "ShaderNodeBsdfRefraction",
                "ShaderNodeBsdfTranslucent", "ShaderNodeBsdfHairPrincipled", "ShaderNodeBsdfHair")


def see_through(materials, objects):
    """Names of ``materials`` that let the camera see through them (Transparent, Glass, Refraction,
    Translucent or hair BSDFs, a Principled BSDF with transmission or alpha below 1) on ``objects`` the camera
    sees, each once."""
    seen = {slot.material for obj in objects if obj.visible_camera
            for slot in getattr(obj, "material_slots", ()) if slot.material is not None}
    names = []
    for mat in materials:
        if mat not in seen or mat.node_tree is None:
            continue
        if any(not node.mute and (node.bl_idname in _SEE_THROUGH or (node.bl_idname == "ShaderNodeBsdfPrincipled"
                                                                        and _principled_see_through(node)))
               for node in mat.node_tree.nodes):
            names.append(mat.name)
    return names


def _principled_see_through(node):
    for name, clear in (("Transmission Weight", 0.0), ("Alpha", 1.0)):
        sock = node.inputs.get(name)
        if sock is not None and (sock.is_linked or sock.default_value != clear):
            return True
    return False


def _box_distance(corners, point):
    """Distance (m) from ``point`` to the axis-aligned box around ``corners`` (8, 3): 0 inside."""
    lo, hi = corners.min(axis=0), corners.max(axis=0)
    return float(np.linalg.norm(np.maximum(np.maximum(lo - point, point - hi), 0.0)))


def _flat_side(obj):
    """(centre, unit normal) in world space of a flat object (its bounding box has no thickness along one local
    axis: a plane, a wall of one face), else None."""
    local = np.asarray(obj.bound_box, float)
    size = local.max(axis=0) - local.min(axis=0)
    k = int(np.argmin(size))
    if size[k] > 1e-6 * max(float(size.max()), 1e-30):
        return None
    m = np.asarray(obj.matrix_world, float)
    normal = np.linalg.inv(m[:3, :3]).T[:, k]
    return m[:3, :3] @ local.mean(axis=0) + m[:3, 3], normal / max(np.linalg.norm(normal), 1e-30)


def shadowing_lights(scene, lights, beta, reach_m):
    """{light name: number of objects} for the ``lights`` with a shadow-casting object (a mesh, curve or the
    like, visible to shadow rays) within their glow's reach: GLOW_OPTICAL_DEPTH / ``beta`` (1/unit), at most
    ``reach_m`` (scene units).  A flat object (a ground plane) counts only where the camera sees its far side
    from the light, where its shadow in the fog lies."""
    reach = min(GLOW_OPTICAL_DEPTH / beta, reach_m) if beta > 0.0 else reach_m
    eye = np.array(scene.camera.matrix_world.translation) if scene.camera is not None else None
    objects = [(np.array(footprint.box_points(o.bound_box, o.matrix_world)).reshape(8, 3), _flat_side(o))
               for o in scene.objects if o.type in ("MESH", "CURVE", "SURFACE", "META", "FONT")
               and not o.hide_render and o.visible_shadow]
    found = {}
    for light in lights:
        p = np.array(light.matrix_world.translation)
        n = 0
        for box, flat in objects:
            if _box_distance(box, p) >= reach:
                continue
            if flat is not None and eye is not None:
                centre, normal = flat
                if np.sign(np.dot(normal, p - centre)) == np.sign(np.dot(normal, eye - centre)):
                    continue   # the light and the camera on the same side: its shadow is out of sight
            n += 1
        if n:
            found[light.name] = n
    return found


def shadow_note(scene, lights, beta, reach_m):
    """A note if objects stand in the glow of some of ``lights`` (they cast no shadow into the fog), else None."""
    found = shadowing_lights(scene, lights, beta, reach_m)
    if not found:
        return None
    names = sorted(found)
    shown = ", ".join(names[:3]) + (f" and {len(names) - 3} more" if len(names) > 3 else "")
    return (f"light shafts are not modelled yet: objects cast no shadow into the fog, so the glow of "
            f"{len(names)} light(s) ({shown}) passes through the objects near them (a lamp's hood, a wall, a "
            "window frame)")


def glass_note(materials, objects):
    """A note if see-through materials are in view (the fog behind them is not seen through them), else None."""
    names = see_through(materials, objects)
    if not names:
        return None
    shown = ", ".join(names[:3]) + (f" and {len(names) - 3} more" if len(names) > 3 else "")
    return (f"see-through materials ({shown}): the fog and the glows behind glass or in a mirror are not seen "
            "through it yet (the camera ray's fog ends at the first surface)")
