"""Spheres (Sun et al. 2005, Figs. 11-12): a diffuse sphere and a glossy sphere
lit by one point lamp in fog; no ground.

The lamp hangs between and above the spheres, in frame; the camera is 7 m
away.  At the default test density beta = 0.15 1/m the optical thickness from
the camera to the spheres is about 1.0 (to the lamp 1.1).

    python demo_scenes/spheres.py OUT.blend
"""
import os
import sys

if __name__ == "__main__":
    sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from demo_scenes import add_camera, add_point_light, add_sphere, main, material, render_settings, set_world

SPHERE_RADIUS = 1.0              # m
DIFFUSE_CENTER = (-1.4, 0.0, 0.0)
GLOSSY_CENTER = (1.4, 0.0, 0.0)
LAMP_LOCATION = (0.0, -1.0, 1.6)
LAMP_POWER = 600.0               # W
CAMERA_LOCATION = (0.0, -7.0, 0.6)
CAMERA_TARGET = (0.0, 0.0, 0.3)
DEFAULT_DENSITY = 0.15           # 1/m


def build(scene):
    render_settings(scene)
    set_world(scene)
    # Pure Lambertian: Principled with no specular layer.
    diffuse = material("Diffuse", (0.8, 0.8, 0.8), roughness=1.0, specular_ior_level=0.0)
    # Plastic: Lambertian base + GGX specular (IOR 1.5) of roughness 0.3.
    glossy = material("Glossy", (0.8, 0.25, 0.15), roughness=0.3, specular_ior_level=0.5)
    add_sphere(scene, "Diffuse Sphere", DIFFUSE_CENTER, SPHERE_RADIUS, diffuse)
    add_sphere(scene, "Glossy Sphere", GLOSSY_CENTER, SPHERE_RADIUS, glossy)
    add_point_light(scene, "Lamp", LAMP_LOCATION, LAMP_POWER)
    add_camera(scene, CAMERA_LOCATION, CAMERA_TARGET, lens=35.0)
    return scene


if __name__ == "__main__":
    sys.exit(main(build))
