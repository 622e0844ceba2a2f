"""The phenomena, one package each: the kernels of a kind of light in fog (written once against the ops of
``core/ops.py``), the tables they read and how those are baked.  ``point/`` is the base the others build on
(Sun et al. 2005's glow of a point light, ``point/model.py``); ``spot/``, ``area/``, ``emitter/``, ``daylight/`` and
``shafts/`` each add their own.
"""
