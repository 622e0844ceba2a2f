"""Glowing objects (emissive surfaces): their glows as a sum of Gaussian blurs (``emitter_glow``) and the layouts,
names and bake times of the tables of weights those read (``emitter_table``).
"""
