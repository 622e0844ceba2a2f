"""Everything the fog computes without Blender: pure numpy, importable without bpy, tested in milliseconds.

``core/`` holds what every part reads (the ops namespace, the settings, the medium, the table layouts, their
registry, bakers and on-disk cache); ``physics/`` one package a phenomenon (point, spot and area lights, glowing
objects, daylight, light shafts), each with its kernels and the tables they read; ``model/`` puts them together
into a pixel's fog (the models as data, the shading and the composer, the predictor of the Quality, the
Compositor's per-pixel formulas and windows, what each method can do).
"""
