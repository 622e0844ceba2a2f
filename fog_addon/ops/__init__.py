"""The ops layer: what the operators, the handlers, the command line and scripts call (``apply`` and the modules it
hands on: ``plan``, ``build``, ``sync``, ``report``), the operators themselves (``operators``), and the progress of
long work (``progress``, ``bake_job``: no Blender, so the numpy tests import them without it)."""
