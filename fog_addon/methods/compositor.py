"""The Compositor method: the fog's light added once per pixel in the compositor (``nodes/comp_fog.py``).

The materials keep only what depends on each sample's depth (the camera ray's extinction, and in EEVEE
the lights' shared dimming of direct light: ``dimming_lights``); the compositor's group evaluates each
light's glows and the fog light its pixel's surface reflects, within the light's window
(``precompute/model/footprint.py``).  Limits: one surface point per pixel, perspective cameras.  The fog passes
are the compositor's, written by a File Output node (``nodes/compositor.py``).
"""
import functools

import bpy
import numpy as np

from ..nodes import (budgets, comp_daylight, comp_fog, comp_shafts, compositor, glass_tails, graph, owned, passes,
                     preview as preview_, preview_sampled, surface_group,
                     world_group)
from .. import caveats, shadow_maps, sunsky, view
from ..precompute.model import footprint, predict, rungs, sampling
from ..precompute.physics.shafts import shafts
from .base import Method

# The viewport's preview of the Compositor's fog (``nodes/preview.py``): each light's share of its budget by ladder
# step (rungs.STEPS: full, glow only, off, left out) and the budget: two lights, each fully modelled or its glow
# alone, with their shafts; the other point lights are sampled, fully modelled, one a sample (``preview_sampled``),
# so a glow-only step would drop the reflected fog light the sampling would have given.  In Cycles, where a scene
# has more point lights than the budget holds (SAMPLE_ALL_FROM or more), the preview samples all of them: a light's
# kernels cost a sample about as much as the fog-free render's own, so two modelled on every sample and one sampled
# cost the viewport several times the fog-free render's time, one sampled about once more
# (docs/measurements/2026-11-29-viewport-preview.md)
PREVIEW_COST = (2.0, 2.0, 0.0, 0.0)
PREVIEW_LIMIT = 4.0
SAMPLE_ALL_FROM = 3


class Compositor(Method):
    name = "compositor"
    label = "Compositor"
    preference = "compositor"

    def check(self, scene, spec):
        why = super().check(scene, spec)
        if why is not None:
            return why
        camera = scene.camera
        eevee = scene.render.engine == budgets.EEVEE_ENGINE
        if camera is not None and camera.data.type != "PERSP" and (eevee or camera.data.type != "PANO"):
            return (f"the Compositor method needs a perspective camera{'' if eevee else ' or a panoramic one'} "
                    f"({camera.name!r} is {camera.data.type.lower()}): use the Node Groups method")
        return None

    def shader_lights(self, scene, spec, lights, models):
        return dimming_lights(scene, spec, lights)

    def preview_budget(self, scene, spec, lights):
        preview = predict.Budget([PREVIEW_COST], [PREVIEW_LIMIT], "the viewport preview's budget")
        if scene.render.engine != budgets.EEVEE_ENGINE:
            if not samples_all(scene, lights):
                return preview
            preview = predict.joint([preview], len(lights))   # (every point light beyond the budget: sampled)
            sampled = set(preview_sampled.sampled(lights))
            points = [i for i, o in enumerate(lights) if o in sampled]
            preview.cost[:, points, :rungs.OFF] = PREVIEW_LIMIT + 1.0
            return preview
        # EEVEE: the preview's lights share the materials' uniform block with the lights whose direct light they
        # dim (``dimming_lights``), which keep the room they have without a preview (the final render's)
        dimmed, _ = dimming_lights(scene, spec, lights)
        taken = budgets.eevee_budget(0.0, [view.has_shape(o) for o in dimmed], [view.is_area(o) for o in dimmed])
        used = float(np.asarray(predict.joint([taken], len(dimmed)).cost)[0, :, rungs.OFF].sum()) if dimmed else 0.0
        dense = spec.multiple_albedo is not None
        sampler = float(np.max(np.asarray(predict.joint([budgets.eevee_budget(spec.anisotropy, dense=dense)], 1).cost)
                               [:, 0, 0]))   # the sampled lights' group: one fully modelled point light
        block = budgets.eevee_budget(spec.anisotropy, [view.has_shape(o) for o in lights],
                                     [view.is_area(o) for o in lights], dense,
                                     allowance=budgets.EEVEE_USER_ALLOWANCE + used + sampler)
        block = predict.joint([block], len(lights))
        block.cost[:, :, rungs.OFF] = 0.0   # (a light off in the preview is not in it)
        block = block._replace(limit=np.maximum(block.limit, 0.0))   # (no room: no light in the preview)
        return predict.joint([preview, block], len(lights))

    def signature(self, scene, spec, shader_lights):
        c = scene.cycles
        return (f"compositor:{scene.render.engine}:{c.pixel_filter_type}:{comp_fog.horizontal_fit(scene)}:"
                f"{scene.camera.data.sensor_fit}:{scene.camera.data.type}|shafts:{spec.shafts}{_moving(scene) if spec.shafts else ''}"
                f"|glow:{_glow_key(scene)}"
                "|dimming:" + ",".join(o.name_full for o in shader_lights))

    def windows(self, scene, lights, partial):
        return view.windows(scene, lights, [scene.frame_current] if partial else None, _halos(scene),
                            fogged=has_fog_surface, opaque=lets_nothing_through)

    def is_built(self):
        return bpy.data.node_groups.get(comp_fog.FOG_GROUP) is not None

    def build(self, scene, spec, plan, images):
        pano = comp_fog.panoramic(scene)
        aovs = functools.partial(comp_fog.add_surface_aovs, engine=scene.render.engine, panoramic=pano)
        day, dims = sunsky.builder(scene, spec), sunsky.dims_surfaces(scene, plan.in_groups)
        table, table_images = sunsky.fog_light_table(scene, spec)   # (None: no daylight to glow)
        images = dict(images, **table_images)
        daylit = table is not None
        shafted = shafted_lights(scene, spec, plan.in_groups) if spec.shafts else []
        # (a handler's rebuild does not step through the frames: the save completes the atlases)
        maps, shadow_images = shadow_maps.ensure(scene, shafted, lazy=plan.this_frame,
                                                 sizing=(spec.beta_per_unit, shafts.map_budget(spec.quality)))
        sun_shadow, sun_images = sunsky.sun_shadow(scene, spec, lazy=plan.this_frame) if daylit else (None, {})
        shadow_maps.remove_unused(set(shadow_images) | set(sun_images))
        images = dict(images, **shadow_images, **sun_images)
        # the glowing meshes measured and cut into points once: the preview, the far glows and the fog light
        points = emitter_points(glowing_points(scene))
        preview, sampled_images = _preview(scene, spec, plan, maps, points, table, dims)
        images = dict(images, **sampled_images)
        tails = _tails(scene, spec, plan, maps)
        # a sharp mirror's reflected fog by its tails where they hold every light (else the pixels' glossy lobe)
        mirrors = bool(tails) and len(tails.lights) == len(plan.in_groups)
        surface_group.build_surface(plan.shader_lights, plan.shader_models, images, spec.passes, extra=aovs,
                                    tails=tails, day=day, day_dims=dims and not daylit, day_exact=not daylit,
                                    preview=preview, mirrors=mirrors)
        images = comp_fog.build_fog_group(scene, plan.in_groups, plan.grouped_models, images,
                                          view.full_windows(plan.in_groups) if plan.partial else plan.windows,
                                          plan.partial, (maps, shafts.samples_for(spec.quality, len(maps)),
                                                         spec.anisotropy),
                                          emitters=((spec.anisotropy, spec.multiple_albedo
                                                     if (plan.choice.get("dense") or {}).get("emitters", True)
                                                     else None)
                                                    if glowing_objects(scene) and not pano else None),
                                          day=(comp_daylight.Day(day, table, dims, sun_shadow,
                                                                 shafts.samples_for(spec.quality).view_nodes)
                                               if daylit else None),
                                          layer=spec.layer_per_unit() if spec.layered else None,
                                          with_passes=spec.passes, mirrors=mirrors,
                                          emitter_points=points if not pano else None)
        world_group.build_world([], [], scene.camera, images, spec.passes, day=day, day_dims=not daylit,
                                preview=preview, extra=comp_fog.add_world_aovs if pano else None)
        return images

    def update(self, scene, spec, plan):
        if plan.windows is not None:
            comp_fog.set_windows(plan.in_groups, plan.windows, grow=plan.partial)
        points = emitter_points(glowing_points(scene))
        comp_fog.set_emitter_points(points)   # (moved, resized, brightened)
        sampled, points = sampled_lights(scene, plan), sampled_points(scene, plan, points)
        if sampled or points:   # the sampled lights as they are now (moved, dimmed, recoloured)
            preview_sampled.write_table(scene, sampled, spec.beta_per_unit, points)

    def passes(self, scene, spec):   # (the fog passes: the materials' transmittance, the fog group's light)
        return (comp_fog.aovs(scene.render.engine, comp_fog.panoramic(scene))
                + (((passes.TRANSMITTANCE, "VALUE"),) if spec.passes else ()))

    def notes(self, scene, spec, plan):
        layers = unfogged_layers(scene)
        layer_note = [(scene.name, f"{len(layers) + 1} view layers render, and without a compositor of yours the "
                                   f"Compositor method's fog is in the composite (the first layer) only: "
                                   f"the own passes of {caveats.listed(layers)} hold no fog light (use the Node "
                                   "Groups method, or a compositor of yours with a Render Layers node per layer)")
                      ] if layers else []
        n, kept = len(plan.in_groups), len(plan.shader_lights)
        layer_note += self.preview_notes(scene, spec, plan)
        glowing = glowing_objects(scene)
        if glowing and comp_fog.panoramic(scene):
            layer_note.append((scene.camera.name, f"is panoramic: the glowing objects ({caveats.listed([o.name for o in glowing])}) "
                                                  "get no glow (the compositor blurs a perspective picture)"))
        if spec.passes:
            name = compositor.passes_file_name("<view layer>").replace("####", "<frame>")
            layer_note.append((scene.name, f"the fog passes are the compositor's: each render writes them beside its "
                                           f"output, as {name}.exr (multilayer EXR: Fog Light, Fog Transmittance); "
                                           "the view layers' own passes hold no fog light"))
        if scene.render.engine == budgets.EEVEE_ENGINE and kept < n:
            return layer_note + [(scene.render.engine, f"{n - kept} of {n} lights are not in the materials' shared "
                                  "dimming of direct light (EEVEE's uniform block): their direct light is dimmed as "
                                  "the nearer lights' is")]
        return layer_note

    def preview_notes(self, scene, spec, plan):
        """What the viewport's preview shows of the compositor's fog (``nodes/preview.py``)."""
        if plan.preview is None:
            return self.glowing_notes(scene, plan)
        eevee = scene.render.engine == budgets.EEVEE_ENGINE
        notes = [("Viewport", "the viewport compositor is on in a 3D view: it adds the compositor's fog over the "
                              "viewport's preview of it (Shading popover > Compositor: Disabled)")
                 ] if eevee and _viewport_compositor_on() else []
        shown, sampled = plan.preview[0], sampled_lights(scene, plan)
        left = [o.name for o in plan.in_groups if o not in shown and o not in sampled]
        if sampled:
            notes.append(("Viewport", f"the viewport's preview samples {len(sampled)} of the {len(plan.in_groups)} "
                                      "lights, one a sample: their fog light is noisy at first and settles as the "
                                      "viewport's samples add up"))
        shafted = shafted_lights(scene, spec, shown) if spec.shafts and shown else []
        unshafted = shafted if eevee else (shadow_maps.moving_lights(scene, shafted)
                                           if shadow_maps.frames_of(scene)[2] > 1 else [])
        if unshafted:
            why = "in EEVEE" if eevee else "while their shadows move over the animation"
            names = caveats.listed([o.name for o in unshafted])
            notes.append(("Viewport", f"the viewport's preview shows no light shafts of {names} {why} (final "
                                      "renders, F12, have them)"))
        sampled_shafts = shafted_lights(scene, spec, sampled) if spec.shafts and sampled else []
        if sampled_shafts:
            notes.append(("Viewport", f"the viewport's preview shows no light shafts of the lights it samples "
                                      f"({caveats.listed([o.name for o in sampled_shafts])}): final renders, F12, "
                                      "have them"))
        notes += self.glowing_notes(scene, plan)
        if spec.layered and shown:
            notes.append(("Viewport", "the viewport's preview takes the lamps' glows through the fog layer's density "
                                      "everywhere, also above its top (final renders, F12, end them there)"))
        if not left:
            return notes
        errors = (plan.preview[2] or {}).get("lights", {})   # each light's own share of a pixel's fog (``predict``)
        share = sum(errors.get(name, [0, 0.0])[1] for name in left)
        return notes + [("Viewport", f"the viewport's preview of the fog leaves out {len(left)} of the "
                                     f"{len(plan.in_groups)} lights (spot and area lights beyond its "
                                     f"{len(shown)}): {caveats.listed(left)}, up to {share:.0%} of a pixel's fog "
                                     "(predicted; final renders, F12, have every light)")]

    def glowing_notes(self, scene, plan):
        """What the viewport's preview shows of the glowing objects' fog (``sampled_points``)."""
        glowing = glowing_objects(scene)
        if not glowing:
            return []
        shining = glowing_points(scene)
        as_points = set(shining[0]) if sampled_points(scene, plan, emitter_points(shining)) is not None else set()
        notes = []
        if as_points:
            notes.append(("Viewport", f"the viewport's preview shows the glows of the glowing objects "
                                      f"({caveats.listed([o.name for o in glowing if o in as_points])}) from points "
                                      "along each, sampled with the lights, without their shadows (final renders, "
                                      "F12, glow their shapes)"))
        missing = [o.name for o in glowing if o not in as_points]
        if missing:
            notes.append(("Viewport", f"the viewport's preview shows no glow of the glowing objects "
                                      f"({caveats.listed(missing)}): final renders, F12, have it"))
        return notes

    def frame_change(self, scene, spec, lights):
        if comp_fog.FOG_GROUP in bpy.data.node_groups:
            comp_fog.set_windows(lights, view.windows(scene, lights, [scene.frame_current], _halos(scene),
                                                      fogged=has_fog_surface, opaque=lets_nothing_through),
                                 grow=True)
            follow_shadows(scene, spec, lights)
            sunsky.follow_sun(scene, spec)
            comp_fog.set_emitter_points(emitter_points(glowing_points(scene)))

    def follow(self, scene, rebuild):
        return compositor.follow(scene, rebuild, bpy.data.node_groups.get(comp_fog.FOG_GROUP))

    def teardown(self, scene):
        old = bpy.data.node_groups.get(comp_fog.FOG_GROUP)
        if old is not None and old.users == 0:
            bpy.data.node_groups.remove(old)
        shadow_maps.remove_unused()


def _preview(scene, spec, plan, maps, points, day_table=None, day_dims=True):
    """(``preview.Shown`` of the viewport's preview (``plan.preview``) or None, the images it reads): in Cycles its
    shafted lights' still maps give it their shafts (``preview_shafts.py``; an animation's atlas does not, nor
    EEVEE, whose uniform block the shares' constants would fill); the other point lights are sampled one a sample,
    with the glowing objects' points (``points``: ``emitter_points``') (``preview_sampled.py``); a fog layer's sun
    and sky (``day_table``: the fog light's TableSpec, or None) as the
    node groups give them, their dimming of the surfaces' direct light where ``day_dims``."""
    lights, models = plan.preview[:2] if plan.preview else ([], [])
    sampled, points = sampled_lights(scene, plan), sampled_points(scene, plan, points)
    if not lights and not sampled and points is None and day_table is None:
        preview_sampled.write_table(scene, [], spec.beta_per_unit)
        return None, {}
    shadows = _still_maps(lights, maps) if scene.render.engine == "CYCLES" else {}
    table, img = preview_sampled.write_table(scene, sampled, spec.beta_per_unit, points)
    final = dict(zip(plan.in_groups, plan.grouped_models))
    dense = preview_sampled.dense_of(
        sampled, [final[o] for o in sampled], spec.anisotropy, spec.multiple_albedo,
        (plan.choice.get("dense") or {}).get("scales") or {},
        sampling.importance([o.matrix_world.translation for o in sampled], view.light_intensities(sampled),
                            scene.camera.matrix_world.translation, spec.beta_per_unit)) if sampled else None
    return (preview_.Shown(lights, models, shadows or None, spec.anisotropy, table, day_table, day_dims, dense,
                            scene.render.engine == "CYCLES"),
            {table.name: img} if table is not None else {})


TAIL_LIGHTS = 8   # the lights whose glows the materials shade past glass and mirrors (the most important first)


def _tails(scene, spec, plan, maps):
    """``glass_tails.Tails`` of the fog past glass and sharp mirrors (``glass_tails.place_tails``, Cycles: the
    compositor sees only a pixel's first surface): the glows along the segments and the fog light the surfaces there
    reflect, of the TAIL_LIGHTS lights of most importance (``sampling.importance``) with the Node Groups method's full
    models, each in its shadows where it has a still map (``maps``: the shafts', ``glass_tails.build_tail_bundle``),
    one of them a sample (``sampling.mixed_chances``); False where the scene has no such path or in EEVEE."""
    if scene.render.engine != "CYCLES" or not plan.in_groups or not caveats.specular_paths(bpy.data.materials):
        return False
    weight = sampling.importance([o.matrix_world.translation for o in plan.in_groups],
                                 view.light_intensities(plan.in_groups), scene.camera.matrix_world.translation,
                                 spec.beta_per_unit)
    order = np.argsort(-weight, kind="stable")[:TAIL_LIGHTS]
    kept = [plan.in_groups[i] for i in order]
    shadows = _still_maps(kept, maps)
    return glass_tails.Tails(kept, [rungs.choose("nodes", 0, spec.anisotropy, view.light_kind(o)) for o in kept],
                             shadows or None, spec.anisotropy, sampling.mixed_chances(weight[order]), cycles=True)


def _still_maps(lights, maps):
    """{name: ShadowMap} of the ``lights`` whose shafts' map (``maps``) is a still one (an animation's atlas is read
    by frame, which the shaders' shares do not)."""
    return {o.name: maps[o.name] for o in lights if o.name in maps and maps[o.name].atlas is None}


def samples_all(scene, lights):
    """True if the viewport's preview samples all the point lights of ``lights``, one a sample (Cycles, with
    SAMPLE_ALL_FROM of them or more), rather than holding some one by one."""
    return scene.render.engine == "CYCLES" and len(preview_sampled.sampled(lights)) >= SAMPLE_ALL_FROM


def sampled_lights(scene, plan):
    """The point lights of the fog the viewport's preview does not hold one by one: it samples them
    (``preview_sampled.py``); none where it holds no light and does not sample them all (EEVEE's uniform block
    without room for the preview)."""
    if not plan.preview or not (plan.preview[0] or samples_all(scene, plan.in_groups)):
        return []
    shown = set(plan.preview[0])
    return preview_sampled.sampled([o for o in plan.in_groups if o not in shown])


def sampled_points(scene, plan, points):
    """The glowing objects' ``points`` (``emitter_points``': (centres (K, 3) m, intensities (K, 3) W/sr), each object
    cut along its length as the final render takes it) where the viewport's preview samples them beside its lights
    (``preview_sampled.write_table``), or None: without a glowing object whose radiance can be read, or in EEVEE
    where the preview holds no light (its uniform block without room).  In Cycles the glowing objects have a
    preview of their own in a scene without lamps."""
    if points is None:
        return None
    if scene.render.engine != "CYCLES" and not (plan.preview and plan.preview[0]):
        return None
    return points


def _viewport_compositor_on():
    """True if a 3D view of the open file runs the viewport compositor (EEVEE's: it would add the compositor's fog
    over the materials' preview of it)."""
    return any(space.type == "VIEW_3D" and space.shading.use_compositor != "DISABLED"
               for screen in bpy.data.screens for area in screen.areas for space in area.spaces)


def dimming_lights(scene, spec, lights):
    """The Compositor method's materials' lights: ([], []) in Cycles, whose lights dim their own direct light
    (``light.py``); in EEVEE, which has no light node trees, (lights, models) of the lights whose direct
    light the materials dim by the shared weights of ``shading.surface_fog`` (rungs step "off": no fog light,
    which the compositor adds), as many as EEVEE's uniform block holds (``budgets.eevee_budget``), the
    brightest at the camera first (radiant intensity over squared distance)."""
    if scene.render.engine != budgets.EEVEE_ENGINE or not lights:
        return [], []
    spots = [view.has_shape(o) for o in lights]
    budget = budgets.eevee_budget(0.0, spots, [view.is_area(o) for o in lights])   # step "off" has no phase
    # weight: its cost does not depend on g
    eye = scene.camera.matrix_world.translation
    intensity = view.light_intensities(lights).sum(axis=1)
    order = sorted(range(len(lights)), key=lambda i: -intensity[i] / max(
        (lights[i].matrix_world.translation - eye).length_squared, 1e-12))
    steps = [rungs.LEFT_OUT] * len(lights)
    for i in order:
        steps[i] = rungs.OFF
        if not budget.fits(steps):
            steps[i] = rungs.LEFT_OUT
            break
    kept = [i for i in range(len(lights)) if steps[i] == rungs.OFF]
    return [lights[i] for i in kept], [rungs.choose("compositor", rungs.OFF, spec.anisotropy,
                                                          view.light_kind(lights[i])) for i in kept]


def glowing_objects(scene):
    """The objects the camera sees whose materials emit (``graph.emits``): they glow in the fog
    (``comp_emitters.glows``)."""
    emitting = {}
    found = []
    for obj in scene.objects:
        if obj.hide_render or not getattr(obj, "visible_camera", True):
            continue
        for slot in getattr(obj, "material_slots", ()):
            mat = slot.material
            if mat is not None and emitting.setdefault(mat.name, graph.emits(mat)):
                found.append(obj)
                break
    return found


def glowing_points(scene):
    """(objects, centres (N, 3) m, intensities (N, 3) W/sr) of the glowing objects (``glowing_objects``) taken each
    as a point source at its bounds' centre of intensity L A / 4: its emission's radiance L (``graph.emitted_radiance``,
    its brightest material) times its mean projected area, a quarter of its surface's for a convex body (Cauchy),
    both sides of an open mesh's faces counted (``emitting_sides``: a flat sign's mean is L A / 2).
    Those whose radiance cannot be read (a procedural texture, a driven strength) or that are not meshes are left
    out.  The predictor's estimate of their fog (``ops/left_out.emitters_fog``) and the viewport preview's glow of
    them (``preview_sampled.write_table``)."""
    shining, centres, intensities = [], [], []
    for obj, radiance in _shining(scene):
        m = obj.matrix_world
        area = world_area(obj.data, m) * emitting_sides(obj.data)
        shining.append(obj)
        centres.append(object_centre(obj))
        intensities.append(np.max(radiance, axis=0) * area / 4.0)
    return shining, np.reshape(centres, (-1, 3)), np.reshape(intensities, (-1, 3))


def emitting_sides(mesh):
    """How many sides of ``mesh``'s faces send their light out: 1 for a closed mesh (every edge between two faces:
    the inner sides light its inside), 2 for an open one (a sign, a plane: Cycles' and EEVEE's emission leaves both
    sides of a face).  A mesh partly open counts as open."""
    used = np.empty(len(mesh.loops), np.int32)
    mesh.loops.foreach_get("edge_index", used)
    counts = np.bincount(used, minlength=len(mesh.edges))
    return 2 if len(counts) and bool((counts == 1).any()) else 1


def world_area(mesh, matrix):
    """The area of ``mesh``'s faces in world space, m^2, under ``matrix`` (any scale, also non-uniform: a neon tube
    is often a cube scaled along one axis): its triangles' (``loop_triangles``) corners moved to world space, read
    in one call each (``foreach_get``), not face by face (a viewport update measures the glowing meshes each
    time)."""
    tris = np.empty(3 * len(mesh.loop_triangles), np.int32)
    mesh.loop_triangles.foreach_get("vertices", tris)
    co = np.empty(3 * len(mesh.vertices), np.float32)
    mesh.vertices.foreach_get("co", co)
    corners = (co.reshape(-1, 3).astype(float) @ np.asarray(matrix.to_3x3(), float).T)[tris.reshape(-1, 3)]
    return float(0.5 * np.linalg.norm(np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]),
                                      axis=1).sum())


EMITTER_PIECES = 4   # the most points a long glowing object is taken as (``emitter_points``)


def emitter_points(shining):
    """(points (N, 3) m, intensities (N, 3) W/sr) whose fog light the compositor's surfaces reflect
    (``comp_fog.emitter_fog_light``), or None without a glowing object: each of ``shining`` (``glowing_points``')
    cut into ``_pieces`` equal pieces along its bounds' longest edge (a neon tube, a strip of windows), a
    point at each piece's centre with its share of the object's intensity."""
    objects, centres, intensities = shining
    if not objects:
        return None
    points, shares = [], []
    for obj, centre, intensity in zip(objects, centres, intensities):
        axis, n = _pieces(obj)
        for i in range(n):
            points.append(centre + axis * ((i + 0.5) / n - 0.5))
            shares.append(intensity / n)
    return np.reshape(points, (-1, 3)), np.reshape(shares, (-1, 3))


def object_centre(obj):
    """(3,) m: the world centre of ``obj``'s bounds (``footprint.box_points``), where a glowing object stands as a
    point source."""
    return footprint.box_points(obj.bound_box, obj.matrix_world).mean(axis=0)


def _pieces(obj):
    """(the world vector of ``obj``'s bounds' longest edge, the pieces ``emitter_points`` cuts it into: that edge
    over the next, rounded, 1 to EMITTER_PIECES).  No mesh is measured: the build's signature asks at every
    update (``_glow_key``)."""
    corners = footprint.box_points(obj.bound_box, obj.matrix_world)
    edges = sorted((corners[j] - corners[0] for j in (4, 3, 1)), key=lambda e: -float(e @ e))   # (Blender's corners)
    ratio = float(np.linalg.norm(edges[0])) / max(float(np.linalg.norm(edges[1])), 1e-9)
    return edges[0], int(min(max(round(ratio), 1), EMITTER_PIECES))


def _glow_key(scene):
    """The glowing objects as the build takes them: each one's name and pieces (``_pieces``), or whether any
    glows at all where no radiance can be read."""
    pieces = ",".join(f"{o.name_full}x{_pieces(o)[1]}" for o, _ in _shining(scene))
    return pieces or str(bool(glowing_objects(scene)))


def _shining(scene):
    """[(object, [RGB radiance of each of its emitting materials])] of the glowing mesh objects whose radiance can be
    read (``glowing_points``; no mesh is measured: the build's signature asks for them at every update)."""
    out = []
    for obj in glowing_objects(scene):
        radiance = [graph.emitted_radiance(slot.material) for slot in obj.material_slots]
        radiance = [r for r in radiance if r is not None and any(c > 0.0 for c in r)]
        if radiance and obj.type == "MESH":
            out.append((obj, radiance))
    return out


def shafted_lights(scene, spec, lights):
    """The ``lights`` whose shadows fall in fog the camera may see (``caveats.shadowing_lights``: an object
    casting shadows within the glow's reach), the Quality's most important of them (``shadow_maps.shafted_split``):
    only they get a shadow map and a shaft group (an area light a point light's map from its centre:
    ``area.shaft_falloff``)."""
    return shadow_maps.shafted_split(scene, lights, spec.beta_per_unit, shafts.shaft_lights(spec.quality))[0]


def _moving(scene):
    """What of the shafts' maps moves over the animation (the lights animated, the casters), as the signature says it:
    a light that starts or stops moving takes an atlas of its maps or a still map (``shadow_maps.ensure``), other
    nodes (``comp_shafts.atlas_tile``)."""
    if shadow_maps.frames_of(scene)[2] < 2:
        return ""
    casters = any(caveats.is_animated(o) for o in caveats.shadow_casters(scene))
    lights = sorted(o.name for o in scene.objects if o.type == "LIGHT" and caveats.is_animated(o))
    return f":moving {int(casters)} " + ",".join(lights) if casters or lights else ""


def follow_shadows(scene, spec, lights):
    """The frame changed: the shadow maps of the shafted lights follow the lights and objects that move.  A still
    map is baked again where a light's pose or the casters' geometry changed (``shadow_maps.ensure``; a spot whose
    map turned gets its shaft group again, its frame is built in, for ``spec``: None while the scene's settings
    can't be used, and the still maps stay as they were built); an animation's atlas has this frame's map baked
    again where it changed since (``shadow_maps.follow_frame``: the animation was edited)."""
    maps_now = [bpy.data.images.get(shadow_maps.IMAGE_PREFIX + o.name) for o in lights]
    shafted = [o for o, img in zip(lights, maps_now) if img is not None]
    if not shafted or not any(caveats.is_animated(o) for o in [*shafted, *caveats.shadow_casters(scene)]):
        return
    atlases = [o for o in shafted if shadow_maps.ATLAS in bpy.data.images[shadow_maps.IMAGE_PREFIX + o.name]]
    shadow_maps.follow_frame(scene, atlases)
    still = [o for o in shafted if o not in atlases]
    if not still or spec is None:
        return
    before = {o.name: bpy.data.images[shadow_maps.IMAGE_PREFIX + o.name].get(shadow_maps.KEY) for o in still}
    maps, images = shadow_maps.ensure(scene, still)
    for light in still:
        shadow = maps[light.name]
        if shadow.spot is not None and images[shadow.spec.name].get(shadow_maps.KEY) != before[light.name]:
            comp_shafts.build_shaft_group(light, shadow, images, shafts.samples_for(spec.quality, len(shafted)),
                                          spec.anisotropy)


def complete_shadows(scene, spec):
    """Before the file is saved (``handlers.on_save_pre``): the atlases of the shafted lights' maps that a frame
    change found out of date, or that were laid out for another frame range, are baked over the scene's range again
    and packed (``shadow_maps.complete``), so a farm without the add-on renders each frame's shafts; a moving spot
    whose maps' frame changed gets its shaft group again, for ``spec`` (None while the scene's settings can't be
    used: its shaft groups stay as they were built)."""
    if bpy.data.node_groups.get(comp_fog.FOG_GROUP) is None:
        return
    lights = [o for o in scene.objects if o.type == "LIGHT"
              and bpy.data.images.get(shadow_maps.IMAGE_PREFIX + o.name) is not None]
    spots = {o.name: bpy.data.images[shadow_maps.IMAGE_PREFIX + o.name].get(shadow_maps.LAYOUT) for o in lights}
    maps, images = shadow_maps.complete(scene, lights)
    if not maps or spec is None:
        return
    for light in lights:
        shadow = maps.get(light.name)
        if shadow is not None and shadow.cone and images[shadow.spec.name].get(shadow_maps.LAYOUT) != spots[light.name]:
            comp_shafts.build_shaft_group(light, shadow, images, shafts.samples_for(spec.quality, len(lights)),
                                          spec.anisotropy)


def unfogged_layers(scene):
    """The view layers that render but that the compositor's fog would not reach: with no compositor of the
    user's, the fog's own (``nodes/compositor.py``) makes the composite of the first layer that renders, as Blender
    does without one; the others' own passes (a multilayer EXR's, the Image Editor's) then hold no fog light.  A
    user's compositor gets the fog after each of its Render Layers nodes.  [] otherwise."""
    tree = scene.compositing_node_group
    if tree is not None and tree.get(owned.TAG) is None and tree.name != compositor.GROUP:
        return []
    used = [vl.name for vl in scene.view_layers if vl.use]
    return used[1:]


def has_fog_surface(material):
    """True if the fog's Surface node is in ``material`` (it writes the pixel's coverage: ``view.occluders``)."""
    return material.node_tree is not None and owned.find(material.node_tree, "Surface") is not None


def lets_nothing_through(material):
    """True if nothing in fogged ``material`` lets light through (no Transparent BSDF, Holdout or Alpha, no backface
    culling): its flat faces end every camera ray that meets them (``view.occluders``)."""
    return not getattr(material, "use_backface_culling", False) and all(
        not k.passes and not k.hidden for k in graph.plan(material.node_tree)[2].values())


def _halos(scene):
    """True if the spots' glows have their multiply scattered halo (the scene's Dense Fog is on)."""
    settings = getattr(scene, "analytic_fog", None)
    return bool(settings is not None and settings.use_multiple_scattering)
