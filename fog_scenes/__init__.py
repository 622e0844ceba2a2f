"""Shared test scenes and the render-test harness: one importable place for tests/, benchmarks/ and tools/.

Not part of the add-on: blender_manifest.toml's ``[build]`` allow-list ships only ``__init__.py`` and
``fog_addon/``, so nothing here goes into the extension zip.

What lives here (every module but ``render_harness`` needs bpy):

* ``many_lights``      -- N point lights over a ground and three spheres, and its numpy twin per pixel;
                          also a script: ``python -m fog_scenes.many_lights OUT_DIR ENGINE METHOD N [SAMPLES]``.
* ``probe_common``     -- what the per-pixel probes share: the tiny render set-up, camera rays, fog-only lights.
* ``cycles_debug_log`` -- Cycles' SVM compilation summary from its debug log in a bpy process.
* ``render_harness``   -- run a Blender job in a fresh process, build demo scenes, cache path-traced
                          references (tests/references/), compare renders (no bpy at import).

How it is reached, without ``sys.path`` patches into tests/:

* tests: ``tests/conftest.py`` puts the repository root on ``sys.path`` once, so a test writes
  ``from fog_scenes import render_harness as h``.
* scripts run in a subprocess (tests/scenes/*.py, benchmarks/, tools/, started by
  ``render_harness.run``): it runs them from the repository root with the root on ``PYTHONPATH``.
  Run by hand by their path, they put the repository root on ``sys.path`` in their first lines (the one
  ``sys.path`` line they keep, as demo_scenes/ does); their own folder is on it already, so
  tests/scenes/*.py import their siblings (``farm_common``, ``shared_common``, ``add_remove``) directly.
* anything else: run from the repository root, ``python -m fog_scenes.many_lights ...`` or
  ``import fog_scenes``.

A module that more than one folder needs belongs here; a script or helper used by one test file stays
in tests/scenes/.
"""
