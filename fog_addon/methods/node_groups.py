"""The node-group methods: every fogged material and the World evaluate every light's terms per sample.

``NodeGroups`` reads the glow from the node groups' tables (Cycles and EEVEE); ``Osl`` prefers the OSL
rungs (the glow by quadrature in an OSL script, Cycles only, with Open Shading Language switched on).
Their cost grows with lights x materials x samples (``auto.py`` predicts it); EEVEE's uniform block and
OSL's shader group cap what one material holds (``budget``): lights step down the ladder beyond the
target until they fit.
"""
import bpy

from ..nodes import budgets, passes, surface_group, world_group
from .. import caveats, sunsky, view
from .base import Method

MANY_LIGHTS = 8   # from this many fog lights on, Cycles' node groups get a note (``many_lights_note``)


class NodeGroups(Method):
    name = "nodes"
    label = "Node Groups"
    preference = "nodes"

    def budget(self, scene, spec, lights):
        if scene.render.engine == budgets.EEVEE_ENGINE:
            return budgets.eevee_budget(spec.anisotropy, [view.has_shape(o) for o in lights],
                                        [view.is_area(o) for o in lights], spec.multiple_albedo is not None)
        return None

    def build(self, scene, spec, plan, images):
        day = sunsky.builder(scene, spec)
        table, table_images = sunsky.fog_light_table(scene, spec)   # (None: no daylight to glow)
        images = dict(images, **table_images)
        surface_group.build_surface(plan.shader_lights, plan.shader_models, images, spec.passes,
                                    tails=caveats.specular_paths(bpy.data.materials), day=day, day_table=table,
                                    day_dims=sunsky.dims_surfaces(scene, plan.in_groups),
                                    mirrors=scene.render.engine == "CYCLES")
        world_group.build_world(plan.shader_lights, plan.shader_models, scene.camera, images, spec.passes, day=day,
                                day_table=table)
        return images

    def passes(self, scene, spec):
        return passes.AOVS if spec.passes else ()

    def notes(self, scene, spec, plan):
        notes = []
        if scene.render.engine == "CYCLES" and len(plan.in_groups) >= MANY_LIGHTS:
            notes.append((scene.render.engine, many_lights_note(plan.in_groups, plan.choice)))
        return notes


class Osl(NodeGroups):
    """Builds in any engine (the groups follow when the user switches to Cycles), but only Cycles runs OSL:
    elsewhere the fog has no glow and no fog light, which ``notes`` says (the command line refuses it)."""
    name = "osl"
    label = "OSL"
    preference = "osl"

    def budget(self, scene, spec, lights):
        return budgets.osl_budget([view.has_shape(o) for o in lights], [view.is_area(o) for o in lights])

    def notes(self, scene, spec, plan):
        if scene.render.engine != "CYCLES":
            return [(scene.render.engine, "the OSL method runs in Cycles only: switch the render engine to Cycles "
                                          "to see the fog's glow and light")]
        return super().notes(scene, spec, plan)


def many_lights_note(lights, choice):
    """Why the Compositor method suits ``lights`` (as many as MANY_LIGHTS or more) in Cycles better than the
    materials' node groups or OSL: what each fogged material holds (``budgets.material_nodes``)."""
    nodes = budgets.material_nodes([choice["lights"].get(o.name, [0])[0] for o in lights],
                                   [view.has_shape(o) for o in lights])
    return (f"{len(lights)} lights: each fogged material holds about {nodes:,} fog nodes and evaluates them on "
            "every sample, and Cycles' set-up before the first sample grows with their square (64 lights on 4 "
            "materials: about 20 s of CPU per render, 256 lights: about 30 min); the Compositor method's "
            "materials do not depend on the lights (1.5-1.9x the fog-free render at 16 to 64 lights)")
