"""Analytic Fog as a Blender extension.

The repository root is the extension's root package: Blender reads
``blender_manifest.toml`` beside this file and imports this package (as
``bl_ext.<repo>.analytic_fog``); the add-on itself is ``fog_addon/``.
"""
from .fog_addon import register, unregister

__all__ = ["register", "unregister"]
