# Writes box.gltf (a closed unit cube: 8 vertices, 12 triangles, wound outward),
# box_out_of_range_index.gltf (the same with one index set to 8, past the last vertex) and
# box.glb (the cube as binary glTF: a JSON chunk and a BIN chunk in one file).
# Run from this folder: python3 make_boxes.py
import base64, json, struct

POSITIONS = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)]
TRIANGLES = [(0, 2, 1), (0, 3, 2), (4, 5, 6), (4, 6, 7), (0, 1, 5), (0, 5, 4),
             (1, 2, 6), (1, 6, 5), (2, 3, 7), (2, 7, 6), (3, 0, 4), (3, 4, 7)]


def document(indices, buffer):
    positions = b"".join(struct.pack("<3f", *p) for p in POSITIONS)
    index_bytes = b"".join(struct.pack("<H", i) for i in indices)
    data = positions + index_bytes
    buffer["byteLength"] = len(data)
    return data, {
        "asset": {"version": "2.0", "generator": "softbake tests/data/import/make_boxes.py"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0, "name": "box"}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        "buffers": [buffer],
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": len(positions)},
                        {"buffer": 0, "byteOffset": len(positions), "byteLength": len(index_bytes)}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": len(POSITIONS), "type": "VEC3",
                       "min": [0, 0, 0], "max": [1, 1, 1]},
                      {"bufferView": 1, "componentType": 5123, "count": len(indices), "type": "SCALAR"}],
    }


def write(name, indices):
    buffer = {}
    data, gltf = document(indices, buffer)
    buffer["uri"] = "data:application/octet-stream;base64," + base64.b64encode(data).decode()
    with open(name, "w") as out:
        json.dump(gltf, out, indent=1)
        out.write("\n")


def write_glb(name, indices):
    buffer = {}
    data, gltf = document(indices, buffer)
    text = json.dumps(gltf, separators=(",", ":")).encode()
    text += b" " * (-len(text) % 4)  # chunks are 4-byte aligned: JSON pads with spaces
    data += b"\0" * (-len(data) % 4)  # and BIN with zeros
    chunks = (struct.pack("<I4s", len(text), b"JSON") + text +
              struct.pack("<I4s", len(data), b"BIN\0") + data)
    with open(name, "wb") as out:
        out.write(struct.pack("<4sII", b"glTF", 2, 12 + len(chunks)) + chunks)


indices = [i for t in TRIANGLES for i in t]
write("box.gltf", indices)
write_glb("box.glb", indices)
indices[5] = len(POSITIONS)  # the second triangle's last corner
write("box_out_of_range_index.gltf", indices)
