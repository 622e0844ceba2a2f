"""Spot lights in fog: the glow of Blender's cone and blend (``spot``), its multiply scattered part
(``spot_multiple``) and the photon walk that bakes that table (``spot_walk``).
"""
