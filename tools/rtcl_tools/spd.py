"""Eric Haines' Standard Procedural Databases (SPD) as rtcl scenes (docs/SCENE.md).

Written from the published descriptions (E. Haines, "A Proposal for Standard
Graphics Environments", IEEE CG&A 7(11), 1987) and the SPD generators balls.c,
tetra.c and mount.c, with the same size factor, camera, lights, colours and
geometry; docs/benchmark-scenes.md lists what maps how.  Each generator returns
a Bench: the scene as a dict and the meshes it references.

The SPD works in a z-up world; the scenes keep its coordinates and say up =
[0, 0, 1].  Its materials (lib_output_color: ka, kd, ks, ks_spec, highlight
angle, kt, ior) become rtcl materials by material() below.
"""

import math
from dataclasses import dataclass, field

import numpy as np

SKY = (0.078, 0.361, 0.753)          # "UNC sky blue", every SPD's background
SPD_IMAGE = (512, 512)
SPD_FOV = 45.0
NFF_AMBIENT = 0.1                     # NFF readers' ka where the SPD gives none
INLINE_LIMIT = 4096                   # "auto": inline triangles up to this many

MOUNTAIN_NO = 21                      # mount.c: picks the mountain
FRACTAL_DIMENSION = 2.2
OLD_HASH_MAX_SIZE = 7                 # mount.c's hash shifts by 7 - size


@dataclass
class Bench:
    """A generated scene: the document, and {file name: (vertices, faces)} it uses."""
    name: str
    scene: dict
    meshes: dict = field(default_factory=dict)


# ---- shared mapping ---------------------------------------------------------------------

def rounded(values, digits=6):
    """Plain floats rounded for the JSON text; never -0.0."""
    return [0.0 if round(float(v), digits) == 0 else round(float(v), digits) for v in values]


def material(color, ka, kd, ks, ks_spec, angle, kt, ior):
    """An rtcl material from lib_output_color's arguments: ks is the reflectance (NFF's
    Ks), ks_spec the highlight, whose half-angle in degrees gives the exponent the SPD
    library uses, shininess = ln(1/2) / ln(cos(angle))."""
    out = {"color": rounded(color), "ambient": ka if ka > 0 else NFF_AMBIENT, "diffuse": kd,
           "specular": ks_spec}
    if ks_spec > 0 and angle > 0:
        out["shininess"] = round(math.log(0.5) / math.log(math.cos(math.radians(angle))), 4)
    if ks > 0:
        out["reflect"] = ks
    if kt > 0:
        out.update(transmit=kt, ior=ior)
    return out


def lights(positions):
    """Point lights of the SPD's intensity 1/sqrt(number of lights) (lib.c's lscale)."""
    gray = round(1 / math.sqrt(len(positions)), 6)
    return [{"position": list(p), "color": [gray] * 3} for p in positions]


def base_scene(version, eye, look_at, up, light_positions, image=SPD_IMAGE, depth=5):
    return {"format": "rtcl-scene", "version": version,
            "image": {"width": image[0], "height": image[1]},
            "camera": {"eye": list(eye), "look_at": list(look_at), "up": list(up),
                       "fov": SPD_FOV},
            "background": list(SKY),
            # White ambient light: the material's ambient is then the SPD's ka.
            "ambient": [1, 1, 1],
            "max_depth": depth,
            "lights": lights(light_positions)}


def place_triangles(scene, name, vertices, faces, material_name, mode, smooth=False):
    """Puts a triangle mesh into scene: inline triangles, or a PLY file referenced
    through meshes; returns {file name: (vertices, faces)} to write beside it."""
    if mode == "auto":
        mode = "inline" if len(faces) <= INLINE_LIMIT else "ply"
    if mode == "inline":
        tris = vertices[faces].astype(np.float64)
        scene.setdefault("triangles", []).extend(
            {"vertices": [rounded(v) for v in tri], "material": material_name} for tri in tris)
        return {}
    if mode != "ply":
        raise ValueError("triangle mode must be auto, inline or ply, got %r" % mode)
    file_name = name + ".ply"
    scene.setdefault("meshes", []).append({"file": file_name, "material": material_name,
                                           "smooth": smooth})
    return {file_name: (vertices, faces)}


# ---- rotations as the SPD library builds them (libvec.c) -------------------------------

def axis_rotation(axis, angle):
    """The right-handed rotation by angle (radians) about the unit axis, for column
    vectors (libvec.c's lib_create_axis_rotate_matrix, which multiplies row vectors,
    is its transpose)."""
    x, y, z = axis
    c, s = math.cos(angle), math.sin(angle)
    t = 1 - c
    return np.array([[x * x * t + c, x * y * t - z * s, x * z * t + y * s],
                     [x * y * t + z * s, y * y * t + c, y * z * t - x * s],
                     [x * z * t - y * s, y * z * t + x * s, z * z * t + c]])


def z_rotation(angle):
    return axis_rotation((0.0, 0.0, 1.0), angle)


def normalized(v):
    v = np.asarray(v, dtype=np.float64)
    return v / np.linalg.norm(v)


# ---- balls: the sphereflake -------------------------------------------------------------

def flake_directions():
    """The 9 unit directions of a sphere's children about +z (balls.c create_objset)."""
    d = 1 / math.sqrt(2)
    trio = np.array([[d, d, 0.0], [d, 0.0, -d], [0.0, d, -d]])
    tilt = axis_rotation(normalized((1.0, -1.0, 0.0)), math.asin(2 / math.sqrt(6)))
    trio = trio @ tilt.T
    return np.concatenate([trio @ z_rotation(k * 2 * math.pi / 3).T for k in range(3)])


def rotations_from_z(directions):
    """Per direction d, the rotation taking +z to d (balls.c output_object), M x 3 x 3."""
    out = np.empty((len(directions), 3, 3))
    out[:] = np.eye(3)
    for i, d in enumerate(directions):
        if d[2] >= 0.9999:
            continue
        if d[2] <= -0.9999:
            out[i] = axis_rotation((0.0, 1.0, 0.0), math.pi)
            continue
        out[i] = axis_rotation(normalized((-d[1], d[0], 0.0)),
                               math.acos(min(1.0, max(-1.0, d[2]))))
    return out


def sphereflake_spheres(size):
    """Returns (centers N x 3, radii N) in balls.c's output order (each sphere, then its
    children's subtrees): sum of 9^k for k = 0 ... size spheres."""
    objset = flake_directions()
    subtree = [sum(9 ** k for k in range(size - level + 1)) for level in range(size + 1)]
    total = subtree[0]
    centers, radii = np.empty((total, 3)), np.empty(total)
    level_c, level_r = np.zeros((1, 3)), np.array([0.5])
    level_d, level_pos = np.array([[0.0, 0.0, 1.0]]), np.array([0])
    for level in range(size + 1):
        centers[level_pos], radii[level_pos] = level_c, level_r
        if level == size:
            break
        offsets = np.einsum("mij,kj->mki", rotations_from_z(level_d), objset)   # M x 9 x 3
        scale = level_r * (1 + 1 / 3)
        level_c = (level_c[:, None, :] + offsets * scale[:, None, None]).reshape(-1, 3)
        level_d = offsets.reshape(-1, 3)
        level_r = np.repeat(level_r / 3, 9)
        # Pre-order: a child follows its parent and its older siblings' subtrees.
        level_pos = (level_pos[:, None] + 1
                     + np.arange(9)[None, :] * subtree[level + 1]).reshape(-1)
    return centers, radii


def balls(size=4, image=SPD_IMAGE, depth=5):
    """balls.c: the sphereflake of size levels of mirrored spheres over a beige floor."""
    scene = base_scene(1, (2.1, 1.3, 1.7), (0, 0, 0), (0, 0, 1),
                       [(4, 3, 2), (1, -4, 4), (-3, 1, 5)], image, depth)
    scene["materials"] = {
        "floor": material((1.0, 0.75, 0.33), 0.2, 0.8, 0.0, 0.0, 0.0, 0.0, 1.0),
        "mirror": material((1.0, 0.9, 0.7), 0.0, 0.5, 0.5, 0.5, 37.0, 0.0, 1.0)}
    centers, radii = sphereflake_spheres(size)
    scene["spheres"] = [{"center": rounded(c, 9), "radius": round(float(r), 12),
                         "material": "mirror"} for c, r in zip(centers, radii)]
    # The SPD's floor is a 24 x 24 square at z = -1/2; version 1 has planes only.
    scene["planes"] = [{"point": [0, 0, -0.5], "normal": [0, 0, 1], "material": "floor"}]
    return Bench("spd-balls-%d" % size, scene)


# ---- tetra: the recursive tetrahedron -----------------------------------------------------

CORNERS = np.array([[-1, -1, 1], [-1, 1, -1], [1, -1, -1], [1, 1, 1]], dtype=np.float64)
# tetra.c's faces: points (k, k+1, k+2) mod 4, the first and last swapped for odd k.
TETRA_FACES = np.array([[0, 1, 2], [3, 2, 1], [2, 3, 0], [1, 0, 3]])


def tetra_mesh(size):
    """Returns (vertices, faces) of tetra.c at size: 4^(size-1) tetrahedra, 4^size
    triangles, in its output order; each tetrahedron has its own 4 vertices."""
    centers, half = np.zeros((1, 3)), 1.0
    for _ in range(size - 1):
        centers = (centers[:, None, :] + CORNERS[None, :, :] * (half / 2)).reshape(-1, 3)
        half /= 2
    vertices = (centers[:, None, :] + CORNERS[None, :, :] * half).reshape(-1, 3)
    faces = (np.arange(len(centers))[:, None, None] * 4 + TETRA_FACES[None]).reshape(-1, 3)
    return vertices.astype(np.float32), faces.astype(np.int32)


def tetra(size=6, image=SPD_IMAGE, depth=5, triangles="auto"):
    """tetra.c: the tetrahedral pyramid (Glassner's and Kay and Kajiya's test scene)."""
    scene = base_scene(2, (1.022846, -3.177154, -2.174512), (-0.004103, -0.004103, 0.216539),
                       (-0.816497, -0.816497, 0.816497), [(2, -18, -5)], image, depth)
    scene["materials"] = {"red": material((1.0, 0.2, 0.2), 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0)}
    name = "spd-tetra-%d" % size
    vertices, faces = tetra_mesh(size)
    meshes = place_triangles(scene, name, vertices, faces, "red", triangles)
    return Bench(name, scene, meshes)


# ---- mount: the fractal mountain and its crystal spheres ------------------------------------

def old_hash(a, b, size):
    """mount.c's original hash_rand (the 1987 database); shifts need size <= 7."""
    a, b = a.astype(np.int64), b.astype(np.int64)
    return ((a << (23 - size)) + (b << (15 - size)) + (a << (7 - size))) & 0xffff


def jenkins_hash(a, b, size):
    """mount.c's JENKINS_HASH hash_rand: Bob Jenkins' mix on 32-bit ints."""
    a, b = a.astype(np.int32), b.astype(np.int32)
    c = np.full_like(a, size)
    with np.errstate(over="ignore"):
        for shift_a, shift_b, shift_c in ((13, 8, 13), (12, 16, 5), (3, 10, 15)):
            a = a - b - c
            a ^= c >> shift_a
            b = b - c - a
            b ^= a << shift_b
            c = c - a - b
            c ^= b >> shift_c
    return c.astype(np.int64) & 0xffff


def gauss_table(count):
    """lib_gauss_rand(seed) for seed 0 ... count - 1 (libvec.c, Numerical Recipes'
    GASDEV with its own linear congruential generator)."""
    m1, ia1, ic1 = 134456, 8121, 28411
    ix2 = np.arange(count, dtype=np.int64)
    out = np.empty(count)
    todo = np.ones(count, dtype=bool)
    while todo.any():
        ix1 = (ic1 + ix2 * ia1) % m1
        ix2 = (ic1 + ix1 * ia1) % m1
        # RM1 is the macro 1.0/M1: "ix * 2.0 * RM1" is (ix * 2.0 * 1.0) / M1.
        v1 = ix1 * 2.0 * 1.0 / m1 - 1.0
        v2 = ix2 * 2.0 * 1.0 / m1 - 1.0
        r = v1 * v1 + v2 * v2
        done = todo & (r < 1.0)
        out[done] = v1[done] * np.sqrt(-2.0 * np.log(r[done]) / r[done])
        todo &= ~done
    return out


def mountain_heights(size):
    """Returns the (2^size + 1)^2 heights z[x, y] of mount.c's grow_mountain: each square
    gets its edge midpoints (mean of the ends) and centre (mean of the corners) raised by
    a gaussian of its size, seeded by a hash of the point.  The SPD's own hash for
    size <= 7; above, its shifts go negative (undefined in C) and the SPD's
    alternative (JENKINS_HASH) is used."""
    n = 1 << size
    z = np.zeros((n + 1, n + 1))
    gauss = gauss_table(MOUNTAIN_NO + 0x10000)
    hash_rand = old_hash if size <= OLD_HASH_MAX_SIZE else jenkins_hash
    ratio = 2.0 / math.exp(math.log(2.0) / (FRACTAL_DIMENSION - 1.0))
    roughness = math.sqrt(ratio * ratio - 1.0)

    def raise_by(x, y, rise):
        return rise * gauss[MOUNTAIN_NO + hash_rand(x, y, size)]

    width = n
    while width > 1:
        half = width >> 1
        rise = (half * 2.0 / n) * roughness
        ll = np.arange(0, n, width)
        edge = np.arange(0, n + 1, width)
        mx, my = np.meshgrid(ll + half, edge, indexing="ij")    # midpoints along x
        z[mx, my] = (z[mx - half, my] + z[mx + half, my]) / 2.0 + raise_by(mx, my, rise)
        mx, my = np.meshgrid(edge, ll + half, indexing="ij")    # midpoints along y
        z[mx, my] = (z[mx, my - half] + z[mx, my + half]) / 2.0 + raise_by(mx, my, rise)
        cx, cy = np.meshgrid(ll + half, ll + half, indexing="ij")
        corners = (z[cx - half, cy - half] + z[cx + half, cy - half]
                   + z[cx + half, cy + half] + z[cx - half, cy + half])
        z[cx, cy] = corners / 4.0 + raise_by(cx, cy, 1.4142136 * rise)
        width = half
    return z


def quadrant_order(size):
    """Cell indices (x, y) in grow_mountain's order: lower left, lower right, upper right,
    upper left quarters, recursively."""
    n = 1 << size
    x, y = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    x, y = x.reshape(-1), y.reshape(-1)
    key = np.zeros(n * n, dtype=np.int64)
    quadrant = np.array([[0, 3], [1, 2]])                  # [x bit][y bit]
    for bit in range(size - 1, -1, -1):
        key = key * 4 + quadrant[(x >> bit) & 1, (y >> bit) & 1]
    order = np.argsort(key, kind="stable")
    return x[order], y[order]


def mountain_mesh(size):
    """Returns (vertices, faces) of the mountain: 2 * 4^size triangles over [-1, 1]^2, two
    per grid square (ll, lr, ur) and (ur, ul, ll), in mount.c's order."""
    n = 1 << size
    z = mountain_heights(size)
    coord = -1.0 + np.arange(n + 1) * 2.0 / n
    gx, gy = np.meshgrid(coord, coord, indexing="ij")
    vertices = np.stack([gx, gy, z], axis=-1).reshape(-1, 3).astype(np.float32)
    x, y = quadrant_order(size)
    ll, lr = x * (n + 1) + y, (x + 1) * (n + 1) + y
    ur, ul = lr + 1, ll + 1
    faces = np.stack([np.stack([ll, lr, ur], 1), np.stack([ur, ul, ll], 1)], 1)
    return vertices, faces.reshape(-1, 3).astype(np.int32)


def crystal_spheres(center, radius):
    """mount.c create_spheres: 4 touching spheres stacked as a tetrahedron about center."""
    top = np.array([0.0, 0.0, radius * math.sqrt(3.0 / 2.0)])
    tilted = axis_rotation(normalized((1.0, 1.0, 0.0)), math.acos(-1.0 / 3.0)) @ top
    centers = [np.asarray(center) + top]
    centers += [np.asarray(center) + z_rotation(i * 2 * math.pi / 3) @ tilted for i in range(3)]
    return [(c, radius) for c in centers]


GLASS = material((1.0, 1.0, 1.0), 0.0, 0.1, 0.1, 0.4, 6.7, 0.9, 1.5)
MOUNTAIN = material((0.5, 0.45, 0.35), 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0)


def mount_scene(size, image, depth):
    scene = base_scene(2, (-1.6, 1.6, 1.7), (0, 0, 0), (0, 0, 1), [(-100, -100, 100)],
                       image, depth)
    scene["materials"] = {"glass": GLASS, "mountain": MOUNTAIN}
    scene["spheres"] = [{"center": rounded(c, 9), "radius": r, "material": "glass"}
                        for c, r in crystal_spheres((-0.8, 0.8, 1.0), 0.17)]
    return scene


def mount(size=6, image=SPD_IMAGE, depth=5, triangles="auto"):
    """mount.c: a fractal mountain (Carpenter's midpoint displacement on a square grid)
    with a pyramid of 4 crystal spheres in front of it."""
    scene = mount_scene(size, image, depth)
    name = "spd-mount-%d" % size
    vertices, faces = mountain_mesh(size)
    return Bench(name, scene, place_triangles(scene, name, vertices, faces, "mountain",
                                              triangles))


LAKE_LEVEL = 0.0
LAKE = {"color": [0.55, 0.7, 0.8], "ambient": 0.1, "diffuse": 0.15, "specular": 0.5,
        "shininess": 200, "reflect": 0.75}


def lake(size=10, image=SPD_IMAGE, depth=5):
    """Not an SPD: mount at size (2 * 4^size triangles, 2,097,152 at 10) with its crystal
    spheres, and a mirror lake (the plane z = LAKE_LEVEL) that floods the valleys:
    a million-triangle scene with glass and mirror for the BVH."""
    scene = mount_scene(size, image, depth)
    scene["materials"]["lake"] = LAKE
    scene["planes"] = [{"point": [0, 0, LAKE_LEVEL], "normal": [0, 0, 1], "material": "lake"}]
    name = "lake-%d" % size
    vertices, faces = mountain_mesh(size)
    return Bench(name, scene, place_triangles(scene, name, vertices, faces, "mountain", "ply"))


# The lake path-traced (issue 41): each material's BSDF, the sun and the sky.
LAKE_PATH_MATERIALS = {
    "glass": {"bsdf": {"type": "dielectric", "ior": 1.5}},
    "mountain": {"bsdf": {"type": "diffuse", "reflectance": [0.5, 0.45, 0.35]}},
    "lake": {"bsdf": {"type": "conductor", "reflectance": [0.55, 0.7, 0.8]}},
}
LAKE_EXTENT = 20.0                    # the lake's square reaches x, y = +-20
SUN_IRRADIANCE = [2.6, 2.5, 2.3]
LAKE_PATH_SAMPLES = 16


def lake_path(size=10, image=SPD_IMAGE, depth=8):
    """The lake under the path integrator: the same mountain (2 * 4^size
    triangles) and crystal spheres, now smooth glass (dielectric, ior 1.5); the
    mountain diffuse in its SPD colour; the lake a tinted mirror (a smooth
    conductor of F0 the lake's colour) as a square of two triangles at z =
    LAKE_LEVEL reaching +-LAKE_EXTENT, beyond what the camera sees (a plane is
    infinite, which Mitsuba cannot take); lit by the sun, a directional light
    along the SPD light's direction, and the SPD's sky blue as a uniform sky."""
    scene = mount_scene(size, image, depth)
    scene.pop("ambient")
    scene["integrator"] = "path"
    scene["image"]["samples"] = LAKE_PATH_SAMPLES
    scene["materials"] = {name: dict(m) for name, m in LAKE_PATH_MATERIALS.items()}
    light = np.array(scene["lights"][0]["position"], dtype=np.float64)
    scene["lights"] = [{"direction": rounded(-light / np.linalg.norm(light)),
                        "color": list(SUN_IRRADIANCE)}]
    e, z = LAKE_EXTENT, LAKE_LEVEL
    corners = [[-e, -e, z], [e, -e, z], [e, e, z], [-e, e, z]]
    scene["triangles"] = [{"vertices": [corners[0], corners[1], corners[2]], "material": "lake"},
                          {"vertices": [corners[0], corners[2], corners[3]], "material": "lake"}]
    name = "lake-path-%d" % size
    vertices, faces = mountain_mesh(size)
    return Bench(name, scene, place_triangles(scene, name, vertices, faces, "mountain", "ply"))
