"""The fog's settings, stored on the scene (``scene.analytic_fog``)."""
import bpy

from .precompute import presets


def _update(self, context):
    """Push a changed setting into the shared params group, if the fog is on."""
    from .nodes import groups
    if self.enabled and bpy.data.node_groups.get(groups.PARAMS) is not None:
        groups.set_params(self.density, tuple(self.color))


class AnalyticFogSettings(bpy.types.PropertyGroup):
    enabled: bpy.props.BoolProperty(name="Enabled", default=False,
                                    description="The fog is applied to this scene (set by Add/Remove Fog)")
    density: bpy.props.FloatProperty(
        name="Density", default=presets.PRESETS["fog"], min=0.0, soft_max=1.0, max=100.0, precision=5,
        unit="NONE", update=_update,
        description="Extinction coefficient beta in 1/m (= scattering coefficient). "
                    "Visibility V = 3.912 / beta (Koschmieder)")
    color: bpy.props.FloatVectorProperty(
        name="Color", subtype="COLOR", size=3, default=(1.0, 1.0, 1.0), min=0.0, max=1.0, update=_update,
        description="Single-scattering albedo of the fog: the fraction of extinguished light it scatters")
    anisotropy: bpy.props.FloatProperty(
        name="Anisotropy", default=0.0, min=0.0, max=0.0,
        description="Henyey-Greenstein g of the fog's phase function (only isotropic fog, 0, so far)")
    method: bpy.props.EnumProperty(
        name="Method", default="NODES",
        items=[("NODES", "Node Groups", "Shader node groups with packed tables: Cycles and EEVEE"),
               ("OSL", "OSL", "Airlight by quadrature in an OSL script: Cycles only (switches Cycles' OSL on)")],
        description="How the fog is evaluated")


def register():
    bpy.utils.register_class(AnalyticFogSettings)
    bpy.types.Scene.analytic_fog = bpy.props.PointerProperty(type=AnalyticFogSettings)


def unregister():
    del bpy.types.Scene.analytic_fog
    bpy.utils.unregister_class(AnalyticFogSettings)
