"""Imports an `svbtdf export` glTF into Blender, renders it with Cycles on the CPU in front of a
checkerboard, and measures how much each region of the sample blurs the checkerboard against the
exported roughness (docs/export.md, tests/export/gltf_blender_test.cc).

Run headless:
  blender -b --factory-startup --python tools/blender/render_export.py -- \
      --gltf OUT/name.gltf --png picture.png [--json result.json] [--regions X Y]
             [--resolution 240] [--samples 32] [--distance 0.02] [--checker 0.003]

The JSON records what the importer made of the material (roughness, transmission, IOR), each
region's exported roughness and blur, their Spearman rank correlation, and the seconds taken.
With --regions the sample is split into X x Y equal regions (the test's material is made of such
regions); without it, no correlation is computed (the demo's picture).

Blender 3.4 (Debian 12) limits: its glTF importer calls numpy.bool, which numpy 1.24 removed,
so it is aliased to bool before importing (the JSON records whether it was missing); it ignores
KHR_materials_anisotropy and KHR_materials_diffuse_transmission.
"""
import argparse
import json
import math
import sys
import time

import numpy

NUMPY_BOOL_MISSING = not hasattr(numpy, "bool")
if NUMPY_BOOL_MISSING:
    numpy.bool = bool  # Blender 3.4's importer (gltf2_blender_mesh.py) still uses the removed alias

import bpy  # noqa: E402


def parse_arguments():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    parser = argparse.ArgumentParser(prog="render_export.py")
    parser.add_argument("--gltf", required=True)
    parser.add_argument("--png", required=True)
    parser.add_argument("--json")
    parser.add_argument("--regions", type=int, nargs=2)
    parser.add_argument("--resolution", type=int, default=240, help="pixels across the sample's width")
    parser.add_argument("--samples", type=int, default=32)
    parser.add_argument("--distance", type=float, default=0.02, help="checkerboard behind the sample, metres")
    parser.add_argument("--checker", type=float, default=0.003, help="checker square, metres")
    return parser.parse_args(argv)


def import_sample(path):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.import_scene.gltf(filepath=path)
    meshes = [o for o in bpy.context.scene.objects if o.type == "MESH"]
    if len(meshes) != 1:
        raise SystemExit(f"{path}: expected one mesh, Blender imported {len(meshes)}")
    return meshes[0]


def principled(material):
    for node in material.node_tree.nodes:
        if node.type == "BSDF_PRINCIPLED":
            return node
    raise SystemExit(f"material {material.name}: the importer made no Principled BSDF")


def describe_material(sample):
    """What the importer carried over: a linked socket is a texture, otherwise its value."""
    node = principled(sample.active_material)

    def socket(name):
        s = node.inputs[name]
        return {"linked": s.is_linked, "value": None if s.is_linked else float(s.default_value)}

    return {"name": sample.active_material.name, "roughness": socket("Roughness"),
            "transmission": socket("Transmission"), "ior": socket("IOR")}


def sample_extent(sample):
    xs = [(sample.matrix_world @ v.co).x for v in sample.data.vertices]
    zs = [(sample.matrix_world @ v.co).z for v in sample.data.vertices]
    return min(xs), max(xs), min(zs), max(zs)


def build_scene(sample, args):
    """glTF's +z (the sample's camera side) is Blender's -y: the camera looks along +y, straight
    through the sample, at an emissive checkerboard `distance` behind it."""
    x0, x1, z0, z1 = sample_extent(sample)
    width, height = x1 - x0, z1 - z0
    scene = bpy.context.scene
    world = bpy.data.worlds.new("black")
    world.color = (0, 0, 0)
    scene.world = world

    bpy.ops.mesh.primitive_plane_add(size=4 * max(width, height), location=(0, args.distance, 0), rotation=(math.pi / 2, 0, 0))
    board = bpy.context.active_object
    material = bpy.data.materials.new("checkerboard")
    material.use_nodes = True
    nodes, links = material.node_tree.nodes, material.node_tree.links
    nodes.clear()
    checker = nodes.new("ShaderNodeTexChecker")
    checker.inputs["Color1"].default_value = (1, 1, 1, 1)
    checker.inputs["Color2"].default_value = (0.05, 0.05, 0.05, 1)
    checker.inputs["Scale"].default_value = 4 * max(width, height) / args.checker
    coords = nodes.new("ShaderNodeTexCoord")
    emission = nodes.new("ShaderNodeEmission")
    output = nodes.new("ShaderNodeOutputMaterial")
    links.new(checker.inputs["Vector"], coords.outputs["UV"])
    links.new(emission.inputs["Color"], checker.outputs["Color"])
    links.new(output.inputs["Surface"], emission.outputs["Emission"])
    board.data.materials.append(material)

    camera_data = bpy.data.cameras.new("camera")
    camera_data.type = "ORTHO"
    camera_data.ortho_scale = max(width, height)
    camera = bpy.data.objects.new("camera", camera_data)
    camera.location = ((x0 + x1) / 2, -0.5, (z0 + z1) / 2)
    camera.rotation_euler = (math.pi / 2, 0, 0)
    scene.collection.objects.link(camera)
    scene.camera = camera

    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = args.samples
    scene.cycles.use_denoising = False
    scene.cycles.seed = 1
    scene.render.resolution_x = args.resolution
    scene.render.resolution_y = max(1, round(args.resolution * height / width))
    scene.render.resolution_percentage = 100
    scene.render.image_settings.file_format = "PNG"
    scene.view_settings.view_transform = "Standard"


def render(path):
    bpy.context.scene.render.filepath = path
    bpy.ops.render.render(write_still=True)
    image = bpy.data.images.load(path)
    w, h = image.size
    pixels = numpy.array(image.pixels[:], dtype=numpy.float64).reshape(h, w, image.channels)
    return pixels[::-1, :, :3]  # Blender's rows start at the bottom


def region_means(image, regions_x, regions_y, margin=0.2):
    """Per region (row-major from the top left, the material's order), the inner part's pixels."""
    h, w = image.shape[:2]
    for ry in range(regions_y):
        for rx in range(regions_x):
            x0, x1 = rx * w / regions_x, (rx + 1) * w / regions_x
            y0, y1 = ry * h / regions_y, (ry + 1) * h / regions_y
            mx, my = margin * (x1 - x0), margin * (y1 - y0)
            yield image[int(y0 + my):int(y1 - my), int(x0 + mx):int(x1 - mx)]


def ranks(values):
    order = sorted(range(len(values)), key=lambda i: values[i])
    result = [0.0] * len(values)
    i = 0
    while i < len(order):  # ties share their mean rank
        j = i
        while j + 1 < len(order) and values[order[j + 1]] == values[order[i]]:
            j += 1
        for k in range(i, j + 1):
            result[order[k]] = (i + j) / 2
        i = j + 1
    return result


def spearman(a, b):
    ra, rb = ranks(a), ranks(b)
    ma, mb = sum(ra) / len(ra), sum(rb) / len(rb)
    cov = sum((x - ma) * (y - mb) for x, y in zip(ra, rb))
    var = math.sqrt(sum((x - ma) ** 2 for x in ra) * sum((y - mb) ** 2 for y in rb))
    return cov / var if var > 0 else float("nan")


def exported_roughness(gltf_path):
    """The metallic-roughness texture's G channel as the export wrote it (0..1)."""
    with open(gltf_path) as f:
        gltf = json.load(f)
    material = gltf["materials"][0]
    index = material["pbrMetallicRoughness"]["metallicRoughnessTexture"]["index"]
    uri = gltf["images"][gltf["textures"][index]["source"]]["uri"]
    import os
    image = bpy.data.images.load(os.path.join(os.path.dirname(os.path.abspath(gltf_path)), uri))
    image.colorspace_settings.name = "Non-Color"
    w, h = image.size
    pixels = numpy.array(image.pixels[:], dtype=numpy.float64).reshape(h, w, image.channels)
    return pixels[::-1, :, 1]


def main():
    args = parse_arguments()
    start = time.monotonic()
    sample = import_sample(args.gltf)
    result = {"blender": bpy.app.version_string, "numpy": numpy.__version__,
              "numpy_bool_alias_needed": NUMPY_BOOL_MISSING, "material": describe_material(sample)}
    build_scene(sample, args)
    picture = render(args.png)
    result["png"] = args.png
    if args.regions:
        luminance = picture @ numpy.array([0.2126, 0.7152, 0.0722])
        roughness = exported_roughness(args.gltf)
        rx, ry = args.regions
        regions = []
        for pixels, texels in zip(region_means(luminance, rx, ry), region_means(roughness, rx, ry)):
            # Blur as the loss of the checkerboard's contrast: 1 - std / mean (std/mean of a sharp
            # two-level checkerboard is about 0.9; a fully blurred one has none).
            contrast = float(pixels.std() / max(pixels.mean(), 1e-9))
            regions.append({"roughness": float(texels.mean()), "contrast": contrast, "blur": 1.0 - contrast})
        result["regions"] = regions
        result["spearman_roughness_blur"] = spearman([r["roughness"] for r in regions], [r["blur"] for r in regions])
    result["seconds"] = time.monotonic() - start
    text = json.dumps(result, indent=2)
    print(text)
    if args.json:
        with open(args.json, "w") as f:
            f.write(text + "\n")


main()
