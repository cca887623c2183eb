#!/usr/bin/env python3
"""Writes the glTF fuzzing seeds in fuzz/gltf_seeds/: small .gltf files (buffers and images as
data: URIs, since the fuzzer has no file access) and .glb files that between them use every
feature the loader maps: indexed and non-indexed triangles, strips and fans, normals and
texture coordinates, byte/short/normalized components, strides, a base colour texture,
emission, transmission, punctual lights, cameras and a node hierarchy."""
import base64, json, os, struct, zlib

here = os.path.join(os.path.dirname(os.path.abspath(__file__)), "gltf_seeds")


def png(width, height):
    rows = []
    for y in range(height):
        row = b"\0" + b"".join(bytes([(x * 80) % 256, (y * 90) % 256, 128]) for x in range(width))
        rows.append(row)
    raw = b"".join(rows)

    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))


def data_uri(data, mime="application/octet-stream"):
    return "data:%s;base64,%s" % (mime, base64.b64encode(data).decode())


def triangle_model(mode=4, indexed=True, extras=None):
    positions = struct.pack("<9f", -1, -1, 0, 1, -1, 0, 0, 1, 0)
    normals = struct.pack("<9f", 0, 0, 1, 0, 0, 1, 0, 0, 1)
    uvs = struct.pack("<6H", 0, 0, 65535, 0, 32768, 65535)
    indices = struct.pack("<3B", 0, 1, 2) + b"\0"
    buf = positions + normals + uvs + indices
    model = {
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0, 1]}],
        "nodes": [{"mesh": 0, "children": [2]}, {"camera": 0, "translation": [0, 0, 4]},
                  {"translation": [0, 0.5, 0], "scale": [0.5, 0.5, 0.5],
                   "rotation": [0, 0, 0.3826834, 0.9238795], "mesh": 0}],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.7, "aspectRatio": 1.0,
                                                             "znear": 0.1}}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2},
                                    "mode": mode, "material": 0}]}],
        "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.6, 0.4, 1],
                                                "metallicFactor": 0.3, "roughnessFactor": 0.5}}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
             "min": [-1, -1, 0], "max": [1, 1, 0]},
            {"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC3"},
            {"bufferView": 2, "componentType": 5123, "normalized": True, "count": 3, "type": "VEC2"},
            {"bufferView": 3, "componentType": 5121, "count": 3, "type": "SCALAR"}],
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36},
                        {"buffer": 0, "byteOffset": 36, "byteLength": 36},
                        {"buffer": 0, "byteOffset": 72, "byteLength": 12},
                        {"buffer": 0, "byteOffset": 84, "byteLength": 3}],
        "buffers": [{"byteLength": len(buf)}],
    }
    if indexed:
        model["meshes"][0]["primitives"][0]["indices"] = 3
    if extras:
        extras(model)
    return model, buf


def write_gltf(name, model, buf):
    model["buffers"][0]["uri"] = data_uri(buf)
    with open(os.path.join(here, name), "w") as f:
        json.dump(model, f, separators=(",", ":"))


def write_glb(name, model, buf):
    text = json.dumps(model, separators=(",", ":")).encode()
    text += b" " * (-len(text) % 4)
    buf += b"\0" * (-len(buf) % 4)
    out = struct.pack("<4sII", b"glTF", 2, 12 + 8 + len(text) + 8 + len(buf))
    out += struct.pack("<II", len(text), 0x4E4F534A) + text
    out += struct.pack("<II", len(buf), 0x004E4942) + buf
    with open(os.path.join(here, name), "wb") as f:
        f.write(out)


def textured(model):
    model["images"] = [{"uri": data_uri(png(2, 2), "image/png")}]
    model["textures"] = [{"source": 0}]
    model["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = {"index": 0}


def lights(model):
    model["extensionsUsed"] = ["KHR_lights_punctual", "KHR_materials_emissive_strength",
                               "KHR_materials_transmission", "KHR_materials_ior"]
    model["extensions"] = {"KHR_lights_punctual": {"lights": [
        {"type": "point", "color": [1, 0.9, 0.8], "intensity": 20},
        {"type": "spot", "intensity": 50, "spot": {"innerConeAngle": 0.2, "outerConeAngle": 0.6}},
        {"type": "directional", "intensity": 2}]}}
    model["nodes"] += [
        {"translation": [0, 3, 0], "extensions": {"KHR_lights_punctual": {"light": 0}}},
        {"translation": [0, 3, 1], "extensions": {"KHR_lights_punctual": {"light": 1}}},
        {"rotation": [0.7071068, 0, 0, 0.7071068],
         "extensions": {"KHR_lights_punctual": {"light": 2}}}]
    model["scenes"][0]["nodes"] += [3, 4, 5]
    model["materials"].append({"emissiveFactor": [1, 1, 1], "doubleSided": True,
                               "extensions": {"KHR_materials_emissive_strength":
                                              {"emissiveStrength": 3}}})
    model["materials"].append({"extensions": {"KHR_materials_transmission":
                                              {"transmissionFactor": 1},
                                              "KHR_materials_ior": {"ior": 1.33}}})
    model["meshes"].append({"primitives": [{"attributes": {"POSITION": 0}, "material": 1},
                                           {"attributes": {"POSITION": 0}, "material": 2}]})
    model["nodes"][1]["mesh"] = 1


def strided(model):
    # Positions and normals interleaved in one bufferView with byteStride 24.
    model["bufferViews"].append({"buffer": 0, "byteOffset": 0, "byteLength": 72, "byteStride": 24})
    model["accessors"].append({"bufferView": 4, "componentType": 5126, "count": 3, "type": "VEC3"})
    model["accessors"].append({"bufferView": 4, "byteOffset": 12, "componentType": 5126,
                               "count": 3, "type": "VEC3"})
    model["meshes"].append({"primitives": [{"attributes": {"POSITION": 4, "NORMAL": 5},
                                            "indices": 3}]})
    model["nodes"][2]["mesh"] = 1
    del model["scene"]


os.makedirs(here, exist_ok=True)
write_gltf("triangle.gltf", *triangle_model())
write_gltf("strip.gltf", *triangle_model(mode=5, indexed=False))
write_gltf("fan.gltf", *triangle_model(mode=6))
write_gltf("textured.gltf", *triangle_model(extras=textured))
write_gltf("lights.gltf", *triangle_model(extras=lights))
write_gltf("strided.gltf", *triangle_model(extras=strided))
write_glb("triangle.glb", *triangle_model())
write_glb("lights.glb", *triangle_model(extras=lights))
