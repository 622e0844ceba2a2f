"""Area lights in fog: the glow of Blender's square, rectangle, disk and ellipse emitters (``area``).
"""
