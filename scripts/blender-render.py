# Renders a mesh (.ply, .obj, .stl) or a volume (.vdb: its level set, meshed by Blender's Volume to
# Mesh) the way the papers' figures look: Cycles path tracing, a large soft area light and a sky for
# the light that reaches into folds and pores (the ambient occlusion a path tracer gets for free), the
# object standing on a ground plane that only catches its shadow, on white. Run through Blender in
# background mode (scripts/render-blender.sh does this; docs/user-guide.md, "Rendering with Blender"):
#   blender -b --factory-startup --python-exit-code 1 -P scripts/blender-render.py -- IN -o OUT.png [options]
# Prints "blender-render: OUT.png WxH, N triangles, S s" on success; exits 1 with one line on bad input.
import argparse
import math
import os
import sys
import time

import bpy
import numpy as np
from mathutils import Matrix, Vector


def Fail(message):
    print(f"blender-render: {message}", file=sys.stderr)
    sys.exit(1)


def ParseArguments():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    p = argparse.ArgumentParser(prog="blender-render.py", description=__doc__)
    p.add_argument("input", help="a mesh (.ply, .obj, .stl) or a level set (.vdb)")
    p.add_argument("-o", "--out", required=True, help="the PNG to write")
    p.add_argument("--size", default="1200x900", help="WIDTHxHEIGHT in pixels (default 1200x900)")
    p.add_argument("--samples", type=int, default=64, help="Cycles samples per pixel (default 64)")
    p.add_argument("--color", default="clay",
                   help="the surface colour: clay (default), paper (the 2015 paper's warm gold) or #RRGGBB")
    p.add_argument("--up", choices=["x", "y", "z", "-x", "-y", "-z"], default="y",
                   help="the file's up axis (default y, as the shipped bunny and most scanned meshes)")
    p.add_argument("--view", type=float, nargs=2, default=[35.0, 20.0], metavar=("AZIMUTH", "ELEVATION"),
                   help="camera azimuth and elevation in degrees (default 35 20: a three-quarter view)")
    p.add_argument("--vdb-grid", default="",
                   help="the .vdb's level set grid (default: 'surface', quijibo's, else the file's first grid)")
    p.add_argument("--threads", type=int, default=0, help="render threads (default 0: all cores)")
    a = p.parse_args(argv)
    try:
        w, h = (int(v) for v in a.size.lower().split("x"))
        assert 16 <= w <= 16384 and 16 <= h <= 16384
    except (ValueError, AssertionError):
        Fail(f"--size {a.size}: expected WIDTHxHEIGHT, each 16 to 16384")
    a.width, a.height = w, h
    if a.samples < 1:
        Fail(f"--samples {a.samples}: expected at least 1")
    colours = {"clay": (0.80, 0.74, 0.66), "paper": (0.85, 0.62, 0.22)}
    if a.color in colours:
        a.rgb = colours[a.color]
    elif len(a.color) == 7 and a.color[0] == "#":
        try:
            a.rgb = tuple(int(a.color[i:i + 2], 16) / 255 for i in (1, 3, 5))
        except ValueError:
            Fail(f"--color {a.color}: expected clay, paper or #RRGGBB")
    else:
        Fail(f"--color {a.color}: expected clay, paper or #RRGGBB")
    if not os.path.isfile(a.input):
        Fail(f"{a.input}: no such file")
    return a


def ReadBinaryPly(path):
    """Vertices and triangles of a binary little-endian PLY with float/double x y z first and faces as
    'list uchar int|uint' (what quijibo writes), read with NumPy: Blender's Python PLY importer takes
    minutes for millions of triangles. Returns None for any other layout."""
    with open(path, "rb") as f:
        header = []
        while True:
            line = f.readline()
            if not line:
                return None
            header.append(line.decode("ascii", "replace").strip())
            if header[-1] == "end_header":
                break
        if "format binary_little_endian 1.0" not in header:
            return None
        elements, current = [], None
        for h in header:
            t = h.split()
            if t[:1] == ["element"]:
                current = [t[1], int(t[2]), []]
                elements.append(current)
            elif t[:1] == ["property"] and current is not None:
                current[2].append(t[1:])
        if [e[0] for e in elements] != ["vertex", "face"]:
            return None
        (_, nv, vprops), (_, nf, fprops) = elements
        kinds = {"float": "<f4", "float32": "<f4", "double": "<f8", "float64": "<f8"}
        if [p[-1] for p in vprops] != ["x", "y", "z"] or any(p[0] not in kinds for p in vprops):
            return None
        if len(fprops) != 1 or fprops[0][:3] not in (["list", "uchar", "int"], ["list", "uchar", "uint"],
                                                      ["list", "uint8", "int32"], ["list", "uint8", "uint32"]):
            return None
        vdtype = np.dtype([(p[-1], kinds[p[0]]) for p in vprops])
        v = np.frombuffer(f.read(nv * vdtype.itemsize), dtype=vdtype, count=nv)
        faces = np.frombuffer(f.read(nf * 13), dtype=np.dtype([("n", "u1"), ("i", "<i4", 3)]), count=nf)
        if nf and not np.all(faces["n"] == 3):
            return None
        verts = np.stack([v["x"], v["y"], v["z"]], axis=1).astype(np.float32)
        return verts, faces["i"].astype(np.int32)


def MeshObject(name, verts, tris):
    m = bpy.data.meshes.new(name)
    m.vertices.add(len(verts))
    m.vertices.foreach_set("co", verts.ravel())
    m.loops.add(tris.size)
    m.loops.foreach_set("vertex_index", tris.ravel())
    m.polygons.add(len(tris))
    m.polygons.foreach_set("loop_start", np.arange(0, tris.size, 3, dtype=np.int32))
    m.polygons.foreach_set("loop_total", np.full(len(tris), 3, dtype=np.int32))
    m.update(calc_edges=True)
    m.validate(clean_customdata=False)
    o = bpy.data.objects.new(name, m)
    bpy.context.scene.collection.objects.link(o)
    return o


def ImportMesh(path):
    ext = os.path.splitext(path)[1].lower()
    if ext == ".ply":
        read = ReadBinaryPly(path)
        if read is not None:
            return MeshObject("subject", *read)
        bpy.ops.import_mesh.ply(filepath=path)
    elif ext == ".obj":  # the file's axes as they are (forward y, up z: no conversion); --up turns it
        bpy.ops.wm.obj_import(filepath=path, forward_axis="Y", up_axis="Z")
    elif ext == ".stl":
        bpy.ops.import_mesh.stl(filepath=path, axis_forward="Y", axis_up="Z")
    else:
        Fail(f"{path}: expected .ply, .obj, .stl or .vdb")
    objects = [o for o in bpy.context.selected_objects if o.type == "MESH"]
    if not objects:
        Fail(f"{path}: no mesh in the file")
    o = objects[0]
    o.data.transform(o.matrix_world)
    o.matrix_world = Matrix.Identity(4)
    return o


def ImportVolume(path, grid):
    bpy.ops.object.volume_import(filepath=path, align="WORLD", location=(0, 0, 0))
    vol = bpy.context.active_object
    if vol is None or vol.type != "VOLUME":
        Fail(f"{path}: Blender could not read the volume")
    vol.data.grids.load()
    names = [g.name for g in vol.data.grids]
    if not names:
        Fail(f"{path}: the file has no grid")
    if grid and grid not in names:
        Fail(f"{path}: no grid {grid!r} (grids: {', '.join(names)})")
    # A mesh object whose Volume to Mesh modifier meshes the level set at 0 (quijibo's .vdb: the
    # signed distance or the Julia field's log|q_n|, both negative inside).
    m = bpy.data.meshes.new("subject")
    o = bpy.data.objects.new("subject", m)
    bpy.context.scene.collection.objects.link(o)
    mod = o.modifiers.new("level set", "VOLUME_TO_MESH")
    mod.object = vol
    mod.grid_name = grid or ("surface" if "surface" in names else names[0])
    mod.resolution_mode = "GRID"
    mod.threshold = 0.0
    mod.use_smooth_shade = True
    vol.hide_render = True
    bpy.context.view_layer.update()
    evaluated = o.evaluated_get(bpy.context.evaluated_depsgraph_get())
    data = bpy.data.meshes.new_from_object(evaluated)
    o.modifiers.clear()
    o.data = data
    if not data.polygons:
        Fail(f"{path}: grid {mod.grid_name!r} has no surface at 0")
    return o


def Orient(o, up):
    axis = {"x": Vector((1, 0, 0)), "y": Vector((0, 1, 0)), "z": Vector((0, 0, 1))}[up[-1]]
    if up.startswith("-"):
        axis = -axis
    rotation = axis.rotation_difference(Vector((0, 0, 1))).to_matrix().to_4x4()
    o.data.transform(rotation)
    # Into a box of height about 2 standing on z = 0, centred on the z axis.
    co = np.empty(len(o.data.vertices) * 3, dtype=np.float32)
    o.data.vertices.foreach_get("co", co)
    co = co.reshape(-1, 3)
    lo, hi = co.min(axis=0), co.max(axis=0)
    scale = 2.0 / float(max(hi - lo))
    centre = (lo + hi) / 2
    o.data.transform(Matrix.Scale(scale, 4) @ Matrix.Translation(Vector((-centre[0], -centre[1], -lo[2]))))
    # Smooth shading: quijibo's meshes are welded, so vertex normals follow the surface.
    o.data.polygons.foreach_set("use_smooth", np.ones(len(o.data.polygons), dtype=bool))
    return (hi - lo) * scale


def Material(rgb):
    mat = bpy.data.materials.new("clay")
    mat.use_nodes = True
    nodes = mat.node_tree.nodes
    nodes.clear()
    bsdf = nodes.new("ShaderNodeBsdfPrincipled")
    output = nodes.new("ShaderNodeOutputMaterial")
    mat.node_tree.links.new(bsdf.outputs["BSDF"], output.inputs["Surface"])
    bsdf.inputs["Base Color"].default_value = (*rgb, 1.0)
    bsdf.inputs["Roughness"].default_value = 0.55
    bsdf.inputs["Specular"].default_value = 0.3
    return mat


def Scene(a, o, extent):
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = a.samples
    scene.cycles.use_adaptive_sampling = True
    try:
        scene.cycles.use_denoising = True
        scene.cycles.denoiser = "OPENIMAGEDENOISE"
    except TypeError:  # a build without OpenImageDenoise
        scene.cycles.use_denoising = False
    scene.cycles.max_bounces = 6
    scene.render.resolution_x, scene.render.resolution_y = a.width, a.height
    scene.render.resolution_percentage = 100
    scene.render.film_transparent = True  # the shadow catcher's alpha, composited on white below
    scene.render.threads_mode = "FIXED" if a.threads > 0 else "AUTO"
    if a.threads > 0:
        scene.render.threads = a.threads
    # Standard, not Filmic: the white behind the object stays white.
    scene.view_settings.view_transform = "Standard"
    scene.render.image_settings.file_format = "PNG"
    scene.render.image_settings.color_mode = "RGB"

    o.data.materials.append(Material(a.rgb))

    # Ground: a large plane that shows only the shadow.
    bpy.ops.mesh.primitive_plane_add(size=60, location=(0, 0, 0))
    ground = bpy.context.active_object
    ground.is_shadow_catcher = True

    # Sky: a soft, slightly blue dome light (the ambient term, occluded in the folds).
    world = bpy.data.worlds.new("sky")
    scene.world = world
    world.use_nodes = True
    bg = world.node_tree.nodes["Background"]
    bg.inputs["Color"].default_value = (0.78, 0.84, 0.95, 1.0)
    bg.inputs["Strength"].default_value = 0.35

    # Key: a large area light above, to the left and in front: soft shadows, as in the papers' figures.
    radius = float(np.linalg.norm(extent)) / 2
    bpy.ops.object.light_add(type="AREA", location=(-3.0 * radius, -3.0 * radius, 5.0 * radius))
    key = bpy.context.active_object
    key.data.shape = "DISK"
    key.data.size = 3.0 * radius
    key.data.energy = 250.0 * radius * radius
    key.rotation_euler = (Vector((0, 0, extent[2] / 2)) - key.location).to_track_quat("-Z", "Y").to_euler()

    # Camera: a three-quarter view framing the bounding sphere.
    cam_data = bpy.data.cameras.new("camera")
    cam_data.lens = 60
    cam = bpy.data.objects.new("camera", cam_data)
    scene.collection.objects.link(cam)
    scene.camera = cam
    az, el = (math.radians(v) for v in a.view)
    target = Vector((0, 0, extent[2] / 2))
    # cam_data.angle is the field of view across the longer side; frame across the shorter one.
    fov = 2 * math.atan(math.tan(cam_data.angle / 2) * min(a.width, a.height) / max(a.width, a.height))
    distance = radius / math.sin(fov / 2) * 0.92
    direction = Vector((math.sin(az) * math.cos(el), -math.cos(az) * math.cos(el), math.sin(el)))
    cam.location = target + direction * distance
    cam.rotation_euler = (target - cam.location).to_track_quat("-Z", "Y").to_euler()
    cam_data.clip_start = distance / 100
    cam_data.clip_end = distance * 10

    # Compositing: the render over white.
    scene.use_nodes = True
    tree = scene.node_tree
    tree.nodes.clear()
    layers = tree.nodes.new("CompositorNodeRLayers")
    over = tree.nodes.new("CompositorNodeAlphaOver")
    over.inputs[1].default_value = (1, 1, 1, 1)
    out = tree.nodes.new("CompositorNodeComposite")
    tree.links.new(layers.outputs["Image"], over.inputs[2])
    tree.links.new(over.outputs["Image"], out.inputs["Image"])


def Main():
    a = ParseArguments()
    t0 = time.time()
    bpy.ops.wm.read_factory_settings(use_empty=True)
    if a.input.lower().endswith(".vdb"):
        o = ImportVolume(a.input, a.vdb_grid)
    else:
        o = ImportMesh(a.input)
    loop_total = np.empty(len(o.data.polygons), dtype=np.int32)
    o.data.polygons.foreach_get("loop_total", loop_total)
    triangles = int((loop_total - 2).sum())
    extent = Orient(o, a.up)
    Scene(a, o, extent)
    loaded = time.time() - t0
    bpy.context.scene.render.filepath = os.path.abspath(a.out)
    bpy.ops.render.render(write_still=True)
    if not os.path.isfile(a.out):
        Fail(f"{a.out}: Blender did not write the picture")
    print(f"blender-render: {a.out} {a.width}x{a.height}, {triangles} triangles, {a.samples} samples, "
          f"{time.time() - t0:.1f} s ({loaded:.1f} s loading)")


Main()
