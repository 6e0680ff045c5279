"""A version 2 scene's meshes and inline triangles as POV-Ray 3.7 SDL.

Each mesh becomes one mesh2 (vertex_vectors, face_indices and, for a smooth
mesh, normal_vectors with normal_indices), placed here as host/scene/mesh_place.c
places it: scale, then rotate about x, y, z (degrees, right-handed, world
axes), then translate, in double; triangles of area 0 after placement are
dropped as rtcl skips them; smooth normals are area-weighted over the
triangles that share a vertex position (rtcl's rule for a file without
normals), and a vertex whose sum is 0 takes its triangle's normal.  Then the
whole mesh is mirrored in x, as the rest of the scene (povray_sdl).  An inline
triangle becomes a triangle { }.

Only the mesh files tools/genbench.py writes (binary little-endian PLY in
rtcl_tools.ply's layout, without normals) are read: rtcl reads any format the
Open Asset Import Library does, this module does not (MeshError says so).
"""

import math

import numpy as np

from . import ply
from .vector import cross, dot, sub


class MeshError(ValueError):
    """A mesh this converter cannot read."""


def cos_sin(degrees):
    """cos and sin, exact at multiples of 90 degrees (host/scene/mesh_place.c)."""
    quarter = degrees / 90.0
    if quarter == math.floor(quarter) and abs(quarter) < 1e15:
        k = int(math.fmod(quarter, 4.0)) % 4
        cosines = (1.0, 0.0, -1.0, 0.0)
        return cosines[k], cosines[(k + 3) % 4]
    return math.cos(math.radians(degrees)), math.sin(math.radians(degrees))


def rotation(degrees):
    """Rz Ry Rx, as place_set_rotation."""
    cx, sx = cos_sin(degrees[0])
    cy, sy = cos_sin(degrees[1])
    cz, sz = cos_sin(degrees[2])
    rx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]], dtype=float)
    ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]], dtype=float)
    rz = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]], dtype=float)
    return rz @ ry @ rx


def place(mesh, vertices):
    """The vertices (V x 3) placed in rtcl's world, in double."""
    scaled = vertices.astype(np.float64) * np.array(mesh["scale"], dtype=float)
    return scaled @ rotation(mesh["rotate"]).T + np.array(mesh["translate"], dtype=float)


def unit_rows(v):
    """Rows scaled to length 1; rows of length 0 (or not finite) become 0."""
    length = np.linalg.norm(v, axis=1)
    good = np.isfinite(length) & (length > 0)
    out = np.zeros_like(v)
    out[good] = v[good] / length[good, None]
    return out


def smooth_normals(placed, faces, face_cross):
    """Area-weighted unit normals per vertex, summed over equal positions."""
    sums = np.zeros_like(placed)
    for k in range(3):
        np.add.at(sums, faces[:, k], face_cross)
    position = np.unique(placed, axis=0, return_inverse=True)[1].reshape(-1)
    per_position = np.zeros((position.max() + 1, 3))
    np.add.at(per_position, position, sums)
    return unit_rows(per_position[position])


def read_mesh(mesh):
    """(placed vertices, faces with area, vertex normals or None) of one mesh."""
    try:
        vertices, faces = ply.read(mesh["file"])
    except ply.PlyError as e:
        raise MeshError("%s: only the binary PLY meshes tools/genbench.py writes are converted"
                        " to POV-Ray (%s)" % (mesh["file"], e)) from None
    placed = place(mesh, vertices)
    faces = faces.astype(np.int64)
    if np.prod(np.sign(mesh["scale"])) < 0:  # a mirroring scale: rtcl's vertex order
        faces = faces[:, [0, 2, 1]]
    e1 = placed[faces[:, 1]] - placed[faces[:, 0]]
    e2 = placed[faces[:, 2]] - placed[faces[:, 0]]
    face_cross = np.cross(e1, e2)
    keep = unit_rows(face_cross).any(axis=1)
    normals = smooth_normals(placed, faces, face_cross) if mesh["smooth"] else None
    return placed, faces[keep], normals, unit_rows(face_cross[keep])


def vectors_block(name, rows):
    """name { n, <x, y, z>, ... } with rtcl's x mirrored; shortest round-trip text."""
    mirrored = np.array(rows, dtype=np.float64) * np.array([-1.0, 1.0, 1.0])
    mirrored[mirrored == 0] = 0.0  # never -0
    body = ",\n    ".join("<%r, %r, %r>" % tuple(map(float, r)) for r in mirrored)
    return "  %s { %d,\n    %s\n  }" % (name, len(mirrored), body)


def indices_block(name, rows):
    body = ",\n    ".join("<%d, %d, %d>" % tuple(r) for r in rows.tolist())
    return "  %s { %d,\n    %s\n  }" % (name, len(rows), body)


def normal_parts(faces, normals, face_normals):
    """normal_vectors and normal_indices: the vertex normals, then the face
    normal of each triangle that has a vertex without one (rtcl's fallback)."""
    zero = ~normals.any(axis=1)
    indices = faces.copy()
    flagged = np.nonzero(zero[faces].any(axis=1))[0]
    extra = face_normals[flagged]
    for k in range(3):
        use = zero[faces[flagged, k]]
        indices[flagged[use], k] = len(normals) + np.nonzero(use)[0]
    return np.vstack([normals, extra]), indices


def mesh_sdl(mesh, texture, interior):
    """The mesh2 of one mesh, or "" when no triangle has area."""
    placed, faces, normals, face_normals = read_mesh(mesh)
    if len(faces) == 0:
        return ""
    used = np.unique(faces)
    renumber = np.full(len(placed), -1, dtype=np.int64)
    renumber[used] = np.arange(len(used))
    parts = ["mesh2 {  // %d triangles" % len(faces), vectors_block("vertex_vectors", placed[used])]
    if normals is not None:
        vn, ni = normal_parts(faces, normals, face_normals)
        parts.append(vectors_block("normal_vectors", vn))
    parts.append(indices_block("face_indices", renumber[faces]))
    if normals is not None:
        parts.append(indices_block("normal_indices", ni))
    if interior:
        # POV-Ray refracts only in a solid; rtcl takes a mesh as closed.
        parts.append("  inside_vector <0, 0, 1>")
    parts.append("  %s" % texture)
    if interior:
        parts.append("  %s" % interior)
    parts.append("}")
    return "\n".join(parts)


def triangle_sdl(triangle, texture, interior, vec, mirror):
    """An inline triangle, or "" for one of area 0 (rtcl refuses those)."""
    v = triangle["vertices"]
    n = cross(sub(v[1], v[0]), sub(v[2], v[0]))
    if dot(n, n) == 0:
        return ""
    head = "triangle { %s" % ", ".join(vec(mirror(p)) for p in v)
    return "\n".join([head, "  %s" % texture] + (["  %s" % interior] if interior else []) + ["}"])
