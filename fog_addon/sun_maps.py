"""The sun's shadow map: where the sun's shafts in a fog layer come from
(``precompute/physics/daylight/sun_shafts.py``).

The map is a plane of parallel rays along the sunlight over the box of layer the camera sees (``region_of``:
``sunsky.shaft_region``), each grid point the distance to the first shadow caster (``shadow_maps.cast_parallel``),
stored as a packed float image (``shadow_maps.pack_map``) so the saved file renders without the add-on.

**Animations.**  Where the camera or a shadow caster moves and the sun does not (``moves``), the image is an atlas
of the maps at every frame an animation renders (``shadow_maps.frames_of``; the lamps' atlas layout,
``shadow_maps.store_atlas``), all in one frame that covers every frame's region (``sun_shafts.sun_frame`` over the
union of the regions and the casters of all frames), SUN_ANIMATED_MAP grid points along its longer side.  Frames
whose casters and map are the same share one cast (a camera that moves over still buildings: one map).  The
compositor picks the frame's map with the lamps' simple-expression driver (``comp_shafts.atlas_tile``), so a farm
without the add-on renders each frame's shafts.

A rebuild from a handler (``lazy``) does not step through the frames: it takes an atlas laid out for this range as
it is, or else bakes this frame's still map and marks the image STALE.  A frame change bakes the frame's map into
the atlas again where the casters changed since (``follow_frame``: the animation was edited; STALE too), and the
file's save rebuilds the fog where an atlas is due (``atlas_due``), so the saved file holds every frame's map.

An animated sun keeps one map, as its daylight keeps one direction (``report.daylight_notes`` says so).
"""
import hashlib
import json
from typing import NamedTuple

import bpy
import numpy as np

from . import caveats, view
from .precompute.model import footprint
from .precompute.physics.daylight import sun_shafts
from .precompute.core.tables import TableSpec
from .shadow_maps import (ATLAS, KEY, LAYOUT, STALE, SUN_IMAGE, TILE_KEYS, Atlas, atlas_tiles, cast_parallel,
                          frames_of, map_image, pack_map, scene_bvh, store_atlas, write_tile)

SUN_TILE = "AnalyticFog Sun Shadow Frame"   # the table name the kernels read an atlas's tile of the frame under


class SunShadow(NamedTuple):
    """A sun's baked map: ``spec`` (the table the kernels read: the image's name and grid, or SUN_TILE and one
    tile's grid for an atlas), ``frame`` (``sun_shafts.SunFrame``: where it lies) and ``atlas`` (``shadow_maps.Atlas``
    of an animation's maps, else None)."""
    spec: TableSpec
    frame: sun_shafts.SunFrame
    atlas: Atlas = None


def direction_to(sun):
    """The unit world vector towards Sun light ``sun`` (its local +Z)."""
    return tuple(float(c) for c in sun.matrix_world.to_3x3().col[2].normalized())


def moves(scene, sun):
    """True if the sun's map changes over the animation while the sun stands still: more than one frame renders
    and the camera (the region) or a shadow caster is animated (``caveats.is_animated``)."""
    if frames_of(scene)[2] < 2 or caveats.is_animated(sun):
        return False
    return any(o is not None and caveats.is_animated(o) for o in [scene.camera, *caveats.shadow_casters(scene)])


def _casters(scene, region):
    """(the shadow casters that stand higher than ``region``'s bottom, their world corners (K, 8, 3)): the ground
    and what lies on it shadow no fog above them, and in the map a low sun would see fog just above them as behind
    them (a cell's depth on the ground changes by a cell over the sun's elevation tangent)."""
    casters = caveats.shadow_casters(scene)
    if not casters:
        return [], np.zeros((0, 8, 3))
    corners = np.array([footprint.box_points(o.bound_box, o.matrix_world) for o in casters])
    keep = corners[:, :, 2].max(axis=1) > float(np.min(np.asarray(region)[:, 2])) + 1e-6
    return [o for o, k in zip(casters, keep) if k], corners[keep]


def _cast(frame, size, geometry):
    """(height, width) float32: the map of ``frame`` (``sun_shafts.SunFrame``) of ``size`` grid points against
    ``geometry`` (``shadow_maps.scene_bvh``)."""
    width, height = size
    origins = sun_shafts.sun_map_origins(frame, width, height).reshape(-1, 3)
    return cast_parallel(geometry.bvh, origins, frame.forward).reshape(height, width)


def shadow(scene, sun, region_of, lazy=False):
    """The ``SunShadow`` of Sun light ``sun`` over ``region_of(scene)`` (the world corners of the fog the camera
    sees at the scene's frame, (N, 3)), baked unless its image holds it; None if no caster's shadow falls there.
    An atlas of every frame's where the map ``moves``; ``lazy``: see the module's docstring."""
    if not moves(scene, sun):
        return _still(scene, sun, region_of(scene))
    img = bpy.data.images.get(SUN_IMAGE)
    if lazy:
        if _laid_out(img, frames_of(scene)):
            return described(img)
        still = _still(scene, sun, region_of(scene))
        if still is not None:
            bpy.data.images[SUN_IMAGE][STALE] = True   # an atlas is due (``atlas_due``)
        return still
    return _atlas(scene, sun, region_of, frames_of(scene))


def _still(scene, sun, region):
    """The ``SunShadow`` of one map over ``region`` at the scene's frame (SUN_MAP grid points along its longer
    side), baked unless the image holds this sun, region and geometry."""
    casters, corners = _casters(scene, region)
    if not casters:
        return None
    placed = sun_shafts.sun_frame(direction_to(sun), region, corners.reshape(-1, 3))
    if placed is None:
        return None
    frame, size = placed
    geometry = scene_bvh(scene, objects=casters)
    version = hashlib.sha1(repr((frame, size, geometry.digest)).encode()).hexdigest()
    spec = TableSpec(SUN_IMAGE, *size)
    img = bpy.data.images.get(SUN_IMAGE)
    if img is None or img.get(KEY) != version or img.packed_file is None or ATLAS in img:
        img = map_image(SUN_IMAGE, *size, atlas=False)
        pack_map(img, np.repeat(_cast(frame, size, geometry)[..., None], 4, axis=-1))
        img[KEY] = version
        if STALE in img:
            del img[STALE]
    return SunShadow(spec, frame)


def _layout(frames, frame, size):
    """What an atlas is laid out for, as JSON: its frames, one map's grid and the map's ``SunFrame``."""
    return json.dumps([list(frames), list(size), [list(v) if isinstance(v, tuple) else v for v in frame]])


def _laid_out(img, frames):
    """True if ``img`` is a packed atlas laid out for ``frames``."""
    return (img is not None and ATLAS in img and LAYOUT in img and img.packed_file is not None
            and json.loads(img[LAYOUT])[0] == list(frames))


def described(img):
    """The ``SunShadow`` of an atlas image (its layout read from the image)."""
    _, size, fields = json.loads(img[LAYOUT])
    frame = sun_shafts.SunFrame(*(tuple(v) if isinstance(v, list) else v for v in fields))
    return SunShadow(TableSpec(SUN_TILE, *size), frame, Atlas(*(int(v) for v in img[ATLAS])))


def _atlas(scene, sun, region_of, frames):
    """The ``SunShadow`` of an atlas of the map at every one of ``frames``: the scene stepped through them once for
    the regions and casters (their union places the map: ``sun_shafts.sun_frame`` at SUN_ANIMATED_MAP), then again
    to cast each frame's map where its key (the layout and the casters' geometry) differs from the atlas's; frames
    with the same key share one cast."""
    first, stride, count = frames
    frame_list = [first + stride * t for t in range(count)]
    regions, corners, kept = [], [], []
    for _ in view.at_frames(scene, frame_list):
        region = region_of(scene)
        casters, c = _casters(scene, region)
        regions.append(region)
        corners.append(c.reshape(-1, 3))
        kept.append(casters)
    if not any(kept):
        return None
    placed = sun_shafts.sun_frame(direction_to(sun), np.concatenate(regions), np.concatenate(corners),
                                  size=sun_shafts.SUN_ANIMATED_MAP)
    if placed is None:
        return None
    frame, size = placed
    layout = _layout(frames, frame, size)
    img = bpy.data.images.get(SUN_IMAGE)
    same = img is not None and img.get(LAYOUT) == layout and img.packed_file is not None
    keys = list(img[TILE_KEYS]) if same else [""] * count
    tiles = atlas_tiles(img) if same else [None] * count
    changed = not same or bool(img.get(STALE))
    cast = {}   # key: map (frames whose casters did not change share it)
    for t, (_, depsgraph) in enumerate(view.at_frames(scene, frame_list)):
        geometry = scene_bvh(scene, depsgraph, objects=kept[t])
        version = hashlib.sha1((layout + geometry.digest).encode()).hexdigest()
        if keys[t] == version and tiles[t] is not None:
            cast.setdefault(version, tiles[t])
            continue
        if version not in cast:
            cast[version] = _cast(frame, size, geometry)
        tiles[t], keys[t], changed = cast[version], version, True
    if changed:
        img, atlas = store_atlas(SUN_IMAGE, tiles, frames, size, layout, keys)
    else:
        atlas = Atlas(*(int(v) for v in img[ATLAS]))
    return SunShadow(TableSpec(SUN_TILE, *size), frame, atlas)


def follow_frame(scene, sun, region_of):
    """The frame changed (the add-on's frame handler): the atlas's map of this frame is cast again where the
    casters changed since it was baked (its key), into the atlas's frame, so the add-on renders what the scene holds
    now; the atlas is then STALE (``atlas_due``: the file's save bakes the range again).  True if it changed."""
    img = bpy.data.images.get(SUN_IMAGE)
    if img is None or ATLAS not in img or LAYOUT not in img:
        return False
    first, stride, tiles, *_ = (int(v) for v in img[ATLAS])
    keys = list(img[TILE_KEYS])
    t, off = divmod(scene.frame_current - first, stride)
    if json.loads(img[LAYOUT])[0] != list(frames_of(scene)):
        img[STALE] = True
    if off or not 0 <= t < len(keys):
        return False
    shadow_ = described(img)
    region = region_of(scene)
    casters, corners = _casters(scene, region)
    if not _covers(shadow_.frame, sun, region, corners):
        img[STALE] = True   # the camera's or the casters' animation changed: the atlas is laid out again at saving
    geometry = scene_bvh(scene, objects=casters)
    version = hashlib.sha1((img[LAYOUT] + geometry.digest).encode()).hexdigest()
    if keys[t] == version:
        return False
    if tiles == 1:   # the one map every frame shared: now this frame's, the others to be cast again
        keys = [""] * len(keys)
    write_tile(img, t if tiles > 1 else 0, _cast(shadow_.frame, (shadow_.spec.width, shadow_.spec.height), geometry))
    keys[t] = version
    img[TILE_KEYS], img[STALE] = keys, True
    return True


def _covers(frame, sun, region, corners):
    """True if the atlas's ``frame`` (``sun_shafts.SunFrame``) holds the map this frame's ``region`` and casters'
    ``corners`` need (``sun_shafts.sun_frame``'s rectangle, within a cell), for the sun's direction."""
    if not len(corners):
        return True
    placed = sun_shafts.sun_frame(direction_to(sun), region, corners.reshape(-1, 3))
    if placed is None:
        return True
    need, cell = placed[0], frame.bias / sun_shafts.SUN_BIAS_CELLS
    return (need.a[0] >= frame.a[0] - cell and need.a[1] <= frame.a[1] + cell and need.b[0] >= frame.b[0] - cell
            and need.b[1] <= frame.b[1] + cell and np.allclose(need.forward, frame.forward, atol=1e-6))


def atlas_due(scene, sun):
    """True if the sun's map should be an atlas of the animation's frames and is not one laid out for them, up to
    date (``moves``; a handler's rebuild or a frame change left it STALE)."""
    img = bpy.data.images.get(SUN_IMAGE)
    if img is None or sun is None or not moves(scene, sun):
        return False
    return bool(img.get(STALE)) or not _laid_out(img, frames_of(scene))
