"""What every part of ``precompute/`` stands on or reaches through: the ops namespace the kernels are written
against (``ops``), the fog's settings as one value (``spec``), the medium and its presets (``medium``,
``presets``), the table layouts (``tables``), the one registry of table kinds and the bakers that go through it
(``registry``, ``bakers``), the on-disk table cache and the source fingerprint it is keyed by (``table_cache``,
``fingerprint``).
"""
