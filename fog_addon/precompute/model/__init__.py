"""The phenomena put together into a pixel's fog: the models as data and the chooser of each light's models
(``rungs``), the shading of a point (``shading``) and the composer of a pixel's terms (``compose``), the error
predictor behind the Quality (``predict``), the Compositor method's per-pixel formulas and windows (``pixel``,
``footprint``), and the one table of what each method models in each engine (``capabilities``).
"""
