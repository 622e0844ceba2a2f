"""Daylight: a fog layer with a top, the sun and the sky through it.  The layer's kernels (``daylight``), the clear
air's haze (``aerial``), their tables (``daylight_tables``), what a pixel gets from the sun and the sky
(``sunlight``) and the sun's light shafts (``sun_shafts``).
"""
