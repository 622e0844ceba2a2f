"""Fold duplicated fog data-blocks back onto the one shared copy.

Appending (``bpy.ops.wm.append`` or ``bpy.data.libraries.load(link=False)``)
an object whose material is fogged, from another fogged file, brings that
file's copies of the fog's data along under suffixed names: the material's
``AnalyticFog Surface`` arrives as ``AnalyticFog Surface.001`` with its
``AnalyticFog Light.001`` and ``AnalyticFog Params.001`` (the other file's
density and lights), the tables as ``AnalyticFog Airlight N.001`` /
``AnalyticFog Surface M.001``, with the OSL method also
``AnalyticFog Airlight.osl.001``; appending a World adds ``AnalyticFog
World.001`` and ``AnalyticFog Background Light.001``.  ``apply_fog`` leaves
them in place (an already fogged material is not rewrapped), so the appended
material would keep the other file's fog and lights.

The duplicated Surface and World groups also drag in their driver targets:
the other file's point lights (object and light data) and camera.
``wm.append`` instantiates them into the active collection, so they light
the scene; ``libraries.load`` leaves them as objects with no users (dropped
on save).  :func:`merge_duplicates` reports them as *pulled* objects (the
dropped duplicates' driver targets that none of the kept groups drives from)
and removes them only when asked.

Call it first thing in ``apply_fog`` (before the tables and groups are
looked up by name), from a ``load_post`` handler, and after appends (a
``depsgraph_update_post`` handler; do the merge from a ``bpy.app.timers``
callback it registers rather than inside the depsgraph callback itself).
"""
import bpy

from . import groups, images, osl, owned



def _shared():
    """(bpy.data collection name, canonical names, is-ours test) of every shared fog data-block."""
    return (
        ("node_groups", tuple(groups.all_group_names()), lambda ng: bool(ng.get(groups.FOG_PROP))),
        ("images", tuple(images.table_names()), lambda img: images.VERSION_KEY in img),
        ("texts", tuple(osl.text_names()), lambda text: text.as_string().startswith(osl.HEADER)),
    )


def _driver_targets(idblock):
    """Objects and other IDs ``idblock``'s drivers read from."""
    ad = getattr(idblock, "animation_data", None)
    if ad is None:
        return set()
    return {t.id for fc in ad.drivers for v in fc.driver.variables for t in v.targets if t.id is not None}


def _only_in_collections(obj):
    """Nothing but collections (the append's instantiation) uses ``obj``."""
    return obj.users == len(obj.users_collection) + (1 if obj.use_fake_user else 0)


def pending():
    """True if some fog node group, table image or OSL text has a suffixed copy (cheap: names only)."""
    return any(owned.SUFFIX.match(idb.name) and idb.name.startswith(owned.PREFIX)
               for coll_name, _, _ in _shared() for idb in getattr(bpy.data, coll_name))


def merge_duplicates(remove_pulled=False):
    """Remap every local ``AnalyticFog X.NNN`` group, table image and OSL text onto ``AnalyticFog X`` and delete it.

    Where ``AnalyticFog X`` itself is missing, the lowest-numbered copy is
    renamed to it instead.  Linked (library) data is left alone.  Only the
    fog's own data-blocks are touched (the group marker, the table version
    key, the shader's header).

    ``remove_pulled``: also delete the *pulled* objects (see the module
    docstring) that nothing but collections uses any more, with their data
    if that is left without users.  This cannot tell a lamp that came only
    through the drivers from one appended on purpose in the same append
    (say, in a collection), so it is off by default.

    Returns ``(merged, pulled)``: names of the deleted duplicates (as they
    were), names of the pulled objects (deleted or not).
    """
    merged, doomed, kept = [], [], []
    for coll_name, bases, ours in _shared():
        coll = getattr(bpy.data, coll_name)
        found = {}
        for idb in coll:
            m = owned.SUFFIX.match(idb.name)
            if m and m["base"] in bases and idb.library is None and ours(idb):
                found.setdefault(m["base"], []).append((int(m["num"]), idb))
        for base in bases:
            keep = coll.get((base, None))
            dups = [idb for _, idb in sorted(found.get(base, ()), key=lambda t: t[0])]
            if keep is None and dups:
                keep = dups.pop(0)
                keep.name = base
            if keep is not None:
                kept.append(keep)
            for dup in dups:
                merged.append(dup.name)
                dup.user_remap(keep)
                doomed.append(dup)
    if not doomed:
        return merged, []
    pulled_ids = set().union(*(_driver_targets(d) for d in doomed)) - set().union(*(_driver_targets(k) for k in kept))
    pulled = sorted((o for o in pulled_ids if isinstance(o, bpy.types.Object)), key=lambda o: o.name)
    pulled_names = [o.name for o in pulled]
    bpy.data.batch_remove(doomed)
    if remove_pulled:
        for obj in pulled:
            if not _only_in_collections(obj):
                continue
            data = obj.data
            bpy.data.objects.remove(obj)
            if data is not None and data.users == 0:
                bpy.data.batch_remove([data])
    return merged, pulled_names
