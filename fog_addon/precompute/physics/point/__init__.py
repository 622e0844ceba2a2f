"""Point lights in fog: Sun et al. 2005's single-scattered glow (``model``: the per-pixel formulas every other
light builds on; ``airlight``: its table), the fog light a surface reflects (``surface``), and the multiply
scattered glow of Dense Fog (``multiple``) with the Monte Carlo transport it is baked from (``point_source_mc``).
"""
