"""Writes the glTF fixtures of this folder, each built by hand per the glTF
2.0 specification (https://registry.khronos.org/glTF/specs/2.0/glTF-2.0.html)
with its buffer embedded as a base64 data URI. Standard library only:
`python3 make_fixtures.py` in this folder rewrites them byte for byte.

- strand_translation_animation.gltf: one LINE_STRIP strand of 4 vertices
  (node 0) and an animation whose two channels groombake does not read:
  `translation` of node 0 (spec 3.11, animation targets) and a `pointer`
  channel of the KHR_animation_pointer extension (its target path,
  `extensions.KHR_animation_pointer.pointer`).
- strand_and_head_triangle.gltf: the same strand (node 0) beside a mesh of
  one TRIANGLES primitive (node 1), as a groom exported with its head.
- quantized_triangles.gltf: only a TRIANGLES primitive, its POSITION
  quantized to normalized SHORT (KHR_mesh_quantization, required), as mesh
  compressors write them: no curves, and a triangle mesh groombake cannot
  decode as a collider either.
"""

import base64
import json
import struct


def data_uri(data):
    return "data:application/octet-stream;base64," + base64.b64encode(data).decode()


def pad4(data):
    return data + b"\0" * (-len(data) % 4)


STRAND = [(0.0, 0.0, 0.0), (0.0, -0.01, 0.0), (0.0, -0.02, 0.001), (0.0, -0.03, 0.002)]


def floats(values):
    return b"".join(struct.pack("<f", v) for v in values)


def strand_buffer_views(buffer, offset=0):
    """The strand's positions as accessor 0 (views and accessors lists)."""
    flat = [c for p in STRAND for c in p]
    views = [{"buffer": buffer, "byteOffset": offset, "byteLength": 4 * len(flat)}]
    accessors = [{
        "bufferView": 0, "componentType": 5126, "count": len(STRAND), "type": "VEC3",
        "min": [min(p[i] for p in STRAND) for i in range(3)],
        "max": [max(p[i] for p in STRAND) for i in range(3)],
    }]
    return floats(flat), views, accessors


def strand_translation_animation():
    strand, views, accessors = strand_buffer_views(0)
    times = floats([0.0, 1.0])
    translations = floats([0.0, 0.0, 0.0, 0.1, 0.0, 0.0])
    data = pad4(strand) + times + translations
    views.append({"buffer": 0, "byteOffset": len(pad4(strand)), "byteLength": len(times)})
    views.append({"buffer": 0, "byteOffset": len(pad4(strand)) + len(times),
                  "byteLength": len(translations)})
    accessors.append({"bufferView": 1, "componentType": 5126, "count": 2, "type": "SCALAR",
                      "min": [0.0], "max": [1.0]})
    accessors.append({"bufferView": 2, "componentType": 5126, "count": 2, "type": "VEC3"})
    return {
        "asset": {"version": "2.0", "generator": "groombake tests/data/gltf/make_fixtures.py"},
        "extensionsUsed": ["KHR_animation_pointer"],
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0, "name": "strand"}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "mode": 3}]}],
        "animations": [{
            "channels": [
                {"sampler": 0, "target": {"node": 0, "path": "translation"}},
                {"sampler": 0, "target": {
                    "path": "pointer",
                    "extensions": {"KHR_animation_pointer": {"pointer": "/nodes/0/translation"}},
                }},
            ],
            "samplers": [{"input": 1, "output": 2, "interpolation": "LINEAR"}],
        }],
        "buffers": [{"byteLength": len(data), "uri": data_uri(data)}],
        "bufferViews": views,
        "accessors": accessors,
    }


TRIANGLE = [(-0.05, 0.0, -0.05), (0.05, 0.0, -0.05), (0.0, 0.0, 0.05)]


def strand_and_head_triangle():
    strand, views, accessors = strand_buffer_views(0)
    triangle = floats([c for p in TRIANGLE for c in p])
    data = pad4(strand) + triangle
    views.append({"buffer": 0, "byteOffset": len(pad4(strand)), "byteLength": len(triangle)})
    accessors.append({
        "bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC3",
        "min": [min(p[i] for p in TRIANGLE) for i in range(3)],
        "max": [max(p[i] for p in TRIANGLE) for i in range(3)],
    })
    return {
        "asset": {"version": "2.0", "generator": "groombake tests/data/gltf/make_fixtures.py"},
        "scene": 0,
        "scenes": [{"nodes": [0, 1]}],
        "nodes": [{"mesh": 0, "name": "strand"}, {"mesh": 1, "name": "head"}],
        "meshes": [
            {"name": "strand", "primitives": [{"attributes": {"POSITION": 0}, "mode": 3}]},
            {"name": "head", "primitives": [{"attributes": {"POSITION": 1}, "mode": 4}]},
        ],
        "buffers": [{"byteLength": len(data), "uri": data_uri(data)}],
        "bufferViews": views,
        "accessors": accessors,
    }


def quantized_triangles():
    # Normalized SHORT: value / 32767, scaled back by the node (0.05 m).
    shorts = [(-32767, 0, -32767), (32767, 0, -32767), (0, 0, 32767)]
    positions = b"".join(struct.pack("<hhhh", *p, 0) for p in shorts)  # 8-byte stride
    data = positions
    return {
        "asset": {"version": "2.0", "generator": "groombake tests/data/gltf/make_fixtures.py"},
        "extensionsUsed": ["KHR_mesh_quantization"],
        "extensionsRequired": ["KHR_mesh_quantization"],
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0, "name": "head", "scale": [0.05, 0.05, 0.05]}],
        "meshes": [{"name": "head", "primitives": [{"attributes": {"POSITION": 0}, "mode": 4}]}],
        "buffers": [{"byteLength": len(data), "uri": data_uri(data)}],
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": len(data), "byteStride": 8,
                         "target": 34962}],
        "accessors": [{"bufferView": 0, "componentType": 5122, "normalized": True, "count": 3,
                       "type": "VEC3", "min": [-1.0, 0.0, -1.0], "max": [1.0, 0.0, 1.0]}],
    }


for name, make in [
    ("strand_translation_animation.gltf", strand_translation_animation),
    ("strand_and_head_triangle.gltf", strand_and_head_triangle),
    ("quantized_triangles.gltf", quantized_triangles),
]:
    with open(name, "w") as f:
        json.dump(make(), f, indent=1)
        f.write("\n")
