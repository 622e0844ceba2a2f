"""The method interface: how the fog's light reaches the picture.

A method is one unit behind one interface (``Method``).  ``ops/`` runs every method the same way:

    spec (``precompute/core/spec.FogSpec``) -> lights -> method (``methods.resolve``: Auto picks one) ->
    ``method.check`` -> plan (``ops/plan.plan``: each light's models for the Quality within ``method.budget``)
    -> ``method.build`` -> ``method.passes`` (the view layers' AOVs) -> ``method.follow`` (the compositor)

and calls ``method.frame_change`` on each frame of an animation and ``method.teardown`` when the fog or
the method goes.  The methods:

* ``NodeGroups`` (``node_groups.py``): every fogged material and the World evaluate every light's terms
  on every sample, with the node groups' tables (Cycles and EEVEE);
* ``Osl`` (``node_groups.py``): the node groups with the glow by quadrature in an OSL script (Cycles);
* ``Compositor`` (``compositor.py``): the materials keep only what depends on each sample's depth, and
  the compositor adds the fog's light once per pixel (``nodes/comp_fog.py``).
"""
from ..nodes import compositor


class Method:
    """One way of putting the fog's light into the picture; subclasses fill in the hooks."""
    name = ""                        # the spec's method ("nodes", "osl", "compositor")
    label = ""                       # the panel's name of it
    preference = "nodes"             # the models' preference (``rungs.choose``)
    engines = ("CYCLES", "BLENDER_EEVEE")

    def check(self, scene, spec):
        """Why this method can't serve ``scene`` with ``spec`` (a sentence a user understands), or None."""
        if scene.render.engine not in self.engines:
            names = " or ".join({"CYCLES": "Cycles", "BLENDER_EEVEE": "EEVEE"}[e] for e in self.engines)
            return f"the {self.label} method needs {names}, not {scene.render.engine}"
        return None

    def budget(self, scene, spec, lights):
        """What the renderer can hold with ``lights`` (``predict.Budget``), or None: no limit."""
        return None

    def preview_budget(self, scene, spec, lights):
        """What the viewport's preview of a fog added at render time may hold (``predict.Budget`` of the ladder's
        steps: ``nodes/preview.py``), or None: the method's shaders are what the viewport shows."""
        return None

    def shader_lights(self, scene, spec, lights, models):
        """(lights, models) the materials' and World's groups hold."""
        return lights, models

    def signature(self, scene, spec, shader_lights):
        """What, besides the lights' models, the camera and the passes, the built groups depend on."""
        return ""

    def windows(self, scene, lights, partial):
        """Where the method evaluates each term (``view.windows``), or None."""
        return None

    def is_built(self):
        """True if everything this method builds besides the Surface and World groups is there."""
        return True

    def build(self, scene, spec, plan, images):
        """Build the scene groups of ``plan`` (``ops/plan.Plan``); returns the table images in use."""
        raise NotImplementedError

    def update(self, scene, spec, plan):
        """The groups are built for ``plan`` already: set what changes without a rebuild."""

    def passes(self, scene, spec):
        """The AOVs (name, kind) the view layers need."""
        return ()

    def notes(self, scene, spec, plan):
        """[(name, note)] worth telling the user about this method on this scene."""
        return []

    def frame_change(self, scene, spec, lights):
        """A frame of an animation plays or renders; ``lights``: those the fog's groups hold; ``spec``: the scene's
        settings, None while they can't be used (the fog keeps what it was built with)."""

    def follow(self, scene, rebuild):
        """The scene's compositor set-up as this method needs it; returns [(name, note)]."""
        return compositor.follow(scene, rebuild, None)

    def teardown(self, scene):
        """Take off what only this method made (the fog's shared groups are ``ops/apply.remove_fog``'s)."""

    def __repr__(self):
        return f"<{type(self).__name__} {self.name}>"
