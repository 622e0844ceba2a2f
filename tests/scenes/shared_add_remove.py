"""Add / remove / add the fog (operators and apply_fog, both methods, across save and reload); report the fog data after each step (JSON).

Usage: python shared_add_remove.py WORKDIR
"""
import json
import sys
import time

from shared_common import ROOT, copies, expected_names, fog_ids, fog_references  # noqa: F401  (puts ROOT on sys.path)

import bpy  # noqa: E402

import fog_addon  # noqa: E402
from demo_scenes import spheres  # noqa: E402
from fog_addon.ops import apply  # noqa: E402

steps = []
_t = [time.perf_counter()]


def record(label, method, texts_of=None):
    """``method``: what the file should now hold ("nodes", "osl"), None: nothing of the fog;
    ``texts_of``: the method whose OSL texts it holds (default ``method``)."""
    ids = fog_ids()
    count, suffixed = copies(ids)
    steps.append({
        "step": label,
        "seconds": round(time.perf_counter() - _t[0], 2),
        "expect": expected_names(method, bpy.context.scene, texts_of) if method else [],
        "names": sorted(n for names in ids.values() for n in names),
        "max_count": max(count.values(), default=0),
        "suffixed": suffixed,
        "suffixed_refs": [r for r in fog_references() if r[1][-4:-3] == "." and r[1][-3:].isdigit()],
    })
    _t[0] = time.perf_counter()


def with_ops(scene):
    settings = scene.analytic_fog
    settings.method = "NODES"   # (this checks copies of the node groups' data; Auto would pick the compositor)
    assert bpy.ops.fog.add(density=0.1) == {"FINISHED"}
    record("ops add", "nodes")
    assert bpy.ops.fog.remove() == {"FINISHED"}
    record("ops remove", None)
    assert bpy.ops.fog.add(density=0.1) == {"FINISHED"}
    record("ops add again", "nodes")
    assert bpy.ops.fog.add(density=0.2) == {"FINISHED"}
    record("ops add twice", "nodes")
    settings.method = "OSL"
    assert bpy.ops.fog.add() == {"FINISHED"}
    record("ops add osl", "osl")
    assert bpy.ops.fog.remove() == {"FINISHED"}
    record("ops remove osl", None)
    assert bpy.ops.fog.add() == {"FINISHED"}
    record("ops add osl again", "osl")
    settings.method = "NODES"
    assert bpy.ops.fog.add() == {"FINISHED"}
    record("ops add nodes after osl", "nodes", "osl")   # the nodes models' groups; the OSL texts stay, one copy


def with_apply(scene):
    apply.remove_fog(scene)
    record("apply remove", None)
    for k in range(3):
        apply.apply_fog(scene, 0.1)
        record(f"apply_fog {k}", "nodes")
        apply.remove_fog(scene)
        record(f"remove_fog {k}", None)
    apply.apply_fog(scene, 0.1)
    record("apply_fog final", "nodes")


def across_save(workdir):
    path = f"{workdir}/shared_add_remove.blend"
    bpy.ops.wm.save_as_mainfile(filepath=path)
    bpy.ops.wm.open_mainfile(filepath=path)
    record("reopened", "nodes")
    scene = bpy.context.scene
    apply.apply_fog(scene, 0.1)
    record("apply_fog after reopen", "nodes")
    apply.remove_fog(scene)
    apply.apply_fog(scene, 0.1)
    record("remove, apply_fog after reopen", "nodes")


def main():
    workdir = sys.argv[-1]
    bpy.ops.wm.read_factory_settings(use_empty=True)
    fog_addon.register()
    scene = bpy.context.scene
    spheres.build(scene)
    with_ops(scene)
    with_apply(scene)
    across_save(workdir)
    fog_addon.unregister()
    print(json.dumps({"steps": steps}))


if __name__ == "__main__":
    main()
