"""A neon sign over a street in fog (tests/test_emitter_glow.py): a grey Lambertian ground, a 1 m emissive square
(Emission shader, pink, strength 20) standing 8 m ahead with its centre 2 m up, facing the camera (both faces emit),
no lights, World black; camera 1.6 m up looking 5 degrees down, 160 x 90, clip 1 mm to 1 km.  The sign's top is cut
by the frame's edge.  Usage: python tests/scenes/neon_sign.py OUT.blend"""
import bpy, sys, math
bpy.ops.wm.read_factory_settings(use_empty=True)
scene = bpy.context.scene
scene.render.engine = "CYCLES"
world = bpy.data.worlds.new("World"); scene.world = world
world.use_nodes = True; world.node_tree.nodes["Background"].inputs[1].default_value = 0.0
def plane(name, size, loc, rot, mat):
    bpy.ops.mesh.primitive_plane_add(size=size, location=loc, rotation=rot)
    o = bpy.context.object; o.name = name; o.data.materials.append(mat); return o
ground = bpy.data.materials.new("Ground"); ground.use_nodes = True
b = ground.node_tree.nodes["Principled BSDF"]; b.inputs["Base Color"].default_value = (0.5, 0.5, 0.5, 1); b.inputs["Roughness"].default_value = 1.0; b.inputs["Specular IOR Level"].default_value = 0.0
plane("Ground", 60, (0, 10, 0), (0, 0, 0), ground)
neon = bpy.data.materials.new("Neon"); neon.use_nodes = True
nt = neon.node_tree; nt.nodes.remove(nt.nodes["Principled BSDF"])
em = nt.nodes.new("ShaderNodeEmission"); em.inputs["Color"].default_value = (1.0, 0.3, 0.6, 1); em.inputs["Strength"].default_value = 20.0
nt.links.new(em.outputs[0], nt.nodes["Material Output"].inputs["Surface"])
plane("Sign", 1.0, (0, 8, 2.0), (math.radians(90), 0, 0), neon)   # a vertical sign facing the camera (-Y) and +Y
cam = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera")); scene.collection.objects.link(cam); scene.camera = cam
cam.location = (0, 0, 1.6); cam.rotation_euler = (math.radians(85), 0, 0); cam.data.clip_start = 0.001; cam.data.clip_end = 1000
scene.render.resolution_x, scene.render.resolution_y = 160, 90
bpy.ops.wm.save_as_mainfile(filepath=sys.argv[-1])
