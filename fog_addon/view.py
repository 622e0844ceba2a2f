"""What the camera sees, sampled by ray casts into the scene: the error predictor's input (``predict.py``).

Rays through the pixel centres of the camera's frame (``sample_grid``) are cast into one
``mathutils.bvhtree.BVHTree`` of the view's mesh triangles in world space (``_SceneMesh``, no
render); each hit gives the
distance, the normal (turned to face the camera, as a shader sees it) and
the material, read as ``surface.principled_to_phong`` reads a Principled
BSDF's own values.  A material without a Principled BSDF, or whose inputs
are linked (textures), counts twice, as a pure diffuse and as a pure mirror
(rho_s = 1 at the sharpest tabulated lobe): the error of a mix of the two
lies between theirs.  For an animation every ``frames`` frame is sampled,
so the choice holds for the whole range.
"""
import math

import bpy
import numpy as np
from mathutils.bvhtree import BVHTree

from . import caveats
from .precompute.core import tables
from .precompute.model import footprint, predict
from .precompute.physics.area import area
from .precompute.physics.point import surface

JUDGED_ENTRIES = 2_000_000   # samples x lights the Quality's choice judges at most (``judged_grid``)
MIN_JUDGED = 48 * 27           # samples it judges at least
MAX_SAMPLES = 160 * 90          # rays per frame at most: one per pixel centre up to this, else a coarser grid
MAX_FRAMES = 8                  # an animation: at most this many frames, evenly spread over the range
GLASS_HOPS = 4                  # glass surfaces a sample ray passes straight through at most (two panes' faces)
GLASS_STEP = 1e-4               # units past a glass hit the ray goes on from (off the face it hit)
# (rho_d, rho_s, level) stand-ins for a material whose Principled values can't be read: each of the two
# counts (a mix of them errs between them); the mirror has the sharpest tabulated lobe (n = 1024).
LAMBERT = ((1.0, 1.0, 1.0), (0.0, 0.0, 0.0), 0.0)
MIRROR = ((0.0, 0.0, 0.0), (1.0, 1.0, 1.0), len(tables.PHONG_EXPONENTS) - 1.0)


_sampling = []   # non-empty while the view's frames are being sampled (``sampling_frames``)


def sampling_frames():
    """True while this module steps through frames (the frame-change handler leaves those alone)."""
    return bool(_sampling)


def _frame_set(scene, frame, subframe=0.0):
    _sampling.append(True)
    try:
        scene.frame_set(frame, subframe=subframe)
    finally:
        _sampling.pop()


def at_frames(scene, frames):
    """Yield (frame, evaluated depsgraph) at each of ``frames``, the scene's frame restored afterwards."""
    current = scene.frame_current, scene.frame_subframe
    try:
        for f in frames:
            if f != scene.frame_current:
                _frame_set(scene, f)
            yield f, bpy.context.evaluated_depsgraph_get()
    finally:
        if (scene.frame_current, scene.frame_subframe) != current:
            _frame_set(scene, current[0], current[1])


def animated(scene):
    """True if an object or its data is animated (an action or drivers): the view may change with the frame."""
    for obj in scene.objects:
        for idb in (obj, obj.data):
            ad = getattr(idb, "animation_data", None)
            if ad is not None and (ad.action is not None or len(ad.drivers)):
                return True
    return False


def sample_frames(scene):
    """The frames to sample: the current one for a still, up to MAX_FRAMES spread over an animation."""
    first, last = scene.frame_start, scene.frame_end
    if last <= first or not animated(scene):
        return [scene.frame_current]
    count = min(MAX_FRAMES, last - first + 1)
    return sorted({int(round(first + k * (last - first) / max(count - 1, 1))) for k in range(count)})


def _principled(material):
    """(base colour, metallic, roughness, specular IOR level, IOR) of a material's Principled BSDF (the first that
    Cycles' material output renders: ``caveats.surface_nodes``) from its own values, or None."""
    if material is None or not material.use_nodes or material.node_tree is None:
        return None
    for node in caveats.surface_nodes(material.node_tree):
        if node.bl_idname == "ShaderNodeBsdfPrincipled":
            names = ("Base Color", "Metallic", "Roughness", "Specular IOR Level")
            if any(node.inputs[n].is_linked for n in names):
                return None
            return (tuple(node.inputs["Base Color"].default_value)[:3], node.inputs["Metallic"].default_value,
                    node.inputs["Roughness"].default_value, node.inputs["Specular IOR Level"].default_value,
                    node.inputs["IOR"].default_value)
    return None


def _albedos(rows):
    """[(rho_d, rho_s, level)] of the hits ``rows`` (direction, distance, normal, Principled values or a
    stand-in), the Principled ones by ``surface.principled_albedos`` at each hit's view cosine, at once."""
    out = [brdf for _, _, _, brdf in rows]
    live = [k for k, (_, _, _, brdf) in enumerate(rows) if len(brdf) == 5]
    if not live:
        return out
    cols = list(zip(*(rows[k][3] for k in live)))
    cos_view = [-float(np.dot(rows[k][0], rows[k][2])) for k in live]
    levels = {}
    for ior in sorted(set(cols[4])):   # the IOR is a constant of the formula: one call per IOR in the view
        sel = [i for i, v in enumerate(cols[4]) if v == ior]
        rho_d, rho_s, _ = surface.principled_albedos(np.array([cols[0][i] for i in sel]),
                                                     np.array([cols[1][i] for i in sel]),
                                                     np.array([cols[2][i] for i in sel]),
                                                     np.array([cols[3][i] for i in sel]), float(ior),
                                                     np.array([cos_view[i] for i in sel]))
        for j, i in enumerate(sel):
            r = cols[2][i]
            if r not in levels:
                levels[r] = tables.PHONG_LEVELS_PER_OCTAVE * math.log2(surface.phong_exponent_from_roughness(r))
            out[live[i]] = (tuple(rho_d[j]), tuple(rho_s[j]), levels[r])
    return out


class _MeshInfo:
    """An evaluated mesh instance's materials and smooth normals; ``loops``: its loop triangles' corners."""

    def __init__(self, ev, matrix, loops):
        self.ev = ev
        self.mesh = ev.data
        self.loops = loops
        self.inv = np.linalg.inv(matrix)

    def material(self, index):
        try:
            return self.ev.material_slots[self.mesh.polygons[index].material_index].material
        except (AttributeError, IndexError, TypeError):
            return None

    def normal(self, tri, index, location, face_normal):
        """The shading normal at a hit on loop triangle ``tri`` of polygon ``index``: the face's, or on a
        smooth face the triangle's corner normals interpolated at the hit."""
        if not self.mesh.polygons[index].use_smooth:
            return face_normal
        corners = self.loops[tri]
        a, b, c = (np.array(self.mesh.vertices[self.mesh.loops[k].vertex_index].co) for k in corners)
        p = (self.inv @ np.append(location, 1.0))[:3]
        try:
            u, v = np.linalg.lstsq(np.column_stack([b - a, c - a]), p - a, rcond=None)[0]
        except np.linalg.LinAlgError:
            return face_normal
        n_local = sum(w * np.array(self.mesh.corner_normals[k].vector) for w, k in zip((1.0 - u - v, u, v), corners))
        n = self.inv[:3, :3].T @ n_local
        length = np.linalg.norm(n)
        return n / length if length > 0.0 else face_normal


def frame_rays(scene, camera, grid):
    """(origin, unit directions (P, 3)) through the centres of the cells of a ``grid`` (x, y) over the camera's frame,
    row by row from the bottom-left cell (as window coordinates run)."""
    # top-right, bottom-right, bottom-left, top-left
    frame = [np.array(v) for v in camera.data.view_frame(scene=scene)]
    nx, ny = grid
    u = (np.arange(nx) + 0.5) / nx
    v = (np.arange(ny) + 0.5) / ny
    uu, vv = np.meshgrid(u, v)
    local = (frame[2][None, None] + uu[..., None] * (frame[1] - frame[2])[None, None]
             + vv[..., None] * (frame[3] - frame[2])[None, None]).reshape(-1, 3)
    mw = np.array(camera.matrix_world)
    d = local @ mw[:3, :3].T
    d /= np.linalg.norm(d, axis=1)[:, None]
    return mw[:3, 3].copy(), d


class _SceneMesh:
    """Every mesh triangle of the evaluated view (instances included) in world space, in one BVH tree.

    ``Scene.ray_cast`` tests every object's bounds on every ray: 0.47 ms a ray with 1 000 objects,
    7 s of the 8 s the 1 000-material scene spent choosing the lights' models.  One tree over
    all triangles answers a ray in microseconds.
    """

    def __init__(self, depsgraph):
        verts, tris, self.owners, self.first_tri, self.polygon, n_verts, n_tris = [], [], [], [], [], 0, 0
        for inst in depsgraph.object_instances:
            ev = inst.object
            mesh = getattr(ev, "data", None)
            if ev.type != "MESH" or not isinstance(mesh, bpy.types.Mesh) or not len(mesh.polygons):
                continue
            matrix = np.array(inst.matrix_world)
            mesh.calc_loop_triangles()
            co = np.empty(3 * len(mesh.vertices))
            mesh.vertices.foreach_get("co", co)
            co = co.reshape(-1, 3) @ matrix[:3, :3].T + matrix[:3, 3]
            lt = np.empty(3 * len(mesh.loop_triangles), dtype=np.int64)
            mesh.loop_triangles.foreach_get("vertices", lt)
            poly = np.empty(len(mesh.loop_triangles), dtype=np.int64)
            mesh.loop_triangles.foreach_get("polygon_index", poly)
            loops = np.empty(3 * len(poly), dtype=np.int64)
            mesh.loop_triangles.foreach_get("loops", loops)
            self.first_tri.append(n_tris)
            n_tris += len(poly)
            self.owners.append(_MeshInfo(ev, matrix, loops.reshape(-1, 3)))
            self.polygon.append(poly)
            verts.append(co)
            tris.append(lt.reshape(-1, 3) + n_verts)
            n_verts += len(co)
        self.tree = (BVHTree.FromPolygons(np.concatenate(verts).tolist(), np.concatenate(tris).tolist(),
                                          all_triangles=True) if verts else None)

    def ray_cast(self, origin, direction):
        """(location, face normal, owner _MeshInfo, its loop triangle, polygon index) of the first hit, or None."""
        if self.tree is None:
            return None
        loc, normal, index, _ = self.tree.ray_cast(origin, direction)
        if loc is None:
            return None
        k = int(np.searchsorted(self.first_tri, index, side="right")) - 1
        tri = index - self.first_tri[k]
        return np.array(loc), np.array(normal), self.owners[k], tri, int(self.polygon[k][tri])


def _clear_glass(material, cache):
    """True for a material the camera sees through as glass whose far side the fog is shaded on
    (``caveats.served_glass``: a Glass or Refraction BSDF, a Principled BSDF that lets light through, at any
    roughness, on its own or mixed) that Cycles' material output renders (``caveats.surface_nodes``).  A mix
    counts as all glass: the fog past it is counted whole, the larger of the two."""
    if material not in cache:
        tree = material.node_tree if material is not None and material.use_nodes else None
        cache[material] = tree is not None and any(not n.mute and caveats.served_glass(n)
                                                   for n in caveats.surface_nodes(tree))
    return cache[material]


def _first_opaque(world, origin, d, past_glass, glass):
    """``world.ray_cast`` of the ray, gone straight through up to GLASS_HOPS glass surfaces when ``past_glass``
    (what the methods that shade the fog past glass draw there: the segments behind it, straight through a pane,
    ``nodes/glass_tails.py``): the fog of the whole ray to the first opaque surface, lit by that surface's
    fog light."""
    hit = world.ray_cast(origin, d)
    for _ in range(GLASS_HOPS if past_glass else 0):
        if hit is None or not _clear_glass(hit[2].material(hit[4]), glass):
            break
        hit = world.ray_cast(hit[0] + d * GLASS_STEP, d)
    return hit


def _sample_frame(scene, depsgraph, lights, grid, past_glass=False):
    origin, dirs = frame_rays(scene, scene.camera, grid)
    rows = []
    cache, glass = {}, {}
    world = _SceneMesh(depsgraph)
    for d in dirs:
        hit = _first_opaque(world, origin, d, past_glass, glass)
        if hit is None:
            rows.append((d, math.inf, (0.0, 0.0, 1.0), LAMBERT))
            continue
        loc, normal, info, tri, index = hit
        n = info.normal(tri, index, loc, normal)
        if n @ d > 0.0:
            n = -n
        mat = info.material(index)
        if mat not in cache:
            cache[mat] = _principled(mat)
        known = cache[mat]
        dist = float(np.linalg.norm(loc - origin))
        for brdf in ([known] if known is not None else [LAMBERT, MIRROR]):
            rows.append((d, dist, n, brdf))
    rows = [(d, dist, n, brdf) for (d, dist, n, _), brdf in zip(rows, _albedos(rows))]
    light_pos = np.array([np.array(o.matrix_world.translation) for o in lights]).reshape(-1, 3)
    inverse = np.array([np.linalg.inv(np.array(o.matrix_world.to_3x3())) if has_shape(o) else np.eye(3)
                        for o in lights]).reshape(-1, 3, 3)
    return origin, rows, light_pos, inverse


def scene_size(scene):
    """Largest distance (m in scene units) from the camera to an object origin: the depth fog must cross."""
    cam = scene.camera
    if cam is None:
        return 0.0
    c = cam.matrix_world.translation
    return max(((o.matrix_world.translation - c).length for o in scene.objects if o is not cam), default=0.0)


def render_size(scene):
    """(width, height) of the render in pixels (its resolution times its percentage)."""
    r = scene.render
    return (max(1, round(r.resolution_x * r.resolution_percentage / 100)),
            max(1, round(r.resolution_y * r.resolution_percentage / 100)))


def sample_grid(scene, max_samples=MAX_SAMPLES):
    """(nx, ny): the render's pixels if they are at most ``max_samples``, else the largest grid of the
    same aspect within it (then pixels between the rays are not judged: see the README's Quality)."""
    w, h = render_size(scene)
    if w * h <= max_samples:
        return w, h
    k = math.sqrt(max_samples / (w * h))
    return max(1, int(w * k)), max(1, int(h * k))


def judged_grid(scene, lights):
    """``sample_grid`` for the Quality's choice among ``lights`` (a count): at most JUDGED_ENTRIES samples x lights,
    never fewer than MIN_JUDGED samples (the predictor's arrays, and its time, stay bounded in a city of lamps)."""
    return sample_grid(scene, max(MIN_JUDGED, min(MAX_SAMPLES, JUDGED_ENTRIES // max(int(lights), 1))))


def view_samples(scene, lights, frames=None, grid=None, past_glass=False):
    """:class:`predict.ViewSamples` of the scene's camera view over ``frames`` (default
    :func:`sample_frames`); ``past_glass``: a ray goes straight through glass to the first opaque surface, as a
    method that shades the fog past glass draws it (``_first_opaque``).  Changes the current frame while sampling
    and restores it."""
    frames = sample_frames(scene) if frames is None else frames
    grid = sample_grid(scene) if grid is None else grid
    cams, dirs, dists, normals, rds, rss, levels, lps, invs, fr = [], [], [], [], [], [], [], [], [], []
    for f, depsgraph in at_frames(scene, frames):
        origin, rows, light_pos, inverse = _sample_frame(scene, depsgraph, lights, grid, past_glass)
        for d, dist, n, (rd, rs, lev) in rows:
            cams.append(origin)
            dirs.append(d)
            dists.append(dist)
            normals.append(n)
            rds.append(rd)
            rss.append(rs)
            levels.append(lev)
            lps.append(light_pos)
            invs.append(inverse)
            fr.append(f)
    n_lights = len(lights)
    kinds = [predict.Rectangle(*area_half_sizes(o)) if is_area(o) else predict.Cone(*spot_cone(o)) if is_spot(o)
             else None for o in lights]
    shapes = (predict.LightShapes(kinds, np.array(invs).reshape(-1, n_lights, 3, 3))
              if any(k is not None for k in kinds) else None)
    return predict.ViewSamples(np.array(cams).reshape(-1, 3), np.array(dirs).reshape(-1, 3), np.array(dists, float),
                               np.array(normals).reshape(-1, 3), np.array(rds).reshape(-1, 3),
                               np.array(rss).reshape(-1, 3), np.array(levels, float),
                               np.array(lps).reshape(len(dists), n_lights, 3), np.array(fr), shapes)


def multiple_parts(scene, spec, lights, samples=None, single=None, dense=None, grid=None):
    """``predict.multiple_parts`` of ``lights`` in the fog of ``spec`` (a ``FogSpec``) at the view's samples
    (``samples``, else sampled here on ``grid``, default ``sample_grid``'s): (P, N) each light's multiply scattered
    light as a share of a sample's fog.  ``single``, ``dense``: the samples' (glow, scatter) without and with it,
    if computed."""
    if samples is None:
        samples, single, dense = view_samples(scene, lights, grid=grid), None, None
    return predict.multiple_parts(samples, light_intensities(lights), spec.beta_per_unit, spec.anisotropy,
                                  spec.grey_albedo, single, dense)


def is_spot(light):
    """True for a spot light object (its fog follows the cone)."""
    return light.data.type == "SPOT"


def light_kind(light):
    """The light object's kind as the ladder models it (``rungs.LIGHT_KINDS``): "point", "spot" or "area"."""
    return {"SPOT": "spot", "AREA": "area"}.get(light.data.type, "point")


def spot_cone(light):
    """(cos(spot size / 2), blend) of a spot light object: its cone as the kernels take it."""
    return math.cos(light.data.spot_size / 2), light.data.spot_blend


def has_shape(light):
    """True for a spot or an area light: its fog takes the spot kernels' arguments (its matrix and two shape
    values: ``shading.shape_args``), and costs a spot's in the methods' budgets."""
    return is_spot(light) or is_area(light)


def is_area(light):
    """True for an area light object (its fog: ``precompute/physics/area/area.py``)."""
    return light.data.type == "AREA"


def light_intensities(lights):
    """(N, 3) RGB radiant intensity I0 = power * colour * ``area.intensity_per_watt`` of the lights, W/sr."""
    return np.array([[o.data.energy * c * area.intensity_per_watt(o.data.type) for c in o.data.color]
                     for o in lights]).reshape(-1, 3)


def area_half_sizes(light):
    """(a, b) half sizes (m) of an area light's rectangle (``area.half_sizes``), its object's scale included
    (the largest axis of it: ``ops/plan.fog_lights`` notes a non-uniform one)."""
    return area.half_sizes(light.data.shape, light.data.size, light.data.size_y, max(light.matrix_world.to_scale()))


MAX_WINDOW_FRAMES = 250   # an animation longer than this gets no windows (every frame is bounded)
GEOMETRY = {"MESH", "CURVE", "SURFACE", "FONT", "META", "CURVES", "POINTCLOUD", "VOLUME"}


def frame_extent(scene, camera):
    """(left, right, bottom, top) of ``camera``'s frame at unit distance (shifts included)."""
    corners = np.array([tuple(v) for v in camera.data.view_frame(scene=scene)])
    x, y = corners[:, 0] / -corners[:, 2], corners[:, 1] / -corners[:, 2]
    return x.min(), x.max(), y.min(), y.max()


def _frame_windows(scene, depsgraph, lights, fogged, opaque):
    """(surfaces' window, [each spot's glow window, None for a point light]) at the current frame; a spot's
    glow window heeds the picture's occluders (``occluders``, ``footprint.occluded_window``)."""
    camera = scene.camera.evaluated_get(depsgraph)
    mw = np.array(camera.matrix_world)
    mw[:3, :3] /= np.linalg.norm(mw[:3, :3], axis=0)   # the view's axes (a camera's scale does not scale its rays)
    frame = frame_extent(scene, camera)
    boxes = [footprint.box_points(inst.object.bound_box, inst.matrix_world)
             for inst in depsgraph.object_instances if inst.object.type in GEOMETRY]
    surfaces = footprint.boxes_window(np.array(boxes), mw, frame) if boxes else footprint.EMPTY
    margin = occlusion_margin(scene)
    faces = occluders(depsgraph, camera, mw, frame, margin, fogged, opaque) if any(is_spot(o) for o in lights) else []
    glows = []
    for o in lights:
        if not is_spot(o):
            glows.append(None)
            continue
        points = footprint.spot_points(o.evaluated_get(depsgraph).matrix_world, math.cos(o.data.spot_size / 2))
        win = footprint.window(points, mw, frame)
        for face, shade in faces:   # (a face whose picture misses the window hides nothing in it)
            if footprint.intersection(win, shade) != footprint.EMPTY:
                win = footprint.intersection(win, footprint.occluded_window(
                    points, face, mw, frame, margin, camera.data.clip_start, footprint.CONE_EDGES,
                    footprint.clip_depth(camera.data.clip_end, frame)))
        glows.append(win)
    return surfaces, glows


OCCLUDER_FACES = 4          # faces tried as occluders of the spots' glows: those largest in the picture ...
OCCLUDER_CANDIDATES = 64    # ... among the largest in the world
OCCLUDER_OBJECTS = 8        # ... in the meshes largest in the picture (their bounding boxes)
OCCLUDER_POLYGONS = 65536   # objects with more faces are not searched for them
OCCLUSION_MARGIN_PX = 2.0   # px beyond the pixel filter's width (``occlusion_margin``)


def occlusion_margin(scene):
    """(mu, mv): how far, in normalised picture units, an occluder's picture is shrunk (``footprint.
    occluded_window``): the pixel filter's width (a pixel averages its samples over it; at 1 px or less where
    a filter is narrower) and OCCLUSION_MARGIN_PX, at the render's size."""
    r = scene.render
    width = scene.cycles.filter_width if r.engine == "CYCLES" else r.filter_size
    px = max(float(width), 1.0) + OCCLUSION_MARGIN_PX
    scale = r.resolution_percentage / 100.0
    return px / max(r.resolution_x * scale, 1.0), px / max(r.resolution_y * scale, 1.0)


def _asked(test, mat, cache):
    """``test(mat)`` (False for an empty slot), asked once per material in ``cache``."""
    if mat is None:
        return False
    if (test, mat.name) not in cache:
        cache[test, mat.name] = test(mat)
    return cache[test, mat.name]


def occluders(depsgraph, camera, camera_matrix, frame, margin, fogged, opaque):
    """[(face, its window)] of flat convex polygons ((K, 3) world corners in order) that end every camera ray
    meeting them: the faces of rendered meshes (not instances) seen by the camera whose materials are all
    fogged and opaque, and such a mesh's outline where its faces tile a flat convex region
    (``footprint.flat_outline``: a floor of many faces), searched in the OCCLUDER_OBJECTS meshes largest in
    the picture; the OCCLUDER_FACES largest in the picture (among the OCCLUDER_CANDIDATES largest in the
    world; none smaller than twice ``margin``, which ``footprint.occluded_window`` shrinks them by).  None at
    all unless every surface the camera can see is fogged (elsewhere the compositor takes a pixel for sky
    and adds its ray's glow to the sky), and none with depth of field (rays from the whole lens).  What the
    fog's nodes make of a material is the caller's to say: ``fogged(mat)``, the fog's Surface node is in it (it
    writes the pixel's coverage); ``opaque(mat)``, nothing in that fogged material lets light through."""
    if camera.data.dof.use_dof:
        return []
    cache, hidden, meshes = {}, _render_hidden_collections(), []
    for inst in depsgraph.object_instances:
        obj = inst.object
        if obj.type not in GEOMETRY - {"VOLUME"} or not obj.visible_camera:
            continue
        mats = [slot.material for slot in obj.material_slots]
        if not mats or not all(_asked(fogged, m, cache) for m in mats) or obj.is_holdout or obj.is_shadow_catcher:
            return []
        if (obj.type == "MESH" and not inst.is_instance and len(obj.data.polygons) <= OCCLUDER_POLYGONS
                and not obj.original.hide_render and not (hidden and hidden & set(obj.original.users_collection))):
            meshes.append((obj, np.array(inst.matrix_world), mats))
    boxes = np.array([footprint.box_points(obj.bound_box, mw) for obj, mw, _ in meshes]).reshape(-1, 8, 3)
    found = []
    for k in np.argsort(-footprint.boxes_areas(boxes, camera_matrix, frame))[:OCCLUDER_OBJECTS]:
        obj, mw, mats = meshes[k]
        if all(_asked(opaque, m, cache) for m in mats):
            faces, area, corners = _flat_convex_faces(obj.data, mw)
            outline = footprint.flat_outline(corners, area) if len(faces) != 1 else None
            found += faces + ([(area, outline)] if outline is not None else [])
    found.sort(key=lambda area_face: -area_face[0])
    seen = []
    for _, face in found[:OCCLUDER_CANDIDATES]:
        u0, u1, v0, v1 = footprint.window(face, camera_matrix, frame)
        if u1 - u0 > 2.0 * margin[0] and v1 - v0 > 2.0 * margin[1]:
            seen.append(((u1 - u0) * (v1 - v0), face, (u0, u1, v0, v1)))
    seen.sort(key=lambda area_face: -area_face[0])
    return [(face, shade) for _, face, shade in seen[:OCCLUDER_FACES]]


def _render_hidden_collections():
    """The collections a render leaves out (their own or a parent's Disable in Renders): the viewport's
    depsgraph still holds their objects, which must not count as occluders."""
    hidden = set()
    for c in bpy.data.collections:
        if c.hide_render:
            hidden |= {c, *c.children_recursive}
    return hidden


def _flat_convex_faces(mesh, matrix):
    """([(area m^2, (K, 3) world corners)] of the mesh's faces that are flat and convex (within float rounding),
    the area of all its faces (m^2), the world corners of its faces), faces of each corner count at once."""
    n = len(mesh.polygons)
    if not n:
        return [], 0.0, np.zeros((0, 3))
    co = np.empty(3 * len(mesh.vertices))
    mesh.vertices.foreach_get("co", co)
    co = co.reshape(-1, 3) @ matrix[:3, :3].T + matrix[:3, 3]
    starts, totals, verts = (np.empty(n, int), np.empty(n, int), np.empty(len(mesh.loops), int))
    mesh.polygons.foreach_get("loop_start", starts)
    mesh.polygons.foreach_get("loop_total", totals)
    mesh.loops.foreach_get("vertex_index", verts)
    out, total = [], 0.0
    for k in np.unique(totals):
        start = starts[totals == k]
        faces = co[verts[start[:, None] + np.arange(k)]]                              # (M, k, 3)
        after = np.roll(faces, -1, axis=1)
        normal = 0.5 * np.cross(faces, after).sum(axis=1)                            # Newell: area times unit
        area = np.linalg.norm(normal, axis=1)
        total += float(area.sum())
        unit = normal / np.maximum(area, 1e-300)[:, None]
        off_plane = np.abs(np.einsum("mkd,md->mk", faces - faces.mean(axis=1, keepdims=True), unit)).max(axis=1)
        turns = np.einsum("mkd,md->mk", np.cross(after - faces, np.roll(after, -1, axis=1) - after), unit)
        good = (area > 0.0) & (off_plane <= 1e-6 * np.sqrt(area)) & (turns >= -1e-9 * area[:, None]).all(axis=1)
        out += [(float(a), f) for a, f in zip(area[good], faces[good])]
    return out, total, co[np.unique(verts)]


def full_windows(lights):
    """:func:`windows` that crop nothing."""
    return footprint.FULL, [footprint.FULL if is_spot(o) else None for o in lights]


def windows(scene, lights, frames=None, halos=False, *, fogged, opaque):
    """The windows of the Compositor method (``precompute/model/footprint.py``): (the surfaces' window, [each
    light's glow window: a spot's, None for a point light]) holding ``frames`` (default: every frame of an
    animated scene's range, else the current one).  Full windows where they can't be bounded: border
    renders, animations over MAX_WINDOW_FRAMES frames or with motion blur.  ``halos``: the spots' glows have
    a multiply scattered halo (Dense Fog), which fills the picture as a point light's does: no window.
    ``fogged``, ``opaque``: the material tests of ``occluders``."""
    if halos:
        surfaces, glows = windows(scene, lights, frames, fogged=fogged, opaque=opaque)
        return surfaces, [None if is_spot(o) else g for o, g in zip(lights, glows)]
    if scene.render.use_border or scene.camera is None or scene.camera.data.type != "PERSP":
        return full_windows(lights)
    if frames is None and animated(scene):
        if scene.frame_end - scene.frame_start + 1 > MAX_WINDOW_FRAMES or scene.render.use_motion_blur:
            return full_windows(lights)   # (motion blur: the frames' windows don't bound the times between)
        frames = range(scene.frame_start, scene.frame_end + 1)
    frames = [scene.frame_current] if frames is None else frames
    surfaces, glows = footprint.EMPTY, [footprint.EMPTY if is_spot(o) else None for o in lights]
    for _, depsgraph in at_frames(scene, frames):
        s, g = _frame_windows(scene, depsgraph, lights, fogged, opaque)
        surfaces = footprint.union(surfaces, s)
        glows = [None if a is None else footprint.union(a, b) for a, b in zip(glows, g)]
    return surfaces, glows
