"""Mutation check: remove each physical term of the fog in turn and make sure some test fails.

    .venv/bin/python tools/mutations.py [--list] [--markdown] [--update-readme] [--json] [--baseline]
                                        [--rev REV] [--keep] [--quick | --rest] [NAME ...]

Each mutation is data (``MUTATIONS``): a name, what it breaks, the symbol
that holds the term, the exact text it replaces there, the new text and the
test node ids that should kill it, cheapest first.

A mutation names its place by symbol, not by file, so moving code between
modules leaves the list alone: ``target`` is a def, a class or a constant (a
name assigned at module or class level) looked up by ``ast`` across every
``.py`` file under fog_addon/, wherever it is defined (``find_symbol``).  It
is a dotted suffix of the definition's full name: ``shade_point``,
``NodeOps.place``, ``_quadrature.nodes`` (a def inside a def), or, when a bare
name is defined in several places, ``shading.view_transmittance`` or the
whole ``fog_addon.precompute.model.shading.view_transmittance``; it must match
exactly one definition.  The old text must occur exactly once within that
definition's lines (``ast``'s lineno to end_lineno, decorators included), or
the tool refuses, naming the symbol and the lines it searched, so the list
cannot go stale silently.  Old and new texts are written as the symbol reads
dedented to its own first line: the symbol's indentation is taken off before
the search and put back on the replacement (``replace_in_symbol``), so a
function that becomes a method, or the reverse, keeps its mutations too.

The tool snapshots the repository once into a
scratch folder (the files ``git ls-files`` lists, tracked and untracked but
not ignored, as they are in the working tree; or with ``--rev`` a commit's
tree; ``.venv`` is symlinked, not copied), so edits made meanwhile do not
mix in.  For each mutation it copies the snapshot, applies that ONE mutation
and runs ``python -m pytest -x -q <killers>`` in the copy with a private
TMPDIR.  Exit code 1 from pytest (a test failed or errored) kills the
mutation; 0 means it survived (a test gap); anything else (no tests
collected, a bad node id, an internal error, a timeout) is reported as an
error, never as a kill.

``--baseline`` first runs every killer on an unmutated copy: they must pass,
or a kill proves nothing (no mutation runs then).  ``--list`` prints the
mutations, ``--markdown`` the README's table (one source for both;
``--update-readme`` writes it between the markers in docs/testing.md, and
tests/test_mutations.py checks they agree), ``--json`` the results (with
pytest's one-line reason for each kill).  Exit code 0 when every mutation
was killed (and the baseline passed).

``QUICK`` names the subset the default test tier runs (``--quick``;
tests/test_mutations.py, marker ``mutation``): one mutation of each kind of
promise, each with a killer of seconds.  ``--rest`` runs the others (the slow
tier); together they are every mutation, each once.

A mutation of ``fog_addon/precompute/model/shading.py`` changes the shaders and
their numpy twin alike, so a twin comparison (tests/test_nodes.py) cannot
kill it: its killers have expected values of their own (quadrature of Sun et
al. 2005's equations, Eq. 19 written out by hand, Cycles path tracing).  The
twin comparisons kill mutations of the node wiring (``fog_addon/nodes``).
"""
import argparse
import ast
import json
import os
import pathlib
import re
import shutil
import subprocess
import sys
import tempfile
import time
from typing import NamedTuple, Tuple

ROOT = pathlib.Path(__file__).resolve().parents[1]


class Mutation(NamedTuple):
    name: str
    what: str                 # the physics (or the promise) the mutation removes
    target: str               # the symbol holding ``old``: NAME, Class.method, outer.inner or module.NAME
    old: str                  # exact text, present exactly once in the symbol's source as it reads dedented
    new: str                  # what replaces it, written at the same indentation as ``old``
    killers: Tuple[str, ...]  # pytest node ids from the repository root, cheapest first


SHADE_TEST = "tests/test_shading.py"

MUTATIONS = [
    Mutation("glow_on_surfaces", "glow (airlight) along camera rays that hit surfaces zeroed (Eq. 11)", "shade_point",
             "airlight=m.scale(light.intensity, air),",
             "airlight=m.scale(light.intensity, 0.0 * air),",
             (f"{SHADE_TEST}::test_shade_point_against_quadrature",)),
    Mutation("density_zero_hides_the_world", "a fog of no density still hides the World (transmittance 0 at "
             "beta = 0: the limit e^{-beta t} -> 1 is not taken)", "shade_background",
             "    transmittance = kept + m.less(medium.beta, MIN_BETA) * (1.0 - kept)",
             "    transmittance = kept + 0.0 * m.less(medium.beta, MIN_BETA) * (1.0 - kept)",
             (f"{SHADE_TEST}::test_background_against_quadrature",)),
    Mutation("view_attenuation", "the user's shader not dimmed by e^{−β D_vp} on camera rays",
             "shading.view_transmittance",
             "transmit = 1.0 + is_camera * (t_vp - 1.0)",
             "transmit = 1.0 + is_camera * (0.0 * t_vp)",
             (f"{SHADE_TEST}::test_shade_surface_is_eq19",)),
    Mutation("direct_attenuation_cycles", "Cycles: the light's node tree no longer multiplies by "
             "e^{−β · Ray Length}", "wrap_light",
             "neg.inputs[1].default_value = -1.0",
             "neg.inputs[1].default_value = 0.0",
             ("tests/test_render.py::test_cycles_nodes[spheres-0.15]",)),
    Mutation("direct_attenuation_eevee", "EEVEE: the weighted direct attenuation forced to 1", "surface_fog",
             "direct = (num + 1e-30) / (den + 1e-30)",
             "direct = (den + 1e-30) / (den + 1e-30)",
             (f"{SHADE_TEST}::test_shade_surface_is_eq19",)),
    Mutation("diffuse_fog_light", "fog light the diffuse lobe reflects (ρ_d M_1) zeroed", "shade_point",
             "reflected = m.scale(material.diffuse, diffuse) + ",
             "reflected = m.scale(material.diffuse, 0.0 * diffuse) + ",
             (f"{SHADE_TEST}::test_shade_point_against_quadrature",)),
    Mutation("glossy_fog_light", "fog light the glossy lobe reflects (ρ_s M_n) zeroed", "shade_point",
             "+ m.scale(material.specular, glossy)",
             "+ m.scale(material.specular, 0.0 * glossy)",
             (f"{SHADE_TEST}::test_shade_point_against_quadrature",)),
    Mutation("glossy_mirror_axis", "glossy lobe about the normal instead of the mirrored view vector", "shade_point",
             "mirrored = mirror(m, geo.incoming, geo.normal)",
             "mirrored = geo.normal",
             (f"{SHADE_TEST}::test_glossy_lobe_follows_the_mirror_direction",)),
    Mutation("background_glow", "the background's fog (World airlight, Eq. 12) zeroed", "background_point",
             "return m.scale(light.intensity, m.run(models.background, medium.beta, d_sv, along, h,",
             "return m.scale(light.intensity, 0.0 * m.run(models.background, medium.beta, d_sv, along, h,",
             (f"{SHADE_TEST}::test_background_against_quadrature",)),
    Mutation("albedo_surface", "fog colour (albedo) ignored on surfaces", "sum_lights",
             "    albedo = medium.albedo\n",
             "    albedo = 0.0 * medium.albedo + 1.0\n",
             (f"{SHADE_TEST}::test_shade_surface_is_eq19",)),
    Mutation("albedo_nodes", "fog colour (albedo) not passed from the Params group to the shading",
             "light_groups.medium",
             "Medium(m.wrap(beta), m.wrap(albedo, vector=True))",
             "Medium(m.wrap(beta))",
             ("tests/test_nodes.py::test_cycles_whole_fog_matches_numpy_twin[nodes]",)),
    Mutation("view_attenuation_nodes", "material: the user's shader not scaled by the fog's mix factor "
             "(Mix Shader factor 0)", "_build",
             "tree.links.new(mix_factor, mix.inputs[0])",
             "mix.inputs[0].default_value = 0.0",
             ("tests/test_render.py::test_cycles_nodes[spheres-0.15]",)),
    Mutation("direct_attenuation_eevee_nodes", "material: EEVEE given the Cycles mix factor (direct light "
             "not dimmed)", "_build",
             "f\"{'EEVEE' if target == 'EEVEE' else 'Cycles'} Mix Factor\"",
             "\"Cycles Mix Factor\"",
             ("tests/test_render.py::test_eevee_nodes[spheres-0.15]",)),
    Mutation("fog_emission_nodes", "material: the fog's emission (glow and fog light) not added to the shader",
             "_build",
             "tree.links.new(fog_shader, add.inputs[1])",
             "pass",
             ("tests/test_nodes.py::test_cycles_whole_fog_matches_numpy_twin[nodes]",)),
    Mutation("background_glow_nodes", "World: the fog group's glow not linked into the World's output",
             "wrap_world",
             "tree.links.new(fog.outputs[\"Fog\"], mix.inputs[2])",
             "pass",
             ("tests/test_nodes.py::test_cycles_whole_fog_matches_numpy_twin[nodes]",)),
    Mutation("restore_emission_sampling", "fog.remove leaves the materials' `cycles.emission_sampling` off",
             "restore",
             "    for path, value in dict(idblock.get(WAS, {})).items():\n",
             "    for path, value in dict(idblock.get(WAS, {})).items():\n"
             "        if path == \"cycles.emission_sampling\":\n            continue\n",
             ("tests/test_ops.py::test_add_twice_remove_restores",)),
    Mutation("restore_world_sampling", "fog.remove leaves the World's `cycles.sampling_method` off",
             "restore",
             "    for path, value in dict(idblock.get(WAS, {})).items():\n",
             "    for path, value in dict(idblock.get(WAS, {})).items():\n"
             "        if path == \"cycles.sampling_method\":\n            continue\n",
             ("tests/test_ops.py::test_add_twice_remove_restores",)),
    Mutation("restore_osl_switch", "fog.remove leaves the scene's `cycles.shading_system` (OSL) on",
             "use_osl",
             "scene.cycles.shading_system = bool(scene[OSL_WAS])",
             "pass",
             ("tests/test_artist.py::test_method_switch_keeps_materials",)),
    Mutation("restore_light_use_nodes", "fog.remove leaves the light's `use_nodes` on",
             "unwrap_light",
             "light_data.use_nodes = light_data[_USE_NODES]",
             "pass",
             ("tests/test_ops.py::test_add_twice_remove_restores",)),
    Mutation("composer_reflected_extinction", "the composer adds the fog light a surface reflects without its "
             "extinction e^{−β D_vp} on the way to the camera (Eq. 19)", "compose.surface_light",
             "        parts.append(_times(m, total(reflected), _product(m, dims)))",
             "        parts.append(total(reflected))",
             ("tests/test_composer.py::test_pixel_light_is_eq19_over_the_surface_and_eq12_over_the_sky",
              f"{SHADE_TEST}::test_shade_surface_is_eq19",
              "tests/test_compose.py::test_a_pixel_is_eq19_over_its_surface_and_eq12_over_its_sky")),
    Mutation("composer_sky_coverage", "the compositor's pixel takes the glows to infinity over its whole area, "
             "not over the part its rays reach the sky (Eq. 12 weighted by 1 − coverage)", "source_light",
             "_weighted(m, sky, 1.0 - coverage)",
             "_weighted(m, sky, 1.0)",
             ("tests/test_composer.py::test_pixel_light_is_eq19_over_the_surface_and_eq12_over_the_sky",
              "tests/test_compose.py::test_a_pixel_is_eq19_over_its_surface_and_eq12_over_its_sky")),
    Mutation("composer_layer_end", "the composer's layer end dropped: a ray that leaves a fog layer takes the lamps' "
             "glow to infinity, not the glow its kernel ended at the layer's top", "source_light",
             "                sky = m.scale(total(along), end) + m.scale(sky, 1.0 - end)",
             "                sky = sky",
             ("tests/test_compose.py::test_a_layer_end_bounds_the_lamps_glow_to_the_sky",
              "tests/test_lamp_layer_render.py::test_lamp_glow_ends_at_the_layers_top")),
    Mutation("composer_share_gate", "the composer's shares dropped: a glow is not multiplied by its lit share or its "
             "0/1 gate (a ray that never meets a fog layer keeps the lamps' glow to the sky)", "compose._shared",
             "        value = _times(m, value, share)",
             "        value = value",
             ("tests/test_compose.py::test_a_share_multiplies_its_sources_glows_where_it_is_taken",
              "tests/test_compose.py::test_a_layer_end_bounds_the_lamps_glow_to_the_sky")),
    Mutation("preview_in_final_renders", "the viewport's preview stays on in final renders: the Compositor's "
             "fog and the preview's glows are both in F12's picture", "preview.before_render",
             "    show(working())",
             "    show(True)",
             ("tests/test_preview_switch.py::test_the_preview_is_off_in_final_renders_and_saved_files",)),
    Mutation("preview_behind_no_switch", "the preview's closures not behind the Viewport Preview factor: "
             "always in the picture", "preview.behind_switch",
             "    ng.links.new(params.outputs[groups.PREVIEW], mix.inputs[0])",
             "    mix.inputs[0].default_value = 1.0",
             ("tests/test_viewport_preview.py::test_final_renders_are_those_without_the_preview",)),
    Mutation("auto_needs_before_cost", "Method Auto ignores what the scene needs (a panoramic camera in EEVEE): the "
             "compositor by cost alone", "auto.choose",
             "    if hard is not None:\n",
             "    if False:\n",
             ("tests/test_auto_method.py::test_what_only_the_node_groups_have",)),
    Mutation("shaft_visibility", "light shafts: the lit share counts every node as lit (Dobashi 2002 Eq. 2's H = 1)",
             "_quadrature.nodes",
             "    lit_sum = lit_sum + lit_weight\n",
             "    lit_sum = lit_sum + weight\n",
             ("tests/test_shafts.py::test_sphere_shadow_matches_quadrature",)),
    Mutation("shaft_extinction", "light shafts: the nodes' weights lose the extinction from the light, e^{-beta d}",
             "node_terms",
             "    weight = m.exp((t + d) * minus_beta)\n",
             "    weight = m.exp(t * minus_beta)\n",
             ("tests/test_shafts.py::test_sphere_shadow_matches_quadrature",)),
    Mutation("shaft_phase", "light shafts: the nodes' Henyey-Greenstein weight turned backwards",
             "node_terms",
             "        weight = weight * _hg_of_sine(m, g, sin)\n",
             "        weight = weight * _hg(m, g, sin)\n",
             ("tests/test_shafts.py::test_sphere_shadow_matches_quadrature",)),
    Mutation("shaft_spot_unclipped", "light shafts: a spot's nodes spread over the whole ray, not its part inside "
             "the cone (one node held a third of a ray's glow: blobs above a hooded lamp)",
             "lit_share",
             "    if clip is not None:   # each segment cut to the cone",
             "    if False:   # each segment cut to the cone",
             ("tests/test_shafts.py::test_spot_beam_towards_the_camera_matches_quadrature",
              "tests/test_shaft_scenes.py::test_fog_over_a_hood_has_no_blobs")),
    Mutation("surface_ray_nearest", "light shafts: a surface's hemisphere ray weighed at its own distance from the "
             "light however near (one ray passing a lamp outweighed a hundred: 5 x 5 blobs on a stairwell's walls)",
             "ray_integrals",
             "    scale = step / m.maximum(h, m.length(light - origin) * NEAREST_RAY)\n",
             "    scale = step / h\n",
             ("tests/test_shaft_scenes.py::test_walls_by_a_shaded_pendant_have_no_blobs",)),
    Mutation("dense_escape_unblocked", "Dense Fog beside surfaces: the escape fraction counts every direction as "
             "if nothing stopped a light's power before it scattered",
             "escape_fraction",
             "    scattered = -np.expm1(-beta * np.minimum(np.asarray(depth, float), 1e12))\n",
             "    scattered = -np.expm1(-beta * 1e12 + 0.0 * np.asarray(depth, float))\n",
             ("tests/test_escape.py::test_escape_fraction_over_a_floor_against_its_closed_form",)),
    Mutation("dense_scale_unoccluded", "Dense Fog beside surfaces: the photons' flights never stopped by a surface "
             "(a hood, a wall or the ground stops none of a light's power: its field that of unbounded fog)",
             "traced_share",
             "            alive[alive] = free(position[alive], heading[alive], step[alive])\n",
             "            alive[alive] = True\n",
             ("tests/test_escape.py::test_later_orders_lose_more_to_the_floor",)),
    Mutation("dense_second_flight_unseen", "Dense Fog beside surfaces: a scattering's light to the camera's fog never "
             "stopped by a surface (a room lit through its windows: its fog fed through the wall)",
             "traced_share",
             "                kept += float((value[live].reshape(-1) * seen).sum())\n",
             "                kept += float(value[live].sum()) + 0.0 * float(seen.sum())\n",
             ("tests/test_escape.py::test_nothing_reaches_the_fog_behind_an_endless_wall",)),
    Mutation("dense_second_order_only", "Dense Fog beside surfaces: the photons scatter once and stop (the second "
             "order's share: the light the ground stops between later scatterings left out, an open street 16 % "
             "bright)",
             "traced_share",
             "    for _ in range(orders):\n",
             "    for _ in range(min(orders, 1)):\n",
             ("tests/test_escape.py::test_later_orders_lose_more_to_the_floor",)),
    Mutation("dense_ray_angle_dropped", "Dense Fog beside surfaces: a view ray's equiangular estimate without the "
             "angle it subtends (the draw's density taken as 1 / (h^2 + (t - t0)^2) alone)",
             "ray_sample",
             "exp(-beta * (t + d)) * angle / h\n",
             "exp(-beta * (t + d)) / h\n",
             ("tests/test_escape.py::test_a_scattering_sends_the_rays_their_second_order",)),
    Mutation("emitter_surface_light_dropped", "glowing objects: the fog light they scatter onto other surfaces left "
             "out (the ground under a glowing sphere 0.67 of path tracing)",
             "emitter_fog_light",
             "    return m.scale(total, 1.0 - glowing)\n",
             "    return m.scale(total, 0.0 * glowing)\n",
             ("tests/test_emitter_surfaces.py::test_a_glowing_object_lights_the_ground_through_the_fog",)),
    Mutation("emitter_far_glow_dropped", "glowing objects: no glow far from them (the ladder of blurs holds only the "
             "near kernel: a sphere's ground 0.87 of path tracing, 0.999 with the points' far glow)",
             "comp_fog.build_fog_group",
             "            terms += [compose.Term(compose.GLOW, at, compose.EMITTERS, v) for at, v in far.items()]",
             "            terms += []",
             ("tests/test_emitter_surfaces.py::test_a_glowing_object_lights_the_ground_through_the_fog",)),
    Mutation("emitter_far_window_dropped", "glowing objects: the points' far glow not windowed, so added whole over "
             "the ladder's near part (the glow twice near the object)",
             "comp_lights.build_glow_group",
             "        far = emitter_glow.far_window(m, gamma, far_from)",
             "        far = 1.0 + 0.0 * gamma",
             ("tests/test_emitter_glow.py::test_glowing_sphere_against_path_traced_fog",)),
    Mutation("emitter_one_sided", "glowing objects: an open mesh's faces taken to emit on one side (a flat sign's far "
             "glow half)",
             "emitting_sides",
             "    return 2 if len(counts) and bool((counts == 1).any()) else 1",
             "    return 1",
             ("tests/test_emitter_glow.py::test_a_sign_cut_by_the_frame_glows_as_its_pixels_do",)),
    Mutation("emitter_one_point", "glowing objects: a long one's fog light on surfaces from one point at its centre "
             "(a bar's ground 21 % off path tracing by blocks, against 10 % in four pieces; the same points in the "
             "viewport: 4.5 % against 2.4 %)",
             "emitter_points",
             "        axis, n = _pieces(obj)\n",
             "        axis, n = _pieces(obj)[0], 1\n",
             ("tests/test_emitter_surfaces.py::test_a_glowing_object_lights_the_ground_through_the_fog",
              "tests/test_emitter_surfaces.py::test_the_viewport_shows_a_glowing_objects_light_on_the_ground")),
    Mutation("emitter_area_uniform_scale", "glowing objects: the area of a mesh scaled non-uniformly taken as if its "
             "scale were uniform (a cube scaled into a bar: 0.47 of its area, half its fog light)",
             "glowing_points",
             "        area = world_area(obj.data, m) * emitting_sides(obj.data)\n",
             "        area = world_area(obj.data, m.to_3x3().normalized()\n"
             "                          * abs(m.to_3x3().determinant()) ** (1.0 / 3.0))\n",
             ("tests/test_emitter_surfaces.py::test_a_glowing_object_lights_the_ground_through_the_fog",)),
    Mutation("dense_scale_unapplied", "Dense Fog beside surfaces: the lights' multiply scattered terms keep the "
             "unbounded field whatever their scale (the hooded lamp's fog 49 % off path tracing)",
             "_scaled",
             "    if scale == 1.0:\n",
             "    if True:\n",
             ("tests/test_multiple.py::test_multiple_rungs_add_the_multiple_glow_to_the_single",
              "tests/test_dense_surplus.py::test_dense_fog_beside_surfaces_against_path_tracing")),
    Mutation("daylight_outside_the_denominator", "the predictor: a fog layer's sun and sky left out of each "
             "sample's fog, so a lamp's share of a daylit picture is judged as if it were night (Sun et al. 2005 "
             "Eq. 19 sums every source's fog light)",
             "sample_fog",
             "    return fog if other is None else fog + np.asarray(other, float)\n",
             "    return fog\n",
             ("tests/test_predict.py::test_the_fog_no_step_leaves_out_is_in_every_samples_denominator",)),
    Mutation("dense_scale_unjudged", "the Quality's ladder judges each light with Dense Fog's unbounded field "
             "while the render scales it beside surfaces (a random scene at Final measured 1.12 % against 0.98 % "
             "predicted)",
             "light_terms",
             "    scaled = multiple_albedo is not None and multiple_scale is not None and np.any(np.asarray(multiple_scale) != 1.0)\n",
             "    scaled = False\n",
             ("tests/test_predict.py::test_the_ladder_judges_dense_fog_as_the_surfaces_scale_it",)),
    Mutation("emitters_outside_the_denominator", "the predictor: the glowing objects' fog left out of each "
             "sample's fog where the Compositor glows them (their light is part of every pixel's it reaches)",
             "with_other",
             "    if glows_emitters(scene, method):\n",
             "    if False:\n",
             ("tests/test_predict_sources.py::test_a_glowing_objects_fog_is_in_the_compositors_denominator",)),
    Mutation("emission_image_unread", "the predictor: a glowing object's Image Texture colour left unread (its fog "
             "out of the denominator, as a procedural texture's)",
             "emitted_radiance",
             "                colour = image_mean(colour)\n",
             "                colour = None\n",
             ("tests/test_predict_sources.py::test_a_textured_emission_shines_with_its_images_mean",)),
    Mutation("emission_image_srgb_stored", "the predictor: an 8-bit sRGB image's mean taken of its stored values, not "
             "made linear (a grey of 0.5 stored shines 2.3 times its 0.21)",
             "_pixels_mean",
             "    if not img.is_float and img.colorspace_settings.name == \"sRGB\":\n",
             "    if False:\n",
             ("tests/test_predict_sources.py::test_a_textured_emission_shines_with_its_images_mean",)),
    Mutation("predictor_stops_at_glass", "the predictor: a view sample stops at glass where the method shades the "
             "fog past it (the glow of a lamp seen through a shop window left out of its share)",
             "_first_opaque",
             "    for _ in range(GLASS_HOPS if past_glass else 0):\n",
             "    for _ in range(0):\n",
             ("tests/test_predict_glass.py::test_the_predictor_sees_past_glass",)),
    Mutation("predictor_sees_loose_glass", "the predictor: a glass shader anywhere in a material's tree makes it "
             "glass, connected to the output or not (samples pass an opaque pane)",
             "_clear_glass",
             "                                                   for n in caveats.surface_nodes(tree))\n",
             "                                                   for n in tree.nodes)\n",
             ("tests/test_predict_glass.py::test_the_predictor_sees_past_glass",)),
    Mutation("predictor_reads_loose_principled", "the predictor: a surface's albedo from the first Principled BSDF "
             "of its material's tree, connected to the output or not",
             "_principled",
             "    for node in caveats.surface_nodes(material.node_tree):\n",
             "    for node in material.node_tree.nodes:\n",
             ("tests/test_predict_glass.py::test_the_predictor_sees_past_glass",)),
    Mutation("emitter_intensity_whole_area", "the predictor and the preview: a glowing object's intensity L A, its "
             "whole surface instead of its mean projected area A / 4 (Cauchy)",
             "compositor.glowing_points",
             "np.max(radiance, axis=0) * area / 4.0)",
             "np.max(radiance, axis=0) * area)",
             ("tests/test_predict_sources.py::test_a_glowing_objects_fog_is_in_the_compositors_denominator",
              "tests/test_viewport_preview.py::test_viewport_glows_a_glowing_object")),
    Mutation("surface_share_hemisphere", "light shafts: a surface's fog light sees the fog within 30 degrees of its "
             "normal only (Sun 2005 Eq. 17's G_0 is over the whole hemisphere, cos-weighted)",
             "hemisphere_angles",
             "    return [((place + j) * (1.0 / count), ",
             "    return [((place + j) * (0.25 / count), ",
             ("tests/test_shafts.py::test_hemisphere_directions_are_cosine_weighted",
              "tests/test_shafts.py::test_surface_share_matches_quadrature")),
    Mutation("mc_crossing_radiance", "multiple scattering: the Monte Carlo tallies flux, not radiance (a crossing "
             "at mu counts 1, not 1 / |mu|)",
             "_tally_pairs",
             "        val = w[i_photon] * np.exp(-s_h) / np.maximum(np.abs(mu_h), 1e-3)\n",
             "        val = w[i_photon] * np.exp(-s_h)\n",
             ("tests/test_apsf.py::test_monte_carlo_single_scattering_matches_quadrature",)),
    Mutation("mc_expected_crossing", "multiple scattering: the Monte Carlo's expected-value crossings drop their "
             "e^{-s} (every crossing ahead counts as if reached)",
             "_tally_pairs",
             "        val = w[i_photon] * np.exp(-s_h) / np.maximum(np.abs(mu_h), 1e-3)\n",
             "        val = w[i_photon] / np.maximum(np.abs(mu_h), 1e-3)\n",
             ("tests/test_apsf.py::test_monte_carlo_single_scattering_matches_quadrature",)),
    Mutation("multiple_segment_attenuation", "multiple scattering: the field beyond a surface is not dimmed on its "
             "way back to the camera (the segment's e^{-beta D})",
             "multiple_airlight",
             "    return multiple_background(m, spec, beta, d_sv, along, h) - m.exp(-1.0 * beta * d_vp) * beyond\n",
             "    return multiple_background(m, spec, beta, d_sv, along, h) - beyond\n",
             ("tests/test_multiple.py::test_segment_formula_on_the_single_scattering_field",)),
    Mutation("multiple_albedo_power", "multiple scattering: order k weighted W0^k per unit albedo (it is W0^(k-1): "
             "the shading multiplies by W0 once more)",
             "field_of_orders",
             "    weights = float(albedo) ** np.arange(0, MAX_ORDER, dtype=float)",
             "    weights = float(albedo) ** np.arange(1, MAX_ORDER + 1, dtype=float)",
             ("tests/test_multiple.py::test_field_per_unit_albedo_vanishes_with_albedo",
              "tests/test_multiple.py::test_table_matches_an_independent_monte_carlo")),
    Mutation("multiple_irradiance_cosine", "multiple scattering: a surface's irradiance from the field without "
             "the cosine of incidence (Narasimhan §7.4 / Sun Eq. 17 weigh by cos)",
             "irradiance_of_field",
             "    weight = (cp * sp * (0.5 * math.pi / n_polar)",
             "    weight = (sp * (0.5 * math.pi / n_polar)",
             ("tests/test_multiple.py::test_irradiance_of_the_single_scattering_field_is_sun_g0",)),
    Mutation("spot_multiple_azimuth", "spot multiple scattering: the source function read at one azimuth about "
             "the lamp's direction (a beam's scattered light does not depend on which side of it the camera is)",
             "_read",
             "    slot = phi * ((PHI_NODES - 1.0) / math.pi)\n",
             "    slot = 0.0 * phi\n",
             ("tests/test_spot_multiple.py::test_glow_against_64_bounces",)),
    Mutation("spot_multiple_first_collision", "spot multiple scattering: the first collision drawn log-uniformly "
             "without its weight e^-s s ln(hi/lo) (the photons' first scattering as if it were exponential)",
             "collide",
             "            w[-fresh:] *= np.exp(-s0) * s0 * log_range\n",
             "            w[-fresh:] *= 1.0\n",
             ("tests/test_spot_multiple.py::test_a_cone_as_wide_as_the_sphere_is_the_point_light",)),
    Mutation("spot_multiple_surface_cosine", "spot multiple scattering: a surface takes |w . n| of the radiance, "
             "light from behind it too (the irradiance's clamped cosine, Narasimhan §7.4)",
             "_tally_exact",
             "        np.maximum(-dot[:, :n_flat], 0.0, out=face[:, :n_flat])\n"
             "        np.maximum(-plus, 0.0, out=face[:, n_flat:])\n"
             "        face[:, n_flat:] += np.maximum(-minus, 0.0)\n",
             "        np.abs(dot[:, :n_flat], out=face[:, :n_flat])\n"
             "        np.abs(plus, out=face[:, n_flat:])\n"
             "        face[:, n_flat:] += np.abs(minus)\n",
             ("tests/test_spot_multiple.py::test_a_cone_as_wide_as_the_sphere_lights_surfaces_as_the_point_light",)),
    Mutation("area_multiple_profile", "area multiple scattering: the emitter's photons leave isotropically, not by "
             "Lambert's cosine about its normal",
             "_emit",
             "        c = np.sqrt(rng.random(n))\n",
             "        c = 2.0 * rng.random(n) - 1.0\n",
             ("tests/test_spot_multiple.py::test_area_light_glow_against_64_bounces",)),
    Mutation("halo_not_upsampled", "Dense Fog halos: the coarse halo sum brought back without its upsampling (the "
             "samples every Halo Step pixels taken as the picture's)",
             "fine",
             "    step = g[HALO_STEP]\n    args = ",
             "    step = 1.0\n    args = ",
             ("tests/test_spot_multiple.py::test_coarse_halo_at_a_quarter_of_the_resolution",)),
    Mutation("weather_layers_in_ln_t", "weather: the layers even in ln T (far apart in T where T >> 1, where the "
             "multiply scattered halo widens with T)",
             "LAYER_SLOPE",
             "LAYER_SLOPE = 0.5 ",
             "LAYER_SLOPE = 0.0 ",
             ("tests/test_weather.py::test_a_pixel_between_layers_glows_with_its_own_kernel",)),
    Mutation("weather_source_intensity", "weather: a pixel's intensity without its depth squared (L Omega z^2 is "
             "the intensity of a patch filling a pixel at depth z)",
             "glow_kernel",
             "    return kern * (pixel_angle ** 2) * t * t\n",
             "    return kern * (pixel_angle ** 2) * t\n",
             ("tests/test_weather.py::test_a_lamps_pixels_glow_like_path_traced_fog",)),
    Mutation("area_solid_angle_sign", "area lights: the corner terms of the emitter's solid angle all added (the "
             "rectangle from the foot point to each corner is signed by the side it lies on)",
             "_cell_solid_angle",
             "    return corners[i + 1][j + 1] - corners[i][j + 1] - corners[i + 1][j] + corners[i][j]\n",
             "    return corners[i + 1][j + 1] + corners[i][j + 1] + corners[i + 1][j] + corners[i][j]\n",
             ("tests/test_area.py::test_reference_emitter_quadrature_is_the_solid_angle",)),
    Mutation("area_cell_extinction", "area lights: each cell's extinction taken from the emitter's centre (the "
             "cells' e^{-beta (r_k - r)} left out)",
             "_profile",
             "                w = omega * m.exp(beta * (r - rk))   # the cell's extinction over the centre's\n",
             "                w = omega\n",
             ("tests/test_area.py::test_glow_against_quadrature_far_from_the_emitter",)),
    Mutation("area_phase_per_cell", "area lights: the phase function of the emitter's centre for every cell "
             "(the direction from each cell left out)",
             "_profile",
             "                cos_theta = -m.mul_add(cx, dx, m.mul_add(cy, dy, z * dz)) / m.maximum(rk, 1e-30)\n",
             "                cos_theta = -m.mul_add(x, dx, m.mul_add(y, dy, z * dz)) / m.maximum(r, 1e-30)\n",
             ("tests/test_area.py::test_glow_near_the_emitter_as_documented",)),
    Mutation("area_one_sided", "area lights: the emitter shines from both sides (the fog behind it lit)",
             "front_interval",
             "    hi = m.select(heads_out, cross, t_end)\n",
             "    hi = t_end\n",
             ("tests/test_area.py::test_glow_against_quadrature_far_from_the_emitter",)),
    Mutation("emitter_glow_undimmed", "glowing objects: the Emission pass taken as the emitters' light (it is dimmed "
             "by the fog in front of them: their light is the pass times e^{beta D_vp})",
             "glows",
             "    light = m.scale(p[EMITTERS], emitter_glow.source_weight(m, spec, t))\n",
             "    light = m.scale(p[EMITTERS], emitter_glow.source_weight(m, spec, t) * m.exp(-t))\n",
             ("tests/test_emitter_glow.py::test_glowing_sphere_against_path_traced_fog[cycles-0.1-False]",)),
    Mutation("emitter_glow_table_normalisation", "glowing objects: the weights' total read from its table without the "
             "T of its normalisation N e^T / T",
             "source_weight",
             "    return m.exp(m.table(spec, table_x(m, t), 1.0)) * t\n",
             "    return m.exp(m.table(spec, table_x(m, t), 1.0))\n",
             ("tests/test_emitter_glow.py::test_the_table_read_between_its_columns_holds_the_kernel",)),
    Mutation("emitter_glow_dipole_sign", "glowing objects: a flat emitter glows more on the side its normal leans "
             "away from (the dipole's sign)",
             "glows",
             "            lean_grey = (dx + dy) * (-0.5 * emitter_glow.dipole_scale(size))\n",
             "            lean_grey = (dx + dy) * (0.5 * emitter_glow.dipole_scale(size))\n",
             ("tests/test_emitter_glow.py::test_flat_glowing_square_against_path_traced_fog[0.3-False]",)),
    Mutation("emitter_glow_depth_squared", "glowing objects: a pixel's intensity without its depth squared (L "
             "Omega z^2 is the intensity of a patch filling a pixel at depth z)",
             "_kernel_at",
             "    return kern * (pixel_angle ** 2) * float(t) ** 2\n",
             "    return kern * (pixel_angle ** 2) * float(t)\n",
             ("tests/test_emitter_glow.py::test_glowing_sphere_against_path_traced_fog[cycles-0.1-False]",)),
    Mutation("emitted_light_undimmed", "glowing objects: their light on other surfaces not dimmed by its path through "
             "the fog (the emission of (e^{-beta L} - 1) times the user's, off camera rays)",
             "_build",
             "            last = _dim_emitted_light(ops, tree, emitting, last, (x0 + 500, y - 120))\n",
             "            pass\n",
             ("tests/test_emitter_glow.py::test_a_glowing_objects_light_on_the_ground_is_dimmed",)),
    Mutation("emitter_glow_edges_extended", "glowing objects: the Blur nodes extend the picture's edge pixels outwards "
             "(a glowing object cut by the frame glows as if it went on)",
             "glows",
             "            blur.inputs[\"Extend Bounds\"].default_value = True",
             "            blur.inputs[\"Extend Bounds\"].default_value = False",
             ("tests/test_emitter_glow.py::test_a_sign_cut_by_the_frame_glows_as_its_pixels_do",)),
    Mutation("daylight_sky_isotropic", "daylight: the sky's in-scattering ignores the fog's anisotropy",
             "sky_airlight",
             "        if g:\n",
             "        if False:\n",
             ("tests/test_sunlight.py::test_sky_airlight_anisotropic_against_quad",)),
    Mutation("daylight_sky_tilt_flat", "daylight: every surface's sky light is dimmed as a floor's (walls see the "
             "sky near the horizon through longer paths)",
             "tilted_irradiance_of_column",
             "    return m.maximum(a + nz * (half_up + nz * (half_up - a)), 0.0)",
             "    return half_up * (1.0 + nz)",
             ("tests/test_sunlight.py::test_sky_tilted_irradiance_against_quad",)),
    Mutation("daylight_fog_light_no_peak", "daylight: the fog light on surfaces without the sun's phase peak",
             "_irradiance",
             "        peak = _coefficient(m, spec, x, 2 * SH_COUNT) * _coefficient(",
             "        peak = 0.0 * _coefficient(m, spec, x, 2 * SH_COUNT) * _coefficient(",
             ("tests/test_sunlight.py::test_fog_light_against_sphere_quadrature",)),
    Mutation("driver_keyframes", "drivers: the F-Curve's (0, 0), (1, 1) keyframes kept (Blender snaps a driven value "
             "within 1e-4 of them: a 40 km haze's density 9.8e-5 /m driven as 0)",
             "_new_driver",
             "    curve.keyframe_points.clear()",
             "    pass",
             ("tests/test_drivers.py::test_driven_values_pass_through",)),
    Mutation("air_sky_source_isotropic", "air: the sky's Rayleigh scattering taken as isotropic over each ring "
             "(the Rayleigh phase's (v.w)^2 term averaged away)",
             "rayleigh_sky_source",
             "    return (3.0 / 8.0) * ((1.0 + 0.5 * s) * expint2(m, c) + (vz * vz - 0.5 * s) * expint4(m, c))",
             "    return (1.0 / 2.0) * expint2(m, c)",
             ("tests/test_air_kernels.py::test_rayleigh_sky_source_against_quadrature",)),
    Mutation("air_layer_sky_undimmed", "air: the fog layer's sky glow not changed by the air (neither the sky's light "
             "dimmed on its way to the layer nor the glow on its way to the camera)",
             "_ray_glow",
             "    return _air_glow_light(m, day, p_l, p_r, [(sun_l, sun_a, sky * sky_ratio, sky_a) for sun_l, sun_a, "
             "sky_a, sky_ratio",
             "    return _air_glow_light(m, day, p_l, p_r, [(sun_l, sun_a, sky, sky_a) for sun_l, sun_a, "
             "sky_a, sky_ratio",
             ("tests/test_air_kernels.py::test_ray_glow_with_air_against_quadrature",)),
    Mutation("air_fog_light_layer_only", "air: the fog light on surfaces without the air's own scattered sunlight "
             "and skylight",
             "_bake_fog_light_air.fields",
             "    return (lit * (p_l * (sun_l - i_s) + p_r * sun_a), albedo * l_sky * ratio + sky_a, "
             "lit * albedo * i_s)",
             "    return (lit * (p_l * (sun_l - i_s)), albedo * l_sky * ratio, lit * albedo * i_s)",
             ("tests/test_sunlight.py::test_fog_light_with_air_against_sphere_quadrature",)),
    Mutation("daylight_glow_table_no_rayleigh", "daylight: the glow table's reader leaves out the air's Rayleigh "
             "scattering of the sun",
             "table_glow",
             "    return _air_glow_light(m, day, p_l, aerial.rayleigh_phase(m, cos_theta),",
             "    return _air_glow_light(m, day, p_l, 0.0 * aerial.rayleigh_phase(m, cos_theta),",
             ("tests/test_glow_table.py::test_table_glow_against_the_kernels",)),
    Mutation("daylight_proxy_uncorrected", "daylight, Compositor: the materials' grey stand-in transmittance is "
             "left on the picture (not corrected per pixel to the layer's and the air's exact colour)",
             "build_fog_group",
             "        inv = 1.0 / m.maximum(sunlight.proxy_transmittance(m, daylight, d_vp), 1e-30)",
             "        inv = 1.0",
             ("tests/test_haze_render.py::test_haze_against_cycles",)),
    Mutation("lamp_glow_past_the_top", "fog layer: a lamp's glow goes on past the layer's top (the ray's span "
             "never ends where it leaves the layer)",
             "lamp_glow_span",
             "    t1 = m.select(leaves, m.minimum(to_top, far), far)",
             "    t1 = far + 0.0 * to_top",
             ("tests/test_lamp_layer.py::test_glow_over_the_span_against_quadrature",)),
    Mutation("lamp_sky_glow_past_the_top", "fog layer, Compositor: a pixel that sees the sky takes the lamps' glow "
             "to infinity, not to where its ray leaves the layer",
             "build_fog_group",
             "        bounded, meets = m.less(t1, LAYER_OPEN), m.less(t0, LAYER_OPEN)",
             "        bounded, meets = 0.0, m.less(t0, LAYER_OPEN)",
             ("tests/test_lamp_layer_render.py::test_lamp_glow_ends_at_the_layers_top",)),
    Mutation("probe_keeps_sun_disc", "daylight: the World's mean over the sky takes a Sky Texture's sun disc in (a sun "
             "counted as sky)",
             "_probe_pixels",
             "            node.sun_disc = False",
             "            pass",
             ("tests/test_sky_probe.py::test_sun_disc_is_left_out_of_the_skys_mean",)),
    Mutation("emitter_own_pixels_shared", "glowing objects: an emitter's own pixels take only the share of the glow "
             "in front of a surface at its depth (half), not the whole",
             "glows",
             "    t_surface = m.select(glowing, 1.0e6, t_surface)",
             "    t_surface = t_surface",
             ("tests/test_emitter_glow.py::test_glowing_sphere_against_path_traced_fog",)),
    Mutation("daylight_sun_undimmed", "daylight: the sun's light on surfaces is not dimmed by the layer above them",
             "direct_dimming",
             "    t_sun = daylight.sun_transmittance(m, z, sun_elevation(m, day), *args)",
             "    t_sun = 1.0",
             ("tests/test_sunlight.py::test_direct_dimming_limits",)),
    Mutation("world_sky_air_counted_twice", "a Sky Texture World with Air: the air's kernels scatter the sun and the "
             "sky again on top of the World, which already holds the air",
             "_air_glow_light",
             "    if day.world_sky is not None:   # the air's own scattering is in the World",
             "    if False:",
             ("tests/test_world_sky.py::test_a_pixel_of_sky_is_the_world_itself",)),
    Mutation("world_sky_no_limit", "a Sky Texture World with Air: the air's glow is not the World's radiance times the "
             "air's opacity (distant terrain does not fade to the sky above it)",
             "ray_glow",
             "    return glow + world_radiance(m, day, direction) * m.combine(*(1.0 - c for c in t))",
             "    return glow + 0.0 * world_radiance(m, day, direction) * m.combine(*(1.0 - c for c in t))",
             ("tests/test_world_sky.py::test_far_terrain_fades_to_the_world_above_it",)),
    Mutation("world_sky_sun_above_the_air", "a Sky Texture World with Air: the Sun light is dimmed by the whole air "
             "column again, though it is the sun at the ground",
             "direct_dimming",
             "        c_a = c_a - aerial.air_column_depth(m, 0.0, 1.0, day.air_height)",
             "        c_a = c_a - 0.0",
             ("tests/test_world_sky.py::test_the_sun_light_is_the_sun_at_the_ground",)),
    Mutation("sun_shafts_ignore_the_map", "sun shafts: the fog is lit wherever the sun's map says it is in a shadow",
             "sun_lit",
             "    return m.select(inside, m.less(beyond, depth - frame.bias), 1.0)",
             "    return 1.0 + 0.0 * m.select(inside, m.less(beyond, depth - frame.bias), 1.0)",
             ("tests/test_sun_shafts.py::test_sun_share_matches_quadrature",)),
    Mutation("sun_nodes_not_importance_placed", "sun shafts: the lit share's nodes are spread evenly along the ray, "
             "not in the quantiles of the sun's single scattering (the share then weighs the far fog as the near)",
             "sun_node_place",
             "    return m.select(flat, u, placed)",
             "    return u + 0.0 * placed",
             ("tests/test_sun_shafts.py::test_node_places_are_the_quantiles",)),
    Mutation("sun_surface_share_unweighted", "sun shafts: the fog light's share weighs every hemisphere direction "
             "alike, not by the sun's single scattering along it (its phase function and its span in the layer)",
             "sun_surface_share.ray",
             "    weight = integral * (_hg(mm, g, mm.dot(u, s)) if g else 1.0)",
             "    weight = 1.0 + 0.0 * integral",
             ("tests/test_sun_shafts.py::test_sun_surface_share_matches_quadrature",)),
    Mutation("quiet_default_dropped", "node building: a constant fed to a node whose inputs are all numbers is read "
             "and written back unchanged (the quiet write loses the value)",
             "quiet_default",
             "        values[list(inputs).index(sock)] = float(value)\n",
             "        values[list(inputs).index(sock)] += 0.0 * float(value)\n",
             ("tests/test_node_building.py::test_constants_and_places_are_set_without_updates",)),
    Mutation("nodes_left_unplaced", "node building: the nodes of a tree stay where Blender made them (place does "
             "nothing)",
             "NodeOps.place",
             "    if not self._places or self.tree is None:\n",
             "    if True:\n",
             ("tests/test_node_building.py::test_constants_and_places_are_set_without_updates",)),
    Mutation("point_casts_too_few", "light shafts, a point light's map: its rows cast half the rays their latitude "
             "needs (neighbouring rays twice the equator's spacing apart)",
             "point_map_casts",
             "    counts = np.ceil(np.cos(lat).clip(0.0, 1.0) * (width - 1) - 1e-9)",
             "    counts = np.ceil(np.cos(lat).clip(0.0, 1.0) * (width - 1) / 2.0 - 1e-9)",
             ("tests/test_shafts.py::test_point_map_casts_resolve_the_equator_spacing_everywhere",)),
    Mutation("half_share_offsets_alike", "light shafts, surface share at half resolution: its samples take the "
             "interleaving offsets of the picture's pixels, not their own (the samples of a 2 x 2 block's corner "
             "share a quarter of the pattern)",
             "halved",
             "    whole = shafts.surface_offset(m, m.floor(pixel_x * factor), m.floor(pixel_y * factor))",
             "    whole = shafts.surface_offset(m, pixel_x, pixel_y)",
             ("tests/test_shaft_scenes.py::test_shares_at_half_resolution_against_path_tracing[window_room-2]",)),
    Mutation("half_view_unweighted", "light shafts, the glows' lit share at half resolution: the upsampled sums are "
             "not divided by their weights",
             "full_view",
             "    weight = m.maximum(m.dot(packed, (0.0, 0.0, 1.0)), 1e-6)",
             "    weight = 1.0 + 0.0 * m.dot(packed, (0.0, 0.0, 1.0))",
             ("tests/test_half_share.py::test_glow_shares_come_back_each_surface_its_own",)),
    Mutation("half_view_offsets_alike", "light shafts, the glows' lit share at half resolution: its samples take the "
             "interleaving offsets of the picture's pixels, not their own (every sample the same rank)",
             "halved",
             '            HALF + "Shaft Offset": shafts.offset(m, m.floor(px * factor), m.floor(py * factor))}',
             '            HALF + "Shaft Offset": shafts.offset(m, px, py)}',
             ("tests/test_shaft_scenes.py::test_shares_at_half_resolution_against_path_tracing[window_room-2]",
              "tests/test_shaft_scenes.py::test_shares_at_half_resolution_against_path_tracing[colonnade-2]")),
    Mutation("quarter_share_dropped", "light shafts: a picture of 288 px or more keeps its shares at half resolution "
             "(the driver's quarter term dropped)",
             "halved",
             '{HALF_FROM}),1)-0.25*min(floor({size}/"',
             '{HALF_FROM}),1)-0.0*min(floor({size}/"',
             ("tests/test_half_share.py::test_share_scale_follows_the_render_size",)),
    Mutation("scaled_edges_clipped", "light shafts, shares at half or quarter resolution: a picture whose size the "
             "step does not divide loses its edge pixels' shares (the Scale nodes clip)",
             "scaled",
             '        node.inputs[f"Extension {axis}"].default_value = "Extend"',
             '        node.inputs[f"Extension {axis}"].default_value = "Clip"',
             ("tests/test_half_share.py::test_a_size_not_a_multiple_of_the_step_keeps_every_pixel",)),
    Mutation("half_share_upsampled_blind", "light shafts, surface share at half resolution: a pixel takes its sample's "
             "share whatever surface that sample lies on (no depth test)",
             "_upsampled",
             "    own = m.less(m.abs(log_sample - log), UPSAMPLE_EDGE)",
             "    own = 1.0",
             ("tests/test_half_share.py::test_upsampling_keeps_each_surface_its_own_share",)),
    Mutation("emitter_facing_isotropic", "glowing objects: each pixel an isotropic source of what it shows the camera "
             "(a flat sign sends as much light sideways as towards the camera), not the two-sided Lambertian source "
             "its surface is",
             "glows",
             "        light = m.scale(light, emitter_glow.facing_factor(m, facing, m.table(emitter_glow.facing_spec(g), c, "
             "0.0)))",
             "        light = light",
             ("tests/test_emitter_glow.py::test_a_sign_cut_by_the_frame_glows_as_its_pixels_do",)),
    Mutation("emitter_facing_no_phase", "glowing objects: the facing mean weighs the fog's directions alike, not by "
             "the phase function of their scattering towards the camera (forward fog sees a sign's face)",
             "facing_mean",
             "    weight = (1.0 - g * g) / (1.0 + g * g - 2.0 * g * mu) ** 1.5\n",
             "    weight = 1.0 + 0.0 * mu\n",
             ("tests/test_emitter_glow.py::test_facing_mean_against_quadrature",)),
    Mutation("sun_shadow_dims_as_lit", "sun shafts: a surface in the sun's shadow takes the sun's and the sky's "
             "weighted dimming, as if the sun reached it",
             "build_fog_group",
             "        sun_visible = (None if sun_share is None else",
             "        sun_visible = (None if True else",
             ("tests/test_sun_shafts_render.py::test_sun_shafts_against_cycles[hard_g0.7_inside_low]",)),
    Mutation("sun_shafts_unwired", "sun shafts, Compositor: the glow and the fog light on surfaces take no shares",
             "build_fog_group",
             "                                      t_day, cover, sun_share, surface_share)",
             "                                      t_day, cover, None, None)",
             ("tests/test_sun_shafts_render.py::test_sun_shafts_against_cycles[hard_g0.7_inside_low]",)),
    Mutation("preview_no_shafts", "viewport preview, Cycles: a shafted light's glow without its lit share",
             "surface_group._shafted",
             "seen=share if terms.seen is None else m.wrap(terms.seen) * share)",
             "seen=terms.seen)",
             ("tests/test_viewport_preview.py::test_viewport_against_path_tracing[window_room-0.1]",)),
    Mutation("preview_no_surface_share", "viewport preview, Cycles: a surface's reflected fog light without the "
             "share its light's shadows leave",
             "surface_group._shafted",
             "m.scale(m.wrap(terms.scattered, vector=True), visible)",
             "m.wrap(terms.scattered, vector=True)",
             ("tests/test_viewport_preview.py::test_viewport_against_path_tracing[window_room-0.1]",)),
    Mutation("preview_tile_glow_sign", "viewport preview's sampled lights: a tile's guess of a light's glow takes "
             "the ray's nearest approach behind the camera for in front (the airlight integral's atan)",
             "sampling.tile_importance",
             "(0.5 * np.pi + np.arctan(t0 / h)) / h",
             "(0.5 * np.pi - np.arctan(t0 / h)) / h",
             ("tests/test_preview_sampled.py::test_tile_importance_is_the_airlight_integral_of_thin_fog",)),
    Mutation("preview_tiles_flipped", "viewport preview's sampled lights: a pixel draws from the row of the tile "
             "mirrored top to bottom (window coordinates run up from the frame's bottom)",
             "preview_sampled._tile",
             "ty = m.clamp(m.floor(m.wrap(sep.outputs[1]) * float(ny)), 0.0, ny - 1.0)",
             "ty = m.clamp(m.floor((1.0 - m.wrap(sep.outputs[1])) * float(ny)), 0.0, ny - 1.0)",
             ("tests/test_viewport_preview.py::test_viewport_samples_the_other_lamps_of_a_boulevard",)),
    Mutation("preview_sampled_no_dense", "viewport preview's sampled lights: their glows without Dense Fog's "
             "multiply scattered light where the final render has it",
             "preview_sampled.dense_of",
             "    return albedo, float(",
             "    return None and float(",
             ("tests/test_viewport_preview.py::test_viewport_samples_three_lamps_without_bias",)),
    Mutation("equiangular_phase_sign", "the viewport preview's sampled glow: the phase function taken at the "
             "scattering angle's supplement (cos = +sin theta: forward scattering where the light is ahead of the "
             "point)", "model.airlight_equiangular",
             "m.mul_add(m.sin(theta), 2.0 * g, 1.0 + g * g)",
             "m.mul_add(m.sin(theta), -2.0 * g, 1.0 + g * g)",
             ("tests/test_airlight.py::test_equiangular_glow_is_unbiased[0.7]",)),
    Mutation("equiangular_density", "the viewport preview's sampled glow: the equiangular point's density "
             "without its span of angles (biased wherever the segment is not seen under one radian)",
             "model.airlight_equiangular",
             "(beta * (0.25 / math.pi)) * step / h",
             "(beta * (0.25 / math.pi)) / h",
             ("tests/test_airlight.py::test_equiangular_glow_is_unbiased[0.0]",)),
    Mutation("mirror_lobe_kept", "sharp mirrors: the glossy lobe's blurred fog light kept beside the exact mirrored "
             "tail (their reflected fog counted twice)", "surface_group.build_surface",
             "    lobe = specular if mirror is None else m.scale(specular, 1.0 - mirror)",
             "    lobe = specular",
             ("tests/test_glass_mirror.py::test_fog_past_glass_and_mirrors[mirror-nodes]",)),
    Mutation("mirror_no_tail", "sharp mirrors, Compositor: no mirrored tail (the pixels' lobe left out, nothing "
             "in its place)", "glass_tails.place_tails",
             "        mirrored = mirrored + mirror",
             "        mirrored = m.scale(mirrored, 1.0)",
             ("tests/test_glass_mirror.py::test_fog_past_glass_and_mirrors[mirror-compositor]",)),
    Mutation("shafts_interleave_unfiltered", "light shafts: the interleaved shares left unfiltered (a regular 2 x 2 "
             "and 4 x 4 grain: the pattern's excess 20-42 against 0.8-1.9)",
             "comp_shafts._interleave_mean",
             "    log = m.math(\"LOGARITHM\", m.maximum(length, 1e-3), math.e)",
             "    return value",
             ("tests/test_shaft_scenes.py::test_shaft_scene_against_path_tracing[window_room]",)),
    Mutation("shafts_surface_taps_short", "light shafts: the surfaces' 4 x 4 interleaved shares averaged over 2 x 2 "
             "only (a faint 4-pixel grain: its excess 3.4 on the window room, whose relative RMSE still passes)",
             "comp_shafts.SURFACE_TAPS",
             "SURFACE_TAPS = (1,) + (2,) * (2 ** shafts.SURFACE_PATTERN_LEVELS - 1) + (1,)",
             "SURFACE_TAPS = (1, 2, 1)",
             ("tests/test_shaft_scenes.py::test_shaft_scene_against_path_tracing[window_room]",)),
    Mutation("area_shaft_unweighted", "area lights' shafts: the fog weighed as a point light's, not by Lambert's "
             "cosine on the emitter's front side (the softbox colonnade 4.2 % off path tracing, 2.07 % weighed)",
             "area.shaft_falloff",
             "    return lambert_falloff(m, m.dot(normal, u) * -1.0 / m.maximum(m.length(normal) * d, 1e-30))",
             "    return 1.0 + 0.0 * m.dot(normal, u)",
             ("tests/test_shafts.py::test_area_light_share_weighs_its_front_side",)),
    Mutation("area_no_shafts", "area lights cast no shafts (the softbox colonnade 14.9 % off path tracing)",
             "compositor.shafted_lights",
             "    return shadow_maps.shafted_split(scene, lights, spec.beta_per_unit, shafts.shaft_lights(spec.quality))[0]",
             "    return [o for o in shadow_maps.shafted_split(scene, lights, spec.beta_per_unit,\n"
             "                                                 shafts.shaft_lights(spec.quality))[0]\n"
             "            if o.data.type != \"AREA\"]",
             ("tests/test_shaft_scenes.py::test_shaft_scene_against_path_tracing[softbox_colonnade]",)),
    Mutation("shaft_cap_ignored", "a city's lamps all shafted whatever the Quality (its memory and time grow with "
             "every lamp's map and shaft group)", "shadow_maps.shafted_split",
             "    if cap is None or len(casting) <= cap:",
             "    if True:",
             ("tests/test_city_night.py::test_the_quality_shafts_its_most_important_lights",)),
    Mutation("shaft_cap_least_important", "the Quality's shafted lights taken from the least important (the lamps "
             "nearest the camera glow unshadowed)", "shadow_maps.shafted_split",
             "    kept = set(np.argsort(-weight, kind=\"stable\")[:cap].tolist())",
             "    kept = set(np.argsort(weight, kind=\"stable\")[:cap].tolist())",
             ("tests/test_city_night.py::test_the_quality_shafts_its_most_important_lights",)),
    Mutation("map_budget_ignored", "every still shadow map full however many lights (memory grows with the lights)",
             "shaft_maps.map_levels",
             "    if full.sum() <= budget or not len(w):",
             "    if True:",
             ("tests/test_map_budget.py::test_many_maps_stay_within_the_budget",)),
    Mutation("map_budget_unweighted", "the maps' budget shared evenly, not as each light's weight^(2/3)",
             "shaft_maps.map_levels",
             "    share = w ** (2.0 / 3.0)",
             "    share = np.ones_like(w)",
             ("tests/test_map_budget.py::test_grid_points_go_as_the_weight_to_two_thirds",)),
    Mutation("map_level_error_dropped", "the shrunk shadow maps' error left out of the predicted error",
             "left_out.shadow_fog",
             "        out[\"missing\"] += out[\"maps\"]",
             "        out[\"missing\"] += 0.0",
             ("tests/test_city_night.py::test_shrunk_maps_are_in_the_predicted_error",)),
    Mutation("auto_shafts_free", "Auto's predicted cost counts a shafted light as an unshafted one (100 street lamps "
             "predicted 1.66x, measured 2.7x)", "auto.predicted_ratio",
             "(n + SHAFT_LOAD * max(int(shafted), 0))",
             "(n + 0.0 * max(int(shafted), 0))",
             ("tests/test_city_night.py::test_auto_predicts_the_citys_measured_cost",)),
    Mutation("cap_share_alone", "the shadows the Quality's cap leaves out judged as a share of the left-out lamps' "
             "fog alone (the shafted lamps' fog left out of the denominator: 20 street lamps at Draft 618 %)",
             "left_out.shadow_fog",
             "                                        if casting else ()) if unshafted else None",
             "                                        if False else ()) if unshafted else None",
             ("tests/test_city_night.py::test_the_quality_shafts_its_most_important_lights",)),
    Mutation("sums_untied", "the compositor's sums over the lights not tied step by step (each light's buffers live "
             "from the first sum's pass to the last: memory grows with lights x pixels)", "comp_ops.in_step",
             "    if len(keys) > 1:",
             "    if False:",
             ("tests/test_city_night.py::test_a_city_of_lamps_in_bounded_memory",)),
    Mutation("preview_no_glowing_points", "viewport preview: the glowing objects not sampled beside the lights "
             "(no glow of theirs in the preview)", "compositor.sampled_points",
             "    return points",
             "    return None",
             ("tests/test_viewport_preview.py::test_viewport_glows_a_glowing_object",)),
    Mutation("preview_glowing_needs_lamps", "viewport preview: the glowing objects previewed only where the preview "
             "holds lamps (a scene lit by glowing objects alone shows no fog in the viewport)",
             "compositor.sampled_points",
             "    if points is None:",
             "    if points is None or not (plan.preview and plan.preview[0]):",
             ("tests/test_emitter_surfaces.py::test_the_viewport_shows_a_glowing_objects_light_on_the_ground",)),
    Mutation("preview_sampled_no_surface_light", "viewport preview: the sampled lights and glowing objects give the "
             "surfaces no fog light (the ground under a neon bar 0.80 of path tracing)",
             "preview_sampled.build_surface_group",
             "    terms = light_groups.read(m, node, rungs.SURFACE_OUTPUTS, shading.LightTerms)",
             "    terms = light_groups.read(m, node, rungs.SURFACE_OUTPUTS, shading.LightTerms)\n"
             "    terms = terms._replace(scattered=m.scale(terms.scattered, 0.0))",
             ("tests/test_emitter_surfaces.py::test_the_viewport_shows_a_glowing_objects_light_on_the_ground",)),
    Mutation("compositor_no_glass_glow", "glass, Compositor: no glow along the segment past a pane",
             "compositor._tails",
             "    return glass_tails.Tails(kept,",
             "    return False and glass_tails.Tails(kept,",
             ("tests/test_glass_mirror.py::test_fog_past_glass_and_mirrors[glass_box-compositor]",)),
    Mutation("compositor_no_segment_light", "glass, Compositor: no fog light on the surfaces seen past a pane",
             "surface_group.build_surface",
             "        segment_lights = [node.outputs[\"Fog\"] for node, _ in placed_segment]",
             "        segment_lights = []",
             ("tests/test_glass_mirror.py::test_fog_past_glass_and_mirrors[glass_box-compositor]",)),
    Mutation("principled_glass_no_tails", "glass: nothing past a Principled BSDF of transmission 1",
             "caveats.is_glass",
             '    weight = node.inputs.get("Transmission Weight") if node.bl_idname == "ShaderNodeBsdfPrincipled" else None\n',
             '    weight = None\n',
             ("tests/test_glass_mirror.py::test_fog_past_glass_and_mirrors[principled_box-compositor]",)),
    Mutation("principled_transmission_lit", "glass: a Principled BSDF's transmitted share lit as its diffuse base",
             "surface.principled_to_phong",
             "1.0 if isinstance(transmission, (int, float)) and transmission == 0.0 else 1.0 - transmission",
             "1.0",
             ("tests/test_glass_mirror.py::test_fog_past_glass_and_mirrors[principled_box-compositor]",)),
    Mutation("compositor_panoramic_rays", "panoramic camera, Compositor: the pixels' rays from a perspective frame",
             "build_fog_group",
             "        ray = p[DIRECTION_AOV[0]]\n",
             "        pass\n",
             ("tests/test_panoramic.py::test_panoramic_camera_against_path_tracing[compositor]",)),
    Mutation("preview_no_day_light", "viewport preview: no sun's and sky's glow and fog light on surfaces",
             "surface_group.build_surface",
             "        if day_preview is not None:   # the sun's and the sky's glow and fog light, as the node groups give them\n",
             "        if False:\n",
             ("tests/test_viewport_preview.py::test_viewport_shows_the_daylight[cycles]",)),
    Mutation("preview_sky_undimmed", "viewport preview: the sky seen through the fog layer undimmed",
             "world_group.build_world",
             "        if day_preview is not None:   # the sky through the layer where the preview shows (``preview.blend``)\n",
             "        if False:\n",
             ("tests/test_viewport_preview.py::test_viewport_shows_the_daylight[cycles]",)),
    Mutation("glass_mix_unweighted", "glass in a mix: the tails take the glass's full weight, not its share",
             "material._build",
             "        ops.feed(own, _weight(ops, glass_weight, ops.memo) * factor)\n",
             "        ops.feed(own, factor)\n",
             ("tests/test_glass_mirror.py::test_fog_past_glass_and_mirrors[mixed_box-nodes]",)),
    Mutation("segment_pass_through_lost", "glass: what a vertex lets straight through on a segment gets no tail",
             "glass_tails.place_tails",
             "                             \"Straight Weight\": (m.scale(glass, 1.0 - f) - seg3 + through).sock,\n",
             "                             \"Straight Weight\": (m.scale(glass, 1.0 - f) - seg3).sock,\n",
             ("tests/test_glass_mirror.py::test_fog_past_glass_and_mirrors[mixed_box-nodes]",)),
    Mutation("tail_pick_unweighted", "glass, Compositor: a sample's one tail light not weighted by 1 / its probability",
             "sampling.picked",
             "    return gate, 1.0 / chances[k]\n",
             "    return gate, 1.0\n",
             ("tests/test_preview_sampled.py::test_a_sample_takes_one_tail_light_and_its_mean_is_every_light",)),
    Mutation("rough_glass_no_segment", "frosted glass: the rays it lets through are no segments of their own",
             "glass_tails.specular_segment",
             '    through = m.maximum(singular, m.wrap(path.outputs["Is Transmission Ray"]))\n',
             "    through = singular\n",
             ("tests/test_glass_mirror.py::test_fog_past_glass_and_mirrors[rough_box-nodes]",)),
    Mutation("glass_tails_unshadowed", "glass, Compositor: the glows past a pane without their lights' shadows",
             "build_tail_bundle",
             '''                m.wrap(shares[j].outputs["Share"]) if shares else None)).light''',
             "                None)).light",
             ("tests/test_shop_window.py::test_shop_window_against_path_tracing[compositor]",)),
    Mutation("compositor_pass_no_light", "fog passes, Compositor: the Fog Light pass holds no light",
             "build_fog_group",
             "    m.feed(gout.inputs[passes.FOG_LIGHT], fog)\n",
             "    m.feed(gout.inputs[passes.FOG_LIGHT], m.scale(fog, 0.5))\n",
             ("tests/test_passes.py::test_compositor_passes_are_the_fogs_part",)),
    Mutation("compositor_pass_transmittance", "fog passes, Compositor: Fog Transmittance left at 1, not the "
             "materials' e^{-beta D}",
             "build_fog_group",
             "compose.dimmed(m, m.combine(t, t, t), factor)",
             "compose.dimmed(m, m.combine(1.0, 1.0, 1.0), factor)",
             ("tests/test_passes.py::test_compositor_passes_are_the_fogs_part",)),
    Mutation("dense_fog_uncounted", "Dense Fog off: what the multiply scattered light leaves out is not in the "
             "predicted error", "choose_models",
             '    choice["error"] += choice["dense"]["missing"] + choice["dense"].get("surplus_missing", 0.0)\n',
             '    choice["error"] += choice["dense"].get("surplus_missing", 0.0)\n',
             ("tests/test_multiple_render.py::test_dense_fog_off_is_the_single_scattering",)),
    Mutation("dense_fog_not_default", "Dense Fog off by default: a lamp in dense fog renders single scattering",
             "AnalyticFogSettings",
             'name="Dense Fog (Multiple Scattering)", default=True,',
             'name="Dense Fog (Multiple Scattering)", default=False,',
             ("tests/test_multiple_render.py::test_dense_fog_glow_against_64_bounces[4.5-cycles-compositor]",)),
    Mutation("dense_steps_single", "the ladder's steps judged without the multiply scattered terms Dense Fog adds",
             "choose_models",
             "spec.anisotropy, spec.grey_albedo if dense else None, scale)",
             "spec.anisotropy, None, scale)",
             ("tests/test_quality.py::test_measured_error_within_prediction[daylit:5-final]",)),
    Mutation("shadows_uncounted", "Light Shafts off: the shadows the fog lacks are not in the predicted error",
             "plan.plan", '        choice["error"] += choice["shadows"]["missing"]\n', "        pass\n",
             ("tests/test_shaft_scenes.py::test_shafts_off_predicts_what_the_shadows_take[window_room]",)),
    Mutation("shadow_share_lit", "the shadows' predicted share: every quadrature node taken as lit",
             "shadowed_parts",
             "        lit[:, k] = np.nan_to_num(np.asarray(share, float), nan=1.0).clip(0.0, 1.0)\n",
             "        lit[:, k] = 1.0\n",
             ("tests/test_shaft_scenes.py::test_shafts_off_predicts_what_the_shadows_take[window_room]",)),
    Mutation("auto_dense_thin_ignored", "Auto: a spot's Dense Fog asks for the compositor even where the Quality "
             "leaves it out (thin fog)", "_dense_shaped",
             "    return [o.name for o, v in zip(shaped, share) if v > predict.THIN_SHARE * target]\n",
             "    return [o.name for o in shaped]\n",
             ("tests/test_auto_method.py::test_few_samples_keep_the_node_groups",)),
    Mutation("emitters_dense_always", "glowing objects take Dense Fog's kernel even in fog too thin for it (and "
             "lose the flat emitters' facing term)", "emitters_dense",
             "    return bool(parts.max(initial=0.0) > predict.THIN_SHARE * target)\n", "    return True\n",
             ("tests/test_multiple_render.py::test_thin_fog_pays_nothing_and_dense_fog_models_the_rest",)),
]


# The default tier's subset: one mutation of each kind of promise, each killed by a test of seconds -- a term
# of the shading against quadrature (Sun et al. 2005's equations), Eq. 19 written out by hand, the node wiring
# against the numpy twin, the light's node tree against Cycles path tracing, a setting Remove must give back.
QUICK = ("glow_on_surfaces", "view_attenuation", "albedo_nodes", "direct_attenuation_cycles", "restore_light_use_nodes",
         "shaft_visibility")


def quick(mutations=None):
    """The mutations named in ``QUICK`` (KeyError for a name that is not a mutation)."""
    known = {mu.name: mu for mu in (MUTATIONS if mutations is None else mutations)}
    return [known[name] for name in QUICK]


def rest(mutations=None):
    """Every mutation not in ``QUICK``, in ``MUTATIONS``' order."""
    return [mu for mu in (MUTATIONS if mutations is None else mutations) if mu.name not in QUICK]


# --- scratch copies ---------------------------------------------------------------------------------

def repo_files(root=ROOT):
    """The repository's files as in the working tree: tracked and untracked-but-not-ignored, minus deleted."""
    out = subprocess.run(["git", "ls-files", "-z", "--cached", "--others", "--exclude-standard"], cwd=root,
                         capture_output=True, check=True).stdout
    names = sorted({n for n in out.decode().split("\0") if n})
    return [n for n in names if (root / n).is_file() and not n.startswith(".venv/")]


def snapshot(dest, rev=None, root=ROOT):
    """Copy the repository into ``dest``: the working tree's files (``repo_files``), or commit ``rev``'s tree
    (``git archive``); ``.venv`` is symlinked.  Returns ``dest``."""
    dest = pathlib.Path(dest)
    dest.mkdir(parents=True)
    if rev:
        tar = subprocess.run(["git", "archive", "--format=tar", rev], cwd=root, capture_output=True, check=True)
        subprocess.run(["tar", "-x", "-C", str(dest)], input=tar.stdout, check=True)
    else:
        for name in repo_files(root):
            target = dest / name
            target.parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(root / name, target)
    venv = root / ".venv"
    if venv.exists():
        (dest / ".venv").symlink_to(venv.resolve(), target_is_directory=True)
    return dest


def copy_snapshot(src, dest):
    """A fresh copy of a snapshot (its ``.venv`` stays a symlink)."""
    return pathlib.Path(shutil.copytree(src, dest, symlinks=True))


# --- where a mutation applies -----------------------------------------------------------------------

PACKAGE = "fog_addon"   # the symbols a mutation may name are defined under this folder


class Symbol(NamedTuple):
    """One definition under ``PACKAGE``: a def, a class, or a constant (a name assigned at module or class level)."""
    dotted: str   # module.qualified_name: fog_addon.precompute.model.shading.shade_point, fog_addon.x.Class.method
    kind: str     # "def", "class" or "constant"
    path: str     # file from the repository root
    first: int    # first line (decorators included), 1-based
    last: int     # last line, inclusive


def _definitions(tree, module, path):
    """Every def and class at any depth of ``tree`` and every name assigned outside a function, as Symbols.

    Statements that are not definitions (``if``, ``try``, ``with``, ...) are looked into but add nothing to the
    qualified name, as in Python's own ``__qualname__`` (minus its ``<locals>``)."""
    found = []

    def visit(node, qual, in_function):
        for child in ast.iter_child_nodes(node):
            if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
                first = min([child.lineno] + [d.lineno for d in child.decorator_list])
                kind = "class" if isinstance(child, ast.ClassDef) else "def"
                found.append(Symbol(".".join([module, *qual, child.name]), kind, path, first, child.end_lineno))
                visit(child, qual + [child.name], kind == "def")
            elif isinstance(child, (ast.Assign, ast.AnnAssign)):
                if not in_function:
                    targets = child.targets if isinstance(child, ast.Assign) else [child.target]
                    names = [n for t in targets for n in (t.elts if isinstance(t, (ast.Tuple, ast.List)) else [t])]
                    for n in names:
                        if isinstance(n, ast.Name):
                            found.append(Symbol(".".join([module, *qual, n.id]), "constant", path, child.lineno,
                                                child.end_lineno))
            elif isinstance(child, (ast.stmt, ast.excepthandler, ast.match_case)):
                visit(child, qual, in_function)

    visit(tree, [], False)
    return found


_INDEX_CACHE = {}


def symbols(root=ROOT):
    """(Symbols of every ``.py`` file under ``root/PACKAGE``, {file: why it could not be parsed}).

    Cached on the files' names, sizes and modification times."""
    root = pathlib.Path(root)
    files = sorted(p for p in (root / PACKAGE).rglob("*.py")
                   if not any(part.startswith((".", "__pycache__")) for part in p.relative_to(root).parts))
    key = (str(root), tuple((str(p), p.stat().st_mtime_ns, p.stat().st_size) for p in files))
    if key not in _INDEX_CACHE:
        found, broken = [], {}
        for p in files:
            rel = p.relative_to(root)
            parts = list(rel.with_suffix("").parts)
            module = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
            try:
                tree = ast.parse(p.read_text(), filename=str(rel))
            except (SyntaxError, ValueError, UnicodeDecodeError) as e:
                broken[rel.as_posix()] = f"{type(e).__name__}: {e}"
                continue
            found += _definitions(tree, module, rel.as_posix())
        if len(_INDEX_CACHE) > 8:
            _INDEX_CACHE.clear()
        _INDEX_CACHE[key] = (found, broken)
    return _INDEX_CACHE[key]


def find_symbol(target, root=ROOT):
    """The one Symbol whose dotted name ends with ``target``'s dotted parts: ``NAME``, ``Class.method``,
    ``outer.inner``, ``module.NAME`` or the whole ``fog_addon.module.NAME``.  A bare name is found wherever it is
    defined under ``PACKAGE``, so a move to another module needs no edit.  ValueError if none or several match
    (qualify the name then)."""
    want = target.split(".")
    found, broken = symbols(root)
    hits = [s for s in found if s.dotted.split(".")[-len(want):] == want]
    if len(hits) == 1:
        return hits[0]
    if not hits:
        unparsed = "".join(f"; could not parse {f} ({why})" for f, why in broken.items())
        raise ValueError(f"no def, class or constant {target!r} under {PACKAGE}/{unparsed}")
    places = ", ".join(f"{s.dotted} ({s.kind}, {s.path}:{s.first})" for s in hits)
    raise ValueError(f"{target!r} names {len(hits)} definitions under {PACKAGE}/: {places} "
                     f"(qualify it: Class.method, outer.inner or module.name)")


def _lines(text):
    """``text`` cut after each newline, as ``ast`` numbers lines (``str.splitlines`` also cuts at form feeds)."""
    parts = text.split("\n")
    return [p + "\n" for p in parts[:-1]] + ([parts[-1]] if parts[-1] else [])


def _indent(line):
    return line[:len(line) - len(line.lstrip(" \t"))]


def _occurrences(text, old):
    """Start offsets of ``old`` in ``text``, overlapping ones included."""
    starts, i = [], text.find(old)
    while i >= 0:
        starts.append(i)
        i = text.find(old, i + 1)
    return starts


def replace_in_symbol(text, first, last, old, new):
    """``text`` with ``old`` replaced by ``new`` inside lines ``first``..``last`` (1-based, inclusive).

    ``old`` and ``new`` are written as the symbol reads dedented: its first line's indentation is taken off
    every line of the span that starts with it before ``old`` is looked for, and put back on the lines the
    replacement makes (the line the match starts on as it was, every further non-blank line of ``new``), so a
    move that changes the symbol's indentation does not change the mutation.  Returns (new text, number of
    occurrences of ``old`` in the span); the text is None unless that number is 1."""
    lines = _lines(text)
    span = lines[first - 1:last]
    indent = _indent(span[0]) if span else ""
    stripped = [bool(indent) and line.startswith(indent) for line in span]
    flat = [line[len(indent):] if s else line for line, s in zip(span, stripped)]
    dedented = "".join(flat)
    starts = _occurrences(dedented, old) if old else []
    if len(starts) != 1:
        return None, len(starts)
    begin, end = starts[0], starts[0] + len(old)
    offsets = [0]
    for line in flat:
        offsets.append(offsets[-1] + len(line))
    i = max(k for k in range(len(flat)) if offsets[k] <= begin)
    j = max(k for k in range(len(flat)) if offsets[k] <= end - 1)
    region = _lines(flat[i][:begin - offsets[i]] + new + flat[j][end - offsets[j]:])
    region = [(indent if (stripped[i] if n == 0 else line.strip()) else "") + line for n, line in enumerate(region)]
    return "".join(lines[:first - 1 + i] + region + lines[first + j:]), 1


def check(mutation, root=ROOT):
    """(file from the repository root, its text with the mutation applied); raises ValueError unless
    ``mutation.target`` names exactly one symbol under ``PACKAGE`` whose source holds ``mutation.old`` exactly
    once."""
    try:
        sym = find_symbol(mutation.target, root)
    except ValueError as e:
        raise ValueError(f"mutation {mutation.name}: {e} (update tools/mutations.py)") from None
    mutated, n = replace_in_symbol((pathlib.Path(root) / sym.path).read_text(), sym.first, sym.last,
                                   mutation.old, mutation.new)
    if n != 1:
        raise ValueError(f"mutation {mutation.name}: the old text occurs {n} times in {sym.dotted} "
                         f"({sym.kind}, {sym.path} lines {sym.first}-{sym.last}; must be exactly once; "
                         f"update tools/mutations.py):\n{mutation.old!r}")
    return sym.path, mutated


def apply(mutation, root):
    """Apply ``mutation`` to the repository copy ``root``; returns the file it changed."""
    path, mutated = check(mutation, root)
    (pathlib.Path(root) / path).write_text(mutated)
    return path


# --- running ----------------------------------------------------------------------------------------

def _python():
    venv = ROOT / ".venv" / "bin" / "python"
    return str(venv) if venv.exists() else sys.executable


def run_pytest(repo, tests, tmpdir, stop_first=True, timeout=900):
    """Run ``tests`` in the copy ``repo``; returns (exit code, failing node ids, output, seconds)."""
    tmpdir = pathlib.Path(tmpdir)
    tmpdir.mkdir(parents=True, exist_ok=True)
    env = {k: v for k, v in os.environ.items()
           if k not in ("PYTHONPATH", "FOG_PYTHON", "PYTEST_ADDOPTS", "BLENDER_USER_RESOURCES")}
    env.update(TMPDIR=str(tmpdir), PYTHONDONTWRITEBYTECODE="1", FOG_REGEN_REFERENCES="0",
               COLUMNS="400")   # pytest cuts its one-line reasons at the terminal width
    python = str(pathlib.Path(repo) / ".venv" / "bin" / "python")
    if not os.path.exists(python):
        python = _python()
    cmd = [python, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-rfE"] + (["-x"] if stop_first else []) \
        + list(tests)
    t0 = time.perf_counter()
    try:
        p = subprocess.run(cmd, cwd=repo, env=env, capture_output=True, text=True, timeout=timeout)
        code, output = p.returncode, p.stdout + p.stderr
    except subprocess.TimeoutExpired as e:
        code, output = -1, f"timed out after {timeout} s\n{e.stdout or ''}"
    seconds = time.perf_counter() - t0
    failed = []   # (node id, pytest's one-line reason)
    for line in output.splitlines():
        hit = re.match(r"(FAILED|ERROR) (\S+)(?: - (.*))?", line)
        if hit:
            node = hit.group(2)
            failed.append((node if node.startswith("tests/") else "tests/" + node, hit.group(3) or ""))
    details = [line[1:].strip() for line in output.splitlines() if line.startswith("E ") and line[1:].strip()]
    if failed and len(failed[0][1].rstrip(": ")) < 20 and details:   # a bare "AssertionError": say more
        failed[0] = (failed[0][0], "; ".join(details[:3]))
    return code, failed, output, seconds


def run_mutation(mutation, base, scratch, keep=False):
    """Apply ``mutation`` to a fresh copy of snapshot ``base`` under ``scratch`` and run its killers."""
    work = pathlib.Path(tempfile.mkdtemp(prefix=mutation.name + "-", dir=scratch))
    try:
        repo = copy_snapshot(base, work / "repo")
        changed = apply(mutation, repo)
        code, failed, output, seconds = run_pytest(repo, mutation.killers, work / "tmp")
    finally:
        if not keep:
            shutil.rmtree(work, ignore_errors=True)
    status = {0: "SURVIVED", 1: "killed"}.get(code, "ERROR")
    return {"name": mutation.name, "what": mutation.what, "target": mutation.target, "file": changed,
            "status": status,
            "killed_by": failed[0][0] if (status == "killed" and failed) else None,
            "reason": failed[0][1] if (status == "killed" and failed) else None, "exit_code": code,
            "seconds": round(seconds, 1), "output": None if status == "killed" else output[-4000:]}


def baseline(mutations, base, scratch):
    """Every killer on an unmutated copy of ``base`` (all must pass): a result dict with ok, seconds, output."""
    work = pathlib.Path(tempfile.mkdtemp(prefix="baseline-", dir=scratch))
    try:
        repo = copy_snapshot(base, work / "repo")
        tests = list(dict.fromkeys(t for mu in mutations for t in mu.killers))
        code, _, output, seconds = run_pytest(repo, tests, work / "tmp", stop_first=False)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    return {"ok": code == 0, "seconds": round(seconds, 1), "output": None if code == 0 else output[-4000:]}


def run_all(mutations, keep=False, with_baseline=False, rev=None, log=None):
    """Snapshot the repository once (working tree, or commit ``rev``), check every mutation applies to it,
    then run the baseline (if asked) and each mutation on copies of it.

    Returns (results, baseline result or None); raises ValueError if a mutation does not apply.
    """
    scratch = tempfile.mkdtemp(prefix="fog_mutations-", dir=os.environ.get("TMPDIR") or None)
    try:
        base = snapshot(pathlib.Path(scratch) / "snapshot", rev)
        for mu in mutations:
            check(mu, base)
        base_result = None
        if with_baseline:
            base_result = baseline(mutations, base, scratch)
            if log:
                log(f"baseline: {'passed' if base_result['ok'] else 'FAILED'} in {base_result['seconds']} s")
            if not base_result["ok"]:
                return [], base_result   # a kill would prove nothing
        results = []
        for mu in mutations:
            res = run_mutation(mu, base, scratch, keep)
            results.append(res)
            if log:
                log(f"{res['name']}: {res['status']} by {res['killed_by']} in {res['seconds']} s")
    finally:
        if not keep:
            shutil.rmtree(scratch, ignore_errors=True)
    return results, base_result


# --- output -----------------------------------------------------------------------------------------

def _short(node):
    return node.replace("tests/", "", 1)


def list_text(mutations):
    return "\n".join(f"{mu.name:32} {mu.target:34} {mu.what}\n{'':32} killers: {', '.join(mu.killers)}"
                     for mu in mutations)


def markdown(mutations):
    rows = ["| mutation | what it removes | symbol | killed by |", "|---|---|---|---|"]
    for mu in mutations:
        rows.append(f"| `{mu.name}` | {mu.what} | `{mu.target}` | `{_short(mu.killers[0])}` |")
    return "\n".join(rows)


README = ROOT / "docs" / "testing.md"   # where the table lives
BEGIN, END = "<!-- tools/mutations.py --markdown: begin -->", "<!-- tools/mutations.py --markdown: end -->"


def readme_table(text):
    """The table between the markers in README text (None without the markers)."""
    if BEGIN not in text or END not in text:
        return None
    return text.split(BEGIN, 1)[1].split(END, 1)[0].strip("\n")


def update_readme(mutations, path=README):
    """Write ``markdown(mutations)`` between the markers in the README; returns True if it changed."""
    text = path.read_text()
    if readme_table(text) is None:
        raise ValueError(f"{path} has no {BEGIN} ... {END} markers")
    head, rest = text.split(BEGIN, 1)
    new = f"{head}{BEGIN}\n{markdown(mutations)}\n{END}{rest.split(END, 1)[1]}"
    if new != text:
        path.write_text(new)
    return new != text


def table(results):
    rows = [f"{'mutation':32} {'status':9} {'time':>7}  killed by"]
    for r in results:
        rows.append(f"{r['name']:32} {r['status']:9} {r['seconds']:6.1f}s  {r['killed_by'] or '-'}")
    rows.append(f"{'total':32} {'':9} {sum(r['seconds'] for r in results):6.1f}s")
    return "\n".join(rows)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("names", nargs="*", help="run only these mutations")
    ap.add_argument("--list", action="store_true", help="print the mutations and their killers")
    ap.add_argument("--markdown", action="store_true", help="print the README table")
    ap.add_argument("--update-readme", action="store_true", help="write that table into docs/testing.md")
    ap.add_argument("--json", action="store_true", help="print the results as JSON")
    ap.add_argument("--baseline", action="store_true", help="first check every killer passes unmutated")
    ap.add_argument("--keep", action="store_true", help="keep the scratch copies")
    ap.add_argument("--rev", help="mutate this commit's tree (git archive) instead of the working tree")
    which = ap.add_mutually_exclusive_group()
    which.add_argument("--quick", action="store_true", help="only the default test tier's subset (QUICK)")
    which.add_argument("--rest", action="store_true", help="only the mutations not in QUICK (the slow tier)")
    args = ap.parse_args(argv)
    known = {mu.name: mu for mu in MUTATIONS}
    unknown = [n for n in args.names if n not in known]
    if unknown:
        ap.error(f"unknown mutation(s) {unknown}; --list shows them")
    chosen = [known[n] for n in args.names] if args.names else MUTATIONS
    if args.quick or args.rest:
        if args.names:
            ap.error("--quick / --rest choose the mutations: give no NAME with them")
        chosen = quick() if args.quick else rest()
    if args.list:
        print(list_text(chosen))
        return 0
    if args.markdown:
        print(markdown(chosen))
        return 0
    if args.update_readme:
        print(f"{README.relative_to(ROOT)} " + ("updated" if update_readme(MUTATIONS) else "already up to date"))
        return 0
    try:
        results, base = run_all(chosen, args.keep, args.baseline, args.rev,
                                log=None if args.json else lambda s: print(s, file=sys.stderr, flush=True))
    except ValueError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    if args.json:
        print(json.dumps({"baseline": base, "mutations": results}, indent=1))
    else:
        print(table(results))
        for r in results:
            if r["status"] != "killed":
                print(f"\n--- {r['name']} {r['status']} (exit {r['exit_code']}) ---\n{r['output']}")
        if base and not base["ok"]:
            print(f"\n--- baseline FAILED ---\n{base['output']}")
    ok = all(r["status"] == "killed" for r in results) and (base is None or base["ok"])
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
