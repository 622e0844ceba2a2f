"""The fog passes: shader AOVs holding the fog's part of each pixel, for compositing.

* ``Fog Light`` (colour): the light the fog adds to what the camera sees, the
  airlight along the camera ray plus the fog light scattered onto the surface
  (the L_a term of Sun et al. 2005 Eq. 19).  It is exactly the fog's emission
  in each material and in the World.  Where a material lets light through, the
  emission is weighted by the material's opacity, and so is the pass: it holds
  what is actually added.
* ``Fog Transmittance`` (value): e^{-beta D_vp} along the camera ray, weighted
  by the same opacity; 0 on the background, which is seen through infinite fog.

Camera rays that meet an opaque surface give Combined = Fog Transmittance x
(the surface as lit through the fog) + Fog Light.  Cycles writes shader AOVs on
camera rays and adds those of every surface a ray passes through (Transparent
BSDF, alpha), with its own sampling weights; its OSL backend writes none
(Blender 5.0), so with the OSL method both passes stay black in Cycles.

The AOV Output nodes sit in the fog's shared ``AnalyticFog Surface`` and
``AnalyticFog World`` groups, fed by what the groups output (AOV outputs
inside a group are written in Cycles and EEVEE, the group node's outputs
linked or not), so a material gets no node of its own for them: one that lets
light through feeds its opacity to the Surface node's ``Opacity`` input (white
by default).  Per-material AOV Output nodes cost 1.1-1.4 ms per material (the
1000-material add went over its 10 s budget).  The World's Fog Light reads
its own instances of the lights' groups (``world_group.build_world`` says why).
The view layers get the two AOVs while the fog is on; each view layer records
the names it was given (``ADDED``), so Remove deletes exactly those.  A user's
AOV of the same name and type is used and kept.
"""

FOG_LIGHT = "Fog Light"
TRANSMITTANCE = "Fog Transmittance"
AOVS = ((FOG_LIGHT, "COLOR"), (TRANSMITTANCE, "VALUE"))
ADDED = "analytic_fog_aovs"   # on a view layer: {"names": [AOV names the fog added], "active": the user's active index}
ROLES = {FOG_LIGHT: "Fog Light AOV", TRANSMITTANCE: "Fog Transmittance AOV"}   # the AOV Output nodes' names
OPACITY = "Opacity"   # the Surface group's input: the material's opacity, which weights the passes
VERSION = 2           # in each material's stamp: bumped when the material's fog nodes change (2: the Fog shader), so older ones are rebuilt once


# --- the view layers' AOVs --------------------------------------------------------------------

def add_view_layer_aovs(scene, aovs=AOVS):
    """Give each of ``scene``'s view layers the AOVs ``aovs`` ((name, type) pairs: the fog passes', or the
    Compositor method's inputs); returns [(view layer, reason)] for clashes.

    A user's AOV of the same name and type is used as it is (and kept on
    Remove); one of the same name and another type is left alone and reported.
    """
    notes = []
    for vl in scene.view_layers:
        record = vl.get(ADDED)
        added = list(record["names"]) if record is not None else []
        active = record["active"] if record is not None else vl.active_aov_index
        for name, kind in aovs:
            aov = vl.aovs.get(name)
            if aov is None:
                aov = vl.aovs.add()
                aov.name, aov.type = name, kind
                if name not in added:
                    added.append(name)
            elif aov.type != kind:
                notes.append((vl.name, f"has an AOV {name!r} of type {aov.type}: the fog's {kind.lower()} "
                                       f"pass of that name is not written there (rename yours to get it)"))
        if added:
            vl[ADDED] = {"names": added, "active": active}
            vl.active_aov_index = active
    return notes


def remove_view_layer_aovs(scene, kinds, keep=()):
    """Delete the AOVs the fog added to ``scene``'s view layers (the user's own stay), but those named in
    ``keep``; ``kinds``: {name: type} of every AOV the fog adds (one of another type is the user's)."""
    for vl in scene.view_layers:
        record = vl.get(ADDED)
        if record is None:
            continue
        for name in record["names"]:
            aov = vl.aovs.get(name)
            if name not in keep and aov is not None and aov.type == kinds.get(name):
                vl.aovs.remove(aov)
        if 0 <= record["active"] < len(vl.aovs):
            vl.active_aov_index = record["active"]
        names = [n for n in record["names"] if n in keep]
        if names:
            vl[ADDED] = {"names": names, "active": record["active"]}
        else:
            del vl[ADDED]


def has_view_layer_aovs(view_layer):
    """True if ``view_layer`` has both fog AOVs with the right types."""
    return all((a := view_layer.aovs.get(n)) is not None and a.type == k for n, k in AOVS)


# --- AOV Output nodes in the fog's Surface and World groups ------------------------------------------

def write_group(m, ng, light, transmittance, opacity=None, light_weighted=False):
    """AOV Output nodes in the fog's group ``ng`` (built by ``m``, its NodeOps): Fog Light = ``light``
    and Fog Transmittance = ``transmittance``, both times ``opacity`` (the Surface group's Opacity
    input, a colour: its mean for the value) where given; ``light_weighted``: ``light`` already is."""
    if opacity is not None:
        light = light if light_weighted else light * opacity
        transmittance = transmittance * m.vmath("DOT_PRODUCT", opacity, (1.0 / 3.0,) * 3, out=1)
    for k, (name, value, sock) in enumerate(((FOG_LIGHT, light, "Color"), (TRANSMITTANCE, transmittance, "Value"))):
        node = ng.nodes.new("ShaderNodeOutputAOV")
        node.name = node.label = ROLES[name]
        node.aov_name = name
        node.location = (4000, -300 - 150 * k)
        m.feed(node.inputs[sock], m.wrap(value))


def weight_surface(ops, fog, opacity):
    """Give the material's ``AnalyticFog Surface`` node ``fog`` the material's ``opacity`` (a Val of
    ``ops``, the material's NodeOps) for the passes; an opaque material leaves the input at white."""
    if opacity.const is not None and all(c == 1.0 for c in opacity.const):
        return
    ops.feed(fog.inputs[OPACITY], opacity)
