"""Binary little-endian PLY meshes: the writer the benchmark generators use, and a
reader for exactly what it writes (the tests read the files back with it).

The layout is the plainest one every importer reads (assimp, Blender, MeshLab):

    ply
    format binary_little_endian 1.0
    comment ...
    element vertex V
    property float x
    property float y
    property float z
    element face F
    property list uchar int vertex_indices
    end_header

then V records of three float32 and F records of (uint8 3, three int32).  Whole
numpy arrays are written at once: a 2 M-triangle mesh takes well under a second.
"""

import numpy as np

from . import files

FACE_RECORD = np.dtype([("count", "<u1"), ("indices", "<i4", (3,))])
HEADER_LINES = ("ply", "format binary_little_endian 1.0")
VERTEX_PROPERTIES = ("property float x", "property float y", "property float z")
FACE_PROPERTY = "property list uchar int vertex_indices"


class PlyError(ValueError):
    """A file that is not the PLY layout this module writes."""


def header(vertex_count, face_count, comment=""):
    """Returns the header text (ASCII, ending with "end_header\\n")."""
    lines = list(HEADER_LINES)
    if comment:
        lines.append("comment " + " ".join(comment.split()))
    lines += ["element vertex %d" % vertex_count, *VERTEX_PROPERTIES,
              "element face %d" % face_count, FACE_PROPERTY, "end_header"]
    return "\n".join(lines) + "\n"


def encode(vertices, faces, comment=""):
    """Returns the bytes of the PLY file of vertices (V x 3) and faces (F x 3 indices)."""
    vertices = np.ascontiguousarray(vertices, dtype="<f4")
    faces = np.asarray(faces)
    if vertices.ndim != 2 or vertices.shape[1] != 3 or faces.ndim != 2 or faces.shape[1] != 3:
        raise ValueError("vertices and faces must be N x 3 arrays")
    if faces.size and (faces.min() < 0 or faces.max() >= len(vertices)):
        raise ValueError("a face index is outside the vertex list")
    records = np.empty(len(faces), dtype=FACE_RECORD)
    records["count"] = 3
    records["indices"] = faces
    return (header(len(vertices), len(faces), comment).encode("ascii")
            + vertices.tobytes() + records.tobytes())


def write(path, vertices, faces, comment=""):
    """Writes the mesh to path atomically."""
    data = encode(vertices, faces, comment)
    with files.atomic_output(path, "wb") as stream:
        stream.write(data)


def _read_header(data):
    """Returns (vertex count, face count, offset of the body) of PLY bytes."""
    end = data.find(b"end_header\n")
    if end < 0:
        raise PlyError("no end_header line")
    lines = data[:end].decode("ascii").split("\n")[:-1]
    lines = [line for line in lines if not line.startswith("comment ")]
    if tuple(lines[:2]) != HEADER_LINES:
        raise PlyError("not a binary little-endian PLY file: %r" % lines[:2])
    try:
        vertex_count = int(lines[2].split()[2])
        face_count = int(lines[6].split()[2])
    except (IndexError, ValueError):
        raise PlyError("element lines not as written: %r" % lines[2:]) from None
    expected = ["element vertex %d" % vertex_count, *VERTEX_PROPERTIES,
                "element face %d" % face_count, FACE_PROPERTY]
    if lines[2:] != expected:
        raise PlyError("properties not as written: %r" % lines[2:])
    return vertex_count, face_count, end + len(b"end_header\n")


def decode(data):
    """Returns (vertices float32 V x 3, faces int32 F x 3) of the bytes of a PLY file
    in this module's layout; PlyError if it is not one, or has a bad length or index."""
    vertex_count, face_count, offset = _read_header(data)
    body = len(data) - offset
    expected = vertex_count * 12 + face_count * FACE_RECORD.itemsize
    if body != expected:
        raise PlyError("body is %d bytes, the header promises %d" % (body, expected))
    vertices = np.frombuffer(data, dtype="<f4", count=3 * vertex_count,
                             offset=offset).reshape(vertex_count, 3)
    records = np.frombuffer(data, dtype=FACE_RECORD, count=face_count,
                            offset=offset + vertex_count * 12)
    if face_count and np.any(records["count"] != 3):
        raise PlyError("a face is not a triangle")
    faces = records["indices"]
    if face_count and (faces.min() < 0 or faces.max() >= vertex_count):
        raise PlyError("a face index is outside the vertex list")
    return vertices, faces


def read(path):
    with open(path, "rb") as stream:
        return decode(stream.read())
