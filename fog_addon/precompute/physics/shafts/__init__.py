"""Light shafts: the shadow maps' geometry and lookups (``shaft_maps``) and the share of a light's glow along a
camera ray that the light reaches (``shafts``).
"""
