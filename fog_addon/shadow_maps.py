"""Shadow maps of the lights whose shadows fall in the fog: the visibility source of light shafts.

For each such light (``caveats.shadowing_lights``: an object casting shadows within its glow's reach) the
distance from the light to the first surface is ray cast in every direction of its map
(``precompute/shafts.py``: a longitude-latitude grid for a point light, its rows thinned towards the poles to
the equator's spacing, ``point_map_casts``; a square grid over the cone for a spot) against one BVH of the
scene's shadow casters (``mathutils.bvhtree``, evaluated meshes in world space: modifiers, instances and curves
included), and stored as a packed float image, so the saved file renders without the add-on (the compositor
reads it with Map UV).  The map holds the light's pose and the geometry of the frame it was baked at
(``ShadowMap.key``): when either changes, the map is baked again (the frame handler, ``render``); a farm
rendering an animation whose lights or occluders move needs the add-on (``animated_note``).

Objects that Cycles lets shadow rays through (hidden from shadow rays, not rendered) cast none here; every
other surface is opaque (glass included, as Cycles' shadow rays treat it).
"""
import functools
import gc
import hashlib
import itertools
import math
from typing import NamedTuple

import bpy
import numpy as np
from mathutils import Vector
from mathutils.bvhtree import BVHTree

from . import caveats
from .nodes import owned
from .precompute import footprint, shafts
from .precompute.tables import TableSpec

IMAGE_PREFIX = f"{owned.PREFIX} Shadow "   # a light's map: "<IMAGE_PREFIX><light name>"
KEY = "analytic_fog_shadow_key"            # on the image: what the map was baked from (``ShadowMap.key``)


class ShadowMap(NamedTuple):
    """A light's baked map: ``spec`` (its image's name and grid), ``spot``: (frame, half_width) of a spot's
    map (``spot_map``) or None for a point light's."""
    spec: TableSpec
    spot: tuple


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


@functools.lru_cache(maxsize=1)
def _point_casts():
    """(the rays of a point light's map as mathutils Vectors, the ray each grid point takes): ``shafts.point_map_casts``
    (every point light's map shares them)."""
    directions, fill = shafts.point_map_casts()
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
    triangle, NO_HIT if none (a sun's map: ``shafts.SunFrame``)."""
    return _first_hits(bvh, _vectors(origins), itertools.repeat(Vector(tuple(direction)), len(origins)), len(origins))


def _first_hits(bvh, origins, directions, count):
    """(count,) float32: the distance along each ray (``origins`` and unit ``directions``: iterables of mathutils
    Vectors) to the first triangle of ``bvh``, NO_HIT where none (or no BVH).  The rays go through ``map``, not a
    Python loop: most of a map's time is the interpreter's, not the BVH's."""
    if bvh is None:
        return np.full(count, shafts.NO_HIT, np.float32)
    hits = map(bvh.ray_cast, origins, directions)
    return np.fromiter((shafts.NO_HIT if hit[0] is None else hit[3] for hit in hits), np.float32, count)


class SunShadow(NamedTuple):
    """A sun's baked map: ``spec`` (its image's name and grid) and ``frame`` (``shafts.SunFrame``: where it lies)."""
    spec: TableSpec
    frame: shafts.SunFrame


SUN_IMAGE = f"{owned.PREFIX} Sun Shadow"   # the sun's map (one sun shines through a fog layer)


def sun_shadow(scene, sun, region):
    """The ``SunShadow`` of Sun light ``sun`` over ``region`` (world corners of the fog the camera sees, (N, 3)),
    baked unless its image holds this sun, region and geometry; None if no caster's shadow can fall there.  The
    casters that stand no higher than the region's bottom (the ground: a ground plane) are left out: they shadow no
    fog above them, and in the map a low sun would see fog just above them as behind them (a cell's depth on the
    ground changes by a cell over the sun's elevation tangent, several cells at a low sun)."""
    casters = caveats.shadow_casters(scene)
    if not casters:
        return None
    corners = np.array([footprint.box_points(o.bound_box, o.matrix_world) for o in casters])
    ground = float(np.min(np.asarray(region)[:, 2]))
    keep = corners[:, :, 2].max(axis=1) > ground + 1e-6
    if not keep.any():
        return None
    direction = tuple(float(c) for c in sun.matrix_world.to_3x3().col[2].normalized())
    placed = shafts.sun_frame(direction, region, corners[keep].reshape(-1, 3))
    if placed is None:
        return None
    frame, (width, height) = placed
    geometry = scene_bvh(scene, objects=[o for o, k in zip(casters, keep) if k])
    version = hashlib.sha1(repr((frame, width, height, geometry.digest)).encode()).hexdigest()
    spec = TableSpec(SUN_IMAGE, width, height)
    img = bpy.data.images.get(SUN_IMAGE)
    if img is None or img.get(KEY) != version or img.packed_file is None:
        origins = shafts.sun_map_origins(frame, width, height).reshape(-1, 3)
        depth = cast_parallel(geometry.bvh, origins, frame.forward).reshape(height, width)
        _store(spec, depth, version)
    return SunShadow(spec, frame)


def _is_spot(light):
    return light.data.type == "SPOT" and light.data.spot_size < math.radians(179.0)


def bake(light, geometry):
    """(ShadowMap, depths (rows, columns) float32) of ``light`` against ``geometry`` (``scene_bvh``)."""
    origin = tuple(light.matrix_world.translation)
    spot = spot_map(light)
    if spot is not None:
        dirs = shafts.spot_map_directions(*spot)
        depth = cast(geometry.bvh, origin, dirs.reshape(-1, 3)).reshape(dirs.shape[:2])
    else:
        vectors, fill = _point_casts()
        depth = cast(geometry.bvh, origin, vectors)[fill]
    spec = TableSpec(IMAGE_PREFIX + light.name, depth.shape[1], depth.shape[0])
    return ShadowMap(spec, spot), depth


def spot_map(light):
    """(frame, half_width) of a spot's map at the light's pose (``shafts.spot_frame``, ``spot_half_width``),
    None for a point light (or a spot of 179 degrees or more, mapped as one)."""
    if not _is_spot(light):
        return None
    frame = shafts.spot_frame(np.asarray(light.matrix_world)[:3, :3])
    return (tuple(tuple(float(c) for c in v) for v in frame),
            shafts.spot_half_width(math.cos(0.5 * light.data.spot_size)))


def key(light, geometry):
    """What a light's map depends on: its pose, its cone and the casters' geometry."""
    m = tuple(round(v, 6) for row in light.matrix_world for v in row)
    cone = round(light.data.spot_size, 6) if _is_spot(light) else None
    return hashlib.sha1(repr((m, cone, geometry.digest)).encode()).hexdigest()


def _store(spec, depth, version):
    img = bpy.data.images.get(spec.name)
    if img is not None and tuple(img.size) != (spec.width, spec.height):
        bpy.data.images.remove(img)
        img = None
    if img is None:
        img = bpy.data.images.new(spec.name, spec.width, spec.height, alpha=True, float_buffer=True, is_data=True)
        img.colorspace_settings.name = "Non-Color"
        img.alpha_mode = "CHANNEL_PACKED"
        img.use_half_precision = False
    img.pixels.foreach_set(np.repeat(np.asarray(depth, np.float32)[..., None], 4, axis=-1).ravel())
    img.update()
    img.pack()
    img.use_fake_user = True
    img[KEY] = version
    return img


def ensure(scene, lights, geometry=None):
    """{light name: ShadowMap} of ``lights``, each baked unless its image holds this pose and geometry;
    returns (maps, images by spec name)."""
    if not lights:
        return {}, {}
    geometry = geometry or scene_bvh(scene)
    maps, images = {}, {}
    for light in lights:
        version = key(light, geometry)
        name = IMAGE_PREFIX + light.name
        img = bpy.data.images.get(name)
        if img is not None and img.get(KEY) == version and img.packed_file is not None:
            shadow = describe(light, img)
        else:
            shadow, depth = bake(light, geometry)
            img = _store(shadow.spec, depth, version)
        maps[light.name], images[shadow.spec.name] = shadow, img
    return maps, images


def describe(light, img):
    """The ShadowMap of an image baked for ``light`` (its grid from the image, its frame from the light)."""
    return ShadowMap(TableSpec(img.name, img.size[0], img.size[1]), spot_map(light))


def remove_unused(keep=()):
    """Remove the shadow maps of lights no longer shafted (names not in ``keep``; the sun's SUN_IMAGE too unless
    kept)."""
    for img in list(bpy.data.images):
        if (img.name.startswith(IMAGE_PREFIX) or img.name == SUN_IMAGE) and img.name not in keep:
            bpy.data.images.remove(img)
