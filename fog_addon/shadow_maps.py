"""Shadow maps of the lights whose shadows fall in the fog: the visibility source of light shafts.

For each such light (``caveats.shadowing_lights``: an object casting shadows within its glow's reach) the
distance from the light to the first surface is ray cast in every direction of its map
(``precompute/physics/shafts/shafts.py``: a longitude-latitude grid for a point light, its rows thinned towards the
poles to the equator's spacing, ``point_map_casts``; a square grid over the cone for a spot) against one BVH of the
scene's shadow casters (``mathutils.bvhtree``, evaluated meshes in world space: modifiers, instances and curves
included), and stored as a packed float image (a ZIP-compressed OpenEXR, ``_pack``), so the saved file renders
without the add-on (the compositor reads it with Map UV).  A map holds the light's pose and the geometry of the
frame it was baked at (``ShadowMap.key``).

**Animations.**  Where a shafted light or a shadow caster is animated (``moving_lights``), the light's image is an
atlas of its maps at every frame an animation renders (``shaft_maps.atlas_frames``: frame_start..frame_end by
frame_step, every k-th of those beyond ``shaft_maps.ATLAS_MAX_FRAMES``), four frames a texel in R, G, B and A, at
``shaft_maps.ANIMATED_POINT_MAP`` (``ANIMATED_SPOT_MAP``) grid points a frame (``Atlas``).  The compositor picks the
frame's map with a simple-expression driver on the frame (``shaft_maps.ATLAS_TILE``: no Python at render time, so a
farm without the add-on renders every frame's shafts; ``comp_shafts.atlas_tile``).  A moving spot's maps all lie in
one frame that holds the cones of all its poses (``shaft_maps.spot_union``; else a point light's map of the whole
sphere), and its shafts take its cone from the drivers of its glow.  In the add-on the frame handler bakes the
frame's map again where the light or the casters changed since (``follow_frame``) and the file's save bakes and
packs the atlas's whole range again after such a change (``complete``).

Objects that Cycles lets shadow rays through (hidden from shadow rays, not rendered) cast none here; every
other surface is opaque (glass included, as Cycles' shadow rays treat it).
"""
import functools
import gc
import hashlib
import itertools
import json
import math
import os
import tempfile
from typing import NamedTuple

import bpy
import numpy as np
from mathutils import Vector
from mathutils.bvhtree import BVHTree

from . import caveats, view
from .precompute.core.ops import NumpyOps
from .precompute.core.tables import TableSpec
from .precompute.model import bakers, predict, sampling
from .precompute.physics.shafts import shaft_maps, shafts

IMAGE_PREFIX = "AnalyticFog Shadow "   # a light's map: "<IMAGE_PREFIX><light name>" (``nodes/owned.PREFIX``)
KEY = "analytic_fog_shadow_key"            # on the image: what the map was baked from (``ShadowMap.key``)
# on an animation's atlas (``Atlas``): its layout [first frame, stride, tiles, columns, rows, width, height] (the
# compositor's drivers read it), what it was laid out for (``_layout``), each baked frame's key, and whether a frame's
# map changed since it was packed (``follow_frame``; ``complete`` bakes the range again)
ATLAS = "analytic_fog_shadow_atlas"
LAYOUT = "analytic_fog_shadow_layout"
TILE_KEYS = "analytic_fog_shadow_tiles"
STALE = "analytic_fog_shadow_stale"


class Atlas(NamedTuple):
    """Where an animation's maps lie in a light's atlas image: tile t (``shaft_maps.ATLAS_TILE``) is the map of frame
    first + t stride, in slot t // 4 (column, row: ``shaft_maps.atlas_place``), channel t % 4, each map width x height
    grid points.  ``tiles`` is 1 where every frame's map was the same (a light the moving casters do not shadow)."""
    first: int
    stride: int
    tiles: int
    columns: int
    rows: int
    width: int
    height: int


class ShadowMap(NamedTuple):
    """A light's baked map: ``spec`` (its image's name and the grid of one map), ``spot``: (frame, half_width) of a
    spot's map (``spot_map``) or None for a point light's (or a moving spot's whole-sphere map), ``atlas``: the
    ``Atlas`` of an animation's maps or None, ``cone``: True if the spot's cone is read from its drivers (a moving
    spot, whose map's frame is not its pose's)."""
    spec: TableSpec
    spot: tuple
    atlas: Atlas = None
    cone: bool = False


def _triangles(depsgraph, objects):
    """(vertices (V, 3) world m, triangles (T, 3) indices) of ``objects`` as evaluated."""
    verts, tris, base = [], [], 0
    for obj in objects:
        ev = obj.evaluated_get(depsgraph)
        try:
            mesh = ev.to_mesh()
        except RuntimeError:
            continue
        if mesh is None:
            continue
        try:
            mesh.calc_loop_triangles()
            n, t = len(mesh.vertices), len(mesh.loop_triangles)
            if n and t:
                co = np.empty(n * 3, np.float64)
                mesh.vertices.foreach_get("co", co)
                idx = np.empty(t * 3, np.int64)
                mesh.loop_triangles.foreach_get("vertices", idx)
                mw = np.asarray(ev.matrix_world, float)
                verts.append(co.reshape(-1, 3) @ mw[:3, :3].T + mw[:3, 3])
                tris.append(idx.reshape(-1, 3) + base)
                base += n
        finally:
            ev.to_mesh_clear()
    if not verts:
        return np.zeros((0, 3)), np.zeros((0, 3), np.int64)
    return np.concatenate(verts), np.concatenate(tris)


class Scene(NamedTuple):
    """The shadow casters of a frame as one BVH, and a digest of their geometry."""
    bvh: object
    digest: str


def scene_bvh(scene, depsgraph=None, objects=None):
    """The BVH of ``scene``'s shadow casters (``caveats.shadow_casters``, or ``objects``) in world space, and their
    digest."""
    depsgraph = depsgraph or bpy.context.evaluated_depsgraph_get()
    verts, tris = _triangles(depsgraph, caveats.shadow_casters(scene) if objects is None else objects)
    digest = hashlib.sha1(np.ascontiguousarray(verts, np.float32).tobytes()
                          + np.ascontiguousarray(tris, np.int32).tobytes()).hexdigest()
    bvh = BVHTree.FromPolygons(verts.tolist(), tris.tolist(), all_triangles=True) if len(tris) else None
    return Scene(bvh, digest)


@functools.lru_cache(maxsize=8)
def point_casts(width=shaft_maps.POINT_MAP[0], height=shaft_maps.POINT_MAP[1]):
    """(the rays of a point light's map as mathutils Vectors, the ray each grid point takes):
    ``shaft_maps.point_map_casts`` (every point light's map of this grid shares them)."""
    directions, fill = shaft_maps.point_map_casts(width, height)
    return _vectors(directions), fill


def _vectors(rows):
    """mathutils Vectors of the rows of an (N, 3) array, made with Python's cyclic garbage collector paused: each
    new object counts towards its next pass, which walks every tracked object, so half a million new Vectors
    cost twice their own time in passes (none of them can be garbage)."""
    paused = gc.isenabled()
    gc.disable()
    try:
        return [Vector(d) for d in rows.tolist()]
    finally:
        if paused:
            gc.enable()


def cast(bvh, origin, directions):
    """Distance (m) from ``origin`` along each unit direction (N, 3 array, or a list of Vectors) to the first
    triangle, NO_HIT if none."""
    vectors = directions if isinstance(directions, list) else _vectors(directions)
    return _first_hits(bvh, itertools.repeat(Vector(tuple(origin)), len(vectors)), vectors, len(vectors))


def cast_parallel(bvh, origins, direction):
    """Distance (units) from each of ``origins`` ((N, 3) array) along the one unit ``direction`` to the first
    triangle, NO_HIT if none (a sun's map: ``sun_shafts.SunFrame``)."""
    return _first_hits(bvh, _vectors(origins), itertools.repeat(Vector(tuple(direction)), len(origins)), len(origins))


def segments_free(bvh, origins, directions, lengths):
    """(M,) True where no triangle of ``bvh`` (None: none) lies on each segment: ``origins`` and unit ``directions``
    ((M, 3) arrays), ``lengths`` ((M,) units) (``escape``'s photons and their light)."""
    if bvh is None:
        return np.ones(len(origins), bool)
    hits = map(bvh.ray_cast, _vectors(origins), _vectors(directions), np.asarray(lengths, float).tolist())
    return np.fromiter((hit[0] is None for hit in hits), bool, len(origins))


def _first_hits(bvh, origins, directions, count):
    """(count,) float32: the distance along each ray (``origins`` and unit ``directions``: iterables of mathutils
    Vectors) to the first triangle of ``bvh``, NO_HIT where none (or no BVH).  The rays go through ``map``, not a
    Python loop: most of a map's time is the interpreter's, not the BVH's."""
    if bvh is None:
        return np.full(count, shaft_maps.NO_HIT, np.float32)
    hits = map(bvh.ray_cast, origins, directions)
    return np.fromiter((shaft_maps.NO_HIT if hit[0] is None else hit[3] for hit in hits), np.float32, count)


SUN_IMAGE = "AnalyticFog Sun Shadow"   # the sun's map or atlas (``sun_maps.py``: one sun shines through a fog layer)


def _is_spot(light):
    return light.data.type == "SPOT" and light.data.spot_size < math.radians(179.0)


def bake(light, geometry, level=0):
    """(ShadowMap, depths (rows, columns) float32) of ``light`` against ``geometry`` (``scene_bvh``), its grid
    ``level`` times halved across (``shaft_maps.map_grid``)."""
    origin = tuple(light.matrix_world.translation)
    spot = spot_map(light)
    grid = shaft_maps.map_grid(spot is not None, level)
    if spot is not None:
        dirs = shaft_maps.spot_map_directions(*spot, size=grid[0])
        depth = cast(geometry.bvh, origin, dirs.reshape(-1, 3)).reshape(dirs.shape[:2])
    else:
        vectors, fill = point_casts(*grid)
        depth = cast(geometry.bvh, origin, vectors)[fill]
    spec = TableSpec(IMAGE_PREFIX + light.name, depth.shape[1], depth.shape[0])
    return ShadowMap(spec, spot), depth


def spot_map(light):
    """(frame, half_width) of a spot's map at the light's pose (``shaft_maps.spot_frame``, ``spot_half_width``),
    None for a point light (or a spot of 179 degrees or more, mapped as one)."""
    if not _is_spot(light):
        return None
    frame = shaft_maps.spot_frame(np.asarray(light.matrix_world)[:3, :3])
    return (tuple(tuple(float(c) for c in v) for v in frame),
            shaft_maps.spot_half_width(math.cos(0.5 * light.data.spot_size)))


def key(light, geometry):
    """What a light's map depends on: its pose, its cone and the casters' geometry."""
    m = tuple(round(v, 6) for row in light.matrix_world for v in row)
    cone = round(light.data.spot_size, 6) if _is_spot(light) else None
    return hashlib.sha1(repr((m, cone, geometry.digest)).encode()).hexdigest()


def _new_image(name, width, height):
    """A new float image ``name`` for a map: non-colour data, channel-packed alpha, full precision, kept."""
    img = bpy.data.images.new(name, width, height, alpha=True, float_buffer=True, is_data=True)
    img.colorspace_settings.name = "Non-Color"
    img.alpha_mode = "CHANNEL_PACKED"
    img.use_half_precision = False
    img.use_fake_user = True
    return img


def map_image(name, width, height, atlas):
    """The image ``name`` of width x height to hold a map (``atlas`` False) or an atlas (True), new unless it is one
    of that size and kind already."""
    img = bpy.data.images.get(name)
    if img is not None and (tuple(img.size) != (width, height) or (ATLAS in img) != atlas):
        bpy.data.images.remove(img)
        img = None
    return _new_image(name, width, height) if img is None else img


def pack_map(img, rgba):
    """Write ``rgba`` ((height, width, 4) float32, the bottom row first) into ``img`` and pack it into the file as a
    ZIP-compressed OpenEXR (lossless; Blender's own packing of a float image is uncompressed: 16 bytes a texel; a
    map's depths take 2-6x less, docs/measurements/2026-11-29-animated-shadow-maps.md).  The image then reads from
    its packed file (source FILE), as after the file is opened again; without OpenImageIO, Blender's packing."""
    rgba = np.ascontiguousarray(rgba, np.float32)
    img.pixels.foreach_set(rgba.ravel())
    img.update()
    try:
        from . import imageio
        with tempfile.TemporaryDirectory() as folder:
            path = os.path.join(folder, "map.exr")
            imageio.write_exr(path, rgba[::-1], compression="zip")
            with open(path, "rb") as f:
                data = f.read()
    except (ImportError, OSError):
        img.pack()
        return img
    img.pack(data=data, data_len=len(data))
    if img.source != "FILE":
        img.source = "FILE"
    img.filepath_raw = f"//{bpy.path.clean_name(img.name)}.exr"   # (never read: its packed file is)
    img.file_format = "OPEN_EXR"
    return img


def _store(spec, depth, version):
    img = map_image(spec.name, spec.width, spec.height, atlas=False)
    pack_map(img, np.repeat(np.asarray(depth, np.float32)[..., None], 4, axis=-1))
    img[KEY] = version
    return img


def moving_lights(scene, lights):
    """The ``lights`` whose maps change over the animation: all of them where a shadow caster is animated
    (``caveats.is_animated``: an action, drivers or constraints on it or on what it hangs from), else those animated
    themselves."""
    if any(caveats.is_animated(o) for o in caveats.shadow_casters(scene)):
        return list(lights)
    return [o for o in lights if caveats.is_animated(o)]


def frames_of(scene):
    """(first, stride, count) of the frames an animation's maps are baked for (``shaft_maps.atlas_frames``)."""
    return shaft_maps.atlas_frames(scene.frame_start, scene.frame_end, scene.frame_step)


def ensure(scene, lights, geometry=None, lazy=False, sizing=None):
    """{light name: ShadowMap} of ``lights``, each baked unless its image holds this pose and geometry at its grid
    (the lights whose maps move over an animation of more than one frame: their atlases, ``ensure_atlases``,
    ``lazy`` as there); returns (maps, images by spec name).  ``sizing``: (beta 1/unit, budget grid points or None
    for no limit) to size the still maps by ``map_levels``; None keeps each map's grid as it is (a new one full)."""
    if not lights:
        return {}, {}
    moving = {o.name for o in moving_lights(scene, lights)} if frames_of(scene)[2] > 1 else set()
    maps, images = ensure_atlases(scene, [o for o in lights if o.name in moving], lazy=lazy)
    still = [o for o in lights if o.name not in moving]
    levels = map_levels(scene, still, *sizing) if sizing is not None else {}
    for light in still:
        geometry = geometry or scene_bvh(scene)
        version = key(light, geometry)
        name = IMAGE_PREFIX + light.name
        img = bpy.data.images.get(name)
        level = levels.get(light.name, _level_of(light, img))
        if (img is not None and img.get(KEY) == version and img.packed_file is not None and ATLAS not in img
                and tuple(img.size) == shaft_maps.map_grid(spot_map(light) is not None, level)):
            shadow = describe(light, img)
        else:
            shadow, depth = bake(light, geometry, level)
            img = _store(shadow.spec, depth, version)
        maps[light.name], images[shadow.spec.name] = shadow, img
    return maps, images


def shafted_split(scene, lights, beta, cap):
    """(shafted, over): the ``lights`` whose shadows fall in fog the camera may see (``caveats.shadowing_lights``),
    the ``cap`` most important of them to the picture (``sampling.importance``; None: all) shafted and the rest
    over the cap (their glows unshadowed: ``shafts.shaft_lights``), each in the order of ``lights``."""
    found = caveats.shadowing_lights(scene, lights, beta, max(view.scene_size(scene), 1e-6)) if lights else {}
    casting = [o for o in lights if o.name in found]
    if cap is None or len(casting) <= cap:
        return casting, []
    weight = _weights(scene, casting, beta)
    kept = set(np.argsort(-weight, kind="stable")[:cap].tolist())
    return [o for k, o in enumerate(casting) if k in kept], [o for k, o in enumerate(casting) if k not in kept]


def _weights(scene, lights, beta):
    """Each light's share of the picture's fog seen from the camera, up to a factor (``sampling.importance``)."""
    eye = np.array(scene.camera.matrix_world.translation) if scene.camera is not None else np.zeros(3)
    return sampling.importance([o.matrix_world.translation for o in lights], view.light_intensities(lights), eye,
                               beta)


def map_levels(scene, lights, beta, budget=shaft_maps.MAP_BUDGET):
    """{light name: level} of the still maps of ``lights`` (``shaft_maps.map_levels``): their grid points within
    ``budget`` (None: every map full), shared by each light's weight in the picture seen from the camera
    (``sampling.importance``, fog of ``beta`` 1/unit)."""
    if budget is None or not lights:
        return {o.name: 0 for o in lights}
    levels = shaft_maps.map_levels(_weights(scene, lights, beta), [spot_map(o) is not None for o in lights], budget)
    return {o.name: int(k) for o, k in zip(lights, levels)}


def map_level_error(scene, spec, lights, levels, grid=None):
    """The largest share of a view sample's fog that the shrunk maps (``levels`` by name: ``map_levels``) may move:
    each light's glow times ``shaft_maps.MAP_LEVEL_ERROR`` at its level, summed over the lights, over the fog of all
    ``lights`` (at the view's samples on ``grid``, SHADOW_GRID by default; each light a point: an estimate); 0 where
    no map is shrunk."""
    errors = np.array([shaft_maps.MAP_LEVEL_ERROR[levels.get(o.name, 0)] for o in lights])
    if scene.camera is None or not errors.any():
        return 0.0
    samples = view.view_samples(scene, lights, frames=[scene.frame_current],
                                grid=grid or SHADOW_GRID)._replace(shapes=None)
    glow, scatter = predict.light_fog(samples, view.light_intensities(lights), spec.beta_per_unit, spec.anisotropy)
    moved = (np.nan_to_num(glow, nan=0.0, posinf=0.0) * errors[None, :, None]).sum(axis=1)
    fog = np.nan_to_num(glow + scatter, nan=0.0, posinf=0.0).sum(axis=1)
    return float(predict.judged_shares(moved[:, None, :], fog).max(initial=0.0))


def _level_of(light, img):
    """The level (``shaft_maps.map_grid``) of ``light``'s still map ``img`` (0 without one, or for an atlas)."""
    if img is None or ATLAS in img or img.size[0] < 2:
        return 0
    full = shaft_maps.map_grid(spot_map(light) is not None)[0]
    return max(int(round(math.log2(full / img.size[0]))), 0)


def _layout(light, frames, union):
    """(what an atlas of ``light`` is laid out for: its frames, kind, grid and a spot's map frame, as JSON; the grid
    (width, height); the map frame (``spot_map``'s, or None for the whole sphere))."""
    if union is not None:
        size = (shaft_maps.ANIMATED_SPOT_MAP, shaft_maps.ANIMATED_SPOT_MAP)
    else:
        size = shaft_maps.ANIMATED_POINT_MAP
    return json.dumps([list(frames), list(size), union]), size, union


def ensure_atlases(scene, lights, only_stale=False, lazy=False):
    """{light name: ShadowMap} of the moving ``lights`` and their atlas images: each light's map at every frame of
    ``frames_of(scene)`` (the scene stepped through them, its frame restored), baked where its key (``key``: the
    light's pose and the casters' geometry) differs from the one the atlas holds for that frame, and packed.  A
    spot's maps all lie in ``shaft_maps.spot_union``'s frame of its poses (the whole sphere where they turn too far).
    ``only_stale``: only the lights whose atlas is missing, STALE or laid out for other frames.  ``lazy`` (a
    rebuild from the depsgraph handler, which must not step through frames): an atlas laid out for this range is
    taken as it is; a new one gets the map of the current frame only (a spot's over the whole sphere), STALE: the
    frame handler bakes each frame's as it is shown (``follow_frame``), the file's save all of them (``complete``)."""
    frames = frames_of(scene)
    if only_stale:
        lights = [o for o in lights if _needs_baking(o, frames)]
    if not lights:
        return {}, {}
    first, stride, count = frames
    frame_list = [first + stride * t for t in range(count)]
    unions = {}
    spots = [o for o in lights if _is_spot(o)]
    if lazy:   # the spots' maps where they lie now (their poses are not stepped through)
        for o in spots:
            img = bpy.data.images.get(IMAGE_PREFIX + o.name)
            layout = json.loads(img[LAYOUT]) if img is not None and LAYOUT in img else None
            if layout is not None and layout[0] == list(frames) and layout[2] is not None:
                unions[o.name] = (tuple(tuple(v) for v in layout[2][0]), layout[2][1])
    elif spots:   # first the spots' poses: where their maps lie
        poses = {o.name: [] for o in spots}
        for _ in view.at_frames(scene, frame_list):
            for o in spots:
                poses[o.name].append(shaft_maps.spot_frame(np.asarray(o.matrix_world)[:3, :3]))
        unions = {o.name: shaft_maps.spot_union(poses[o.name], math.cos(0.5 * o.data.spot_size)) for o in spots}
    plans = []
    for light in lights:
        layout, size, union = _layout(light, frames, unions.get(light.name))
        img = bpy.data.images.get(IMAGE_PREFIX + light.name)
        same = img is not None and img.get(LAYOUT) == layout and img.packed_file is not None
        keys = list(img[TILE_KEYS]) if same else [""] * count
        plans.append({"light": light, "layout": layout, "size": size, "union": union, "keys": keys,
                      "tiles": atlas_tiles(img) if same else [None] * count, "changed": not same})
    if lazy:
        geometry = None
        for plan in plans:
            if plan["changed"]:   # this frame's map (the one the driver picks here), the others to come
                geometry = geometry or scene_bvh(scene)
                tile, off = divmod(scene.frame_current - first, stride)
                t = min(max(tile, 0), count - 1)
                plan["tiles"][t] = _bake_tile(plan["light"], geometry, plan["union"], plan["size"])
                if not off and tile == t:
                    plan["keys"][t] = key(plan["light"], geometry)
                plan["stale"] = True
            else:
                plan["stale"] = bool(bpy.data.images[IMAGE_PREFIX + plan["light"].name].get(STALE))
        return _store_atlases(plans, frames, dedupe=False)
    for t, (_, depsgraph) in enumerate(view.at_frames(scene, frame_list)):
        geometry = scene_bvh(scene, depsgraph)
        for plan in plans:
            version = key(plan["light"], geometry)
            if plan["keys"][t] != version or plan["tiles"][t] is None:
                plan["tiles"][t] = _bake_tile(plan["light"], geometry, plan["union"], plan["size"])
                plan["keys"][t] = version
                plan["changed"] = True
    return _store_atlases(plans, frames)


def _store_atlases(plans, frames, dedupe=True):
    """({light name: ShadowMap}, images) of ``ensure_atlases``'s ``plans``: each atlas laid out and packed where
    it changed or was STALE (a plan's "stale": it is STALE still, its maps not all baked); ``dedupe``: an atlas
    whose maps are all the same holds one."""
    maps, images = {}, {}
    for plan in plans:
        light, (width, height) = plan["light"], plan["size"]
        name = IMAGE_PREFIX + light.name
        img = bpy.data.images.get(name)
        if not plan["changed"] and img is not None and (plan.get("stale") or not img.get(STALE)):
            atlas = Atlas(*(int(v) for v in img[ATLAS]))   # as it is (``lazy``: still STALE, or all verified)
        else:
            img, atlas = store_atlas(name, plan["tiles"], frames, plan["size"], plan["layout"], plan["keys"],
                                     bool(plan.get("stale")), dedupe)
        spot = None if plan["union"] is None else tuple(plan["union"])
        spot = None if spot is None else (tuple(tuple(v) for v in spot[0]), spot[1])
        maps[light.name] = ShadowMap(TableSpec(name, width, height), spot, atlas, cone=_is_spot(light))
        images[name] = img
    return maps, images


def store_atlas(name, tiles, frames, size, layout, keys, stale=False, dedupe=True):
    """(image, ``Atlas``): the maps ``tiles`` ((height, width) float32 each, or None: not baked yet) of the frames
    ``frames`` ((first, stride, count)) laid out and packed in the atlas image ``name`` (new unless one of that size
    is), with what it was laid out for (``layout``), each tile's key and whether it is STALE; ``dedupe``: maps all
    the same are stored once."""
    first, stride, count = frames
    width, height = size
    if dedupe and all(tiles[0] is not None and np.array_equal(tiles[0], tile) for tile in tiles[1:]):
        tiles = tiles[:1]   # the same map at every frame: one tile
    columns, rows = shaft_maps.atlas_layout(len(tiles), width, height)
    atlas = Atlas(first, stride, len(tiles), columns, rows, width, height)
    img = map_image(name, columns * width, rows * height, atlas=True)
    img[ATLAS] = list(atlas)
    pack_map(img, assemble_atlas(tiles, columns, rows, width, height))
    img[LAYOUT], img[TILE_KEYS], img[STALE] = layout, list(keys), bool(stale)
    if KEY in img:
        del img[KEY]
    return img, atlas


def _needs_baking(light, frames):
    """True if ``light``'s atlas is missing, STALE or laid out for other ``frames``."""
    img = bpy.data.images.get(IMAGE_PREFIX + light.name)
    if img is None or ATLAS not in img or img.get(STALE) or img.packed_file is None:
        return True
    return json.loads(img[LAYOUT])[0] != list(frames)


def _bake_tile(light, geometry, union, size):
    """(height, width) float32: ``light``'s map at its pose against ``geometry``: over a spot's ``union`` frame
    ((frame, half_width)), or the whole sphere (None)."""
    origin = tuple(light.matrix_world.translation)
    if union is not None:
        dirs = shaft_maps.spot_map_directions(*union, size=size[0])
        return cast(geometry.bvh, origin, dirs.reshape(-1, 3)).reshape(dirs.shape[:2])
    vectors, fill = point_casts(*size)
    return cast(geometry.bvh, origin, vectors)[fill]


def assemble_atlas(tiles, columns, rows, width, height):
    """(rows height, columns width, 4) float32: the atlas of ``tiles`` ((height, width) each, or None) in their
    places (``shaft_maps.atlas_place``); unused channels and missing maps NO_HIT."""
    rgba = np.full((rows * height, columns * width, 4), shaft_maps.NO_HIT, np.float32)
    for t, tile in enumerate(tiles):
        if tile is None:   # (not baked yet: ``ensure_atlases``'s lazy)
            continue
        column, row, channel = shaft_maps.atlas_place(t, columns)
        rgba[row * height:(row + 1) * height, column * width:(column + 1) * width, channel] = tile
    return rgba


def atlas_tiles(img):
    """The maps an atlas image holds, one per frame of its TILE_KEYS (a one-tile atlas's map for each)."""
    first, stride, tiles, columns, rows, width, height = (int(v) for v in img[ATLAS])
    rgba = np.empty(img.size[0] * img.size[1] * 4, np.float32)
    img.pixels.foreach_get(rgba)
    rgba = rgba.reshape(img.size[1], img.size[0], 4)
    out = []
    for t in range(tiles):
        column, row, channel = shaft_maps.atlas_place(t, columns)
        out.append(rgba[row * height:(row + 1) * height, column * width:(column + 1) * width, channel].copy())
    count = len(img[TILE_KEYS])
    return out if tiles == count else [out[0]] * count


def follow_frame(scene, lights):
    """The frame changed (the add-on's frame handler): in each of ``lights``' atlases, this frame's map is baked
    again if the light or the casters changed since (its key), so the add-on renders what the scene holds now; the
    atlas is then STALE (its packed copy is old, and the other frames may have changed as well: ``complete`` bakes
    the range again when the file is saved).  A frame no map is baked for (between strides, outside the range)
    keeps the one the compositor's driver picks.  Returns the names of the lights whose map changed."""
    frame = scene.frame_current
    geometry, changed = None, []
    for light in lights:
        img = bpy.data.images.get(IMAGE_PREFIX + light.name)
        if img is None or ATLAS not in img:
            continue
        first, stride, tiles, columns, rows, width, height = (int(v) for v in img[ATLAS])
        keys = list(img[TILE_KEYS])
        t, off = divmod(frame - first, stride)
        if json.loads(img[LAYOUT])[0] != list(frames_of(scene)):
            img[STALE] = True   # the range changed: ``complete`` lays the atlas out again
        if off or not 0 <= t < len(keys):
            continue
        geometry = geometry or scene_bvh(scene)
        version = key(light, geometry)
        if keys[t] == version:
            continue
        _, size, union = json.loads(img[LAYOUT])
        union = None if union is None else (tuple(tuple(v) for v in union[0]), union[1])
        depth = _bake_tile(light, geometry, union, size)
        tile = t if tiles > 1 else 0
        if tiles == 1:   # the one map every frame shared: now this frame's, the others to be baked again
            keys = [""] * len(keys)
        write_tile(img, tile, depth)
        keys[t] = version
        img[TILE_KEYS], img[STALE] = keys, True
        changed.append(light.name)
    return changed


def write_tile(img, tile, depth):
    """Write ``depth`` ((height, width) float32) into tile ``tile`` of the atlas image ``img`` (in memory: its
    packed copy is old until packed again)."""
    first, stride, tiles, columns, rows, width, height = (int(v) for v in img[ATLAS])
    rgba = np.empty(img.size[0] * img.size[1] * 4, np.float32)
    img.pixels.foreach_get(rgba)
    rgba = rgba.reshape(img.size[1], img.size[0], 4)
    column, row, channel = shaft_maps.atlas_place(tile, columns)
    rgba[row * height:(row + 1) * height, column * width:(column + 1) * width, channel] = depth
    img.pixels.foreach_set(rgba.ravel())
    img.update()


def complete(scene, lights):
    """Before the file is saved: the atlases of ``lights`` that are STALE or laid out for another range are baked
    over the scene's range again and packed (``ensure_atlases``), so a farm renders every frame as the add-on does.
    Returns their {light name: ShadowMap} and images."""
    return ensure_atlases(scene, [o for o in lights if ATLAS in (bpy.data.images.get(IMAGE_PREFIX + o.name) or {})],
                          only_stale=True)


def describe(light, img):
    """The ShadowMap of an image baked for ``light`` (its grid from the image, its frame from the light)."""
    return ShadowMap(TableSpec(img.name, img.size[0], img.size[1]), spot_map(light))


def remove_unused(keep=()):
    """Remove the shadow maps of lights no longer shafted (names not in ``keep``; the sun's SUN_IMAGE too unless
    kept)."""
    for img in list(bpy.data.images):
        if (img.name.startswith(IMAGE_PREFIX) or img.name == SUN_IMAGE) and img.name not in keep:
            bpy.data.images.remove(img)


SHADOW_GRID = (48, 27)     # the view's samples the shadows' share is judged at (``shadowed_parts``)
SHARE_MAP = (128, 64)      # longitude x latitude points of the coarse point maps it casts (2.8 degrees apart)
SHARE_NODES = 16           # quadrature nodes along each ray (``shafts.lit_share``)
SHARE_OTHERS = 64          # the other lights whose fog it counts at most beside them (``shadowed_parts``' others)
SHARE_LIGHTS = 16          # the lights it judges at most: the most important (``sampling.importance``)


def judged_lights(scene, spec, lights, count=None):
    """At most ``count`` (SHARE_LIGHTS) of ``lights``, the most important to the picture seen from the camera
    (``sampling.importance``; from the origin without one), in their order."""
    eye = np.array(scene.camera.matrix_world.translation) if scene.camera is not None else np.zeros(3)
    weight = sampling.importance([o.matrix_world.translation for o in lights], view.light_intensities(lights), eye,
                                 spec.beta_per_unit)
    return [lights[k] for k in sorted(np.argsort(-weight, kind="stable")[:count or SHARE_LIGHTS])]


def shadowed_parts(scene, spec, lights, grid=SHADOW_GRID, others=()):
    """Where the fog has no shafts: (names of the judged lights, (P, N') each one's fog light that its shadows
    would take away, as a share of the sample's fog with them), at the view's samples on ``grid``, judged lights
    only (at most SHARE_LIGHTS of ``lights``, the most important to the picture), or None without a camera.

    Each light's glow along a ray is split by its lit share S (``shafts.lit_share``: the equiangular nodes of
    the compositor's shafts, SHARE_NODES of them) read from a coarse point map of the light (SHARE_MAP, ray cast
    here; a spot or an area light is mapped as a point), and the glow without shafts, G, overestimates the fog
    by G (1 - S); the denominator is the fog with the shadows, sum G S + the fog light on surfaces (unshadowed:
    the fog light's own shadows are left out of the estimate).  ``others``: lights whose fog is in the picture
    beside them (the shafted ones where the Quality's cap leaves ``lights`` out), in the denominator too: the most
    important SHARE_OTHERS of them, SHARE_LIGHTS of those with their shadows the same way (the rest's fog left out
    makes the share larger: an estimate on the safe side).  The predicted error's
    share of what Light Shafts off, a method without them or the Quality's cap leaves out
    (``ops/left_out.shadow_fog``)."""
    if scene.camera is None or not lights:
        return None
    judged = judged_lights(scene, spec, lights)
    shaded = judged_lights(scene, spec, others) if others else []
    beside = judged_lights(scene, spec, others, SHARE_OTHERS) if others else []
    every = judged + shaded + [o for o in beside if o not in shaded]
    samples = view.view_samples(scene, every, frames=[scene.frame_current], grid=grid)
    samples = samples._replace(shapes=None)   # (each light a point: an estimate)
    glow, scatter = predict.light_fog(samples, view.light_intensities(every), spec.beta_per_unit, spec.anisotropy)
    geometry = scene_bvh(scene)
    vectors, fill = point_casts(*SHARE_MAP)
    m = NumpyOps(bakers.numpy_tables(spec.anisotropy))
    length = np.where(np.isfinite(samples.distance), samples.distance, 1.0e6)
    lit = np.ones(glow.shape[:2])
    for k, light in enumerate(judged + shaded):
        origin = tuple(light.matrix_world.translation)
        spec_k = TableSpec(f"share map {k}", SHARE_MAP[0], SHARE_MAP[1])
        m.tables[spec_k.name] = cast(geometry.bvh, origin, vectors)[fill].astype(float)
        with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
            share = shafts.lit_share(m, samples.camera, samples.direction, length, np.array(origin),
                                     spec.beta_per_unit, (spec_k, None), SHARE_NODES, g=spec.anisotropy)
        lit[:, k] = np.nan_to_num(np.asarray(share, float), nan=1.0).clip(0.0, 1.0)
    n = len(judged)
    return [o.name for o in judged], predict.judged_shares(glow[:, :n] * (1.0 - lit[:, :n])[..., None],
                                                           (glow * lit[..., None] + scatter).sum(axis=1))
