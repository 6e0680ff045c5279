"""The 2009 paper's experiment scene as an rtcl scene (docs/SCENE.md).

tools/genscene.py is its command line; its docstring describes the layout.
"""

import colorsys
import json
import math
import random

from .vector import cross, dot, normalize, sub

DEFAULT_SEED = 2009
KIND_SHARES = (("diffuse", 0.60), ("mirror", 0.25), ("glass", 0.15))

R_MIN, R_MAX = 0.5, 1.0       # ball radii, world units
GAP = 0.1                     # least distance between two ball surfaces
REFERENCE_BALLS = 60          # the layout below is sized for this many balls

# Camera and framing for REFERENCE_BALLS; positions scale with sqrt(N / 60).
EYE = (0.0, 7.0, -22.0)
LOOK_AT = (0.0, 0.5, 2.0)
FOV = 45.0
NDC_X_LIMIT = 0.92            # |x| of every ball's silhouette on screen, in [-1, 1]
NDC_BOTTOM = -0.94            # every ball's silhouette lies above this
NDC_TOP = 0.22                # every ball's contact point lies below this
VISIBLE_SHARE = 0.3           # a ball in front of another leaves at least this much
                              # of the far one's screen radius beyond its centre

DIGITS = 4                    # decimals written for every number


class PlacementError(ValueError):
    """The balls do not fit the framed part of the table."""


class Framing:
    """The camera basis of RENDERING.md, to test where a ball lands on screen."""

    def __init__(self, eye, look_at, fov):
        self.eye = eye
        self.f = normalize(sub(look_at, eye))
        self.r = normalize(cross(self.f, (0.0, 1.0, 0.0)))
        self.u = cross(self.r, self.f)
        self.h = math.tan(math.radians(fov) / 2)

    def ndc(self, p):
        """Return (x, y, depth) of point p: x, y in [-1, 1] on a square screen."""
        v = sub(p, self.eye)
        depth = dot(v, self.f)
        return dot(v, self.r) / (depth * self.h), dot(v, self.u) / (depth * self.h), depth

    def on_table(self, sx, sy):
        """Return (x, z): where the primary ray through screen point (sx, sy) meets
        the table; sy must lie below the horizon."""
        d = tuple(f + sx * self.h * r + sy * self.h * u
                  for f, r, u in zip(self.f, self.r, self.u))
        t = -self.eye[1] / d[1]
        return self.eye[0] + t * d[0], self.eye[2] + t * d[2]

    def disc(self, x, z, radius):
        """Return (x, y, r, depth): the screen disc of the ball resting at (x, z),
        its radius slightly overestimated, and the depth of its centre."""
        cx, cy, depth = self.ndc((x, radius, z))
        if depth <= radius:
            return cx, cy, float("inf"), depth
        return cx, cy, radius / (math.sqrt(depth * depth - radius * radius) * self.h), depth

    def frames_ball(self, x, z, radius):
        """True when the ball resting at (x, z) lies inside the framed region."""
        cx, cy, spread, _ = self.disc(x, z, radius)
        _, ground_y, _ = self.ndc((x, 0.0, z))
        return (abs(cx) + spread <= NDC_X_LIMIT and cy - spread >= NDC_BOTTOM
                and ground_y <= NDC_TOP)


def hides(near, far):
    """True when screen disc near covers far's centre or comes close to it."""
    return math.hypot(near[0] - far[0], near[1] - far[1]) < near[2] + VISIBLE_SHARE * far[2]


class Grid:
    """Spatial hash of placed balls on the table, for the overlap test."""

    def __init__(self):
        self.cell = 2 * R_MAX + GAP
        self.cells = {}

    def key(self, x, z):
        return int(math.floor(x / self.cell)), int(math.floor(z / self.cell))

    def fits(self, x, z, radius):
        kx, kz = self.key(x, z)
        for i in (kx - 1, kx, kx + 1):
            for j in (kz - 1, kz, kz + 1):
                for (bx, bz, br) in self.cells.get((i, j), ()):
                    if math.hypot(x - bx, z - bz) < radius + br + GAP:
                        return False
        return True

    def add(self, x, z, radius):
        self.cells.setdefault(self.key(x, z), []).append((x, z, radius))


def rnd(value):
    """Round for output; never write -0.0."""
    value = round(value, DIGITS)
    return 0.0 if value == 0 else value


def rvec(values):
    return [rnd(v) for v in values]


def random_color(rng, saturation, value):
    """A colour of random hue with saturation and value drawn from the given ranges."""
    rgb = colorsys.hsv_to_rgb(rng.random(), rng.uniform(*saturation), rng.uniform(*value))
    return rvec(rgb)


def make_material(rng, kind):
    """Inline material of one ball; only fields that differ from SCENE.md's defaults."""
    if kind == "diffuse":
        return {"color": random_color(rng, (0.55, 0.95), (0.6, 0.95)),
                "diffuse": 0.8, "specular": 0.25, "shininess": 40}
    if kind == "mirror":
        return {"color": random_color(rng, (0.2, 0.6), (0.5, 0.9)),
                "diffuse": 0.3, "specular": 0.6, "shininess": 120,
                "reflect": rnd(rng.uniform(0.6, 0.8))}
    if kind == "glass":
        return {"color": random_color(rng, (0.1, 0.4), (0.9, 1.0)),
                "diffuse": 0.05, "specular": 0.8, "shininess": 200,
                "reflect": 0.1, "transmit": 0.85, "ior": 1.5}
    raise ValueError(kind)


class ScreenGrid:
    """Screen discs hashed by centre, so that the test of a new disc against the
    placed ones looks only at those near enough to matter.  hides() needs the
    centres closer than the sum of the radii, so the answer is the one a test
    against every disc gives: the same seed still gives the same scene."""

    def __init__(self, cell):
        self.cell = cell
        self.cells = {}
        self.largest = 0.0      # the largest radius placed so far

    def near(self, disc):
        reach = disc[2] + self.largest
        low_x, high_x = (int(math.floor((disc[0] + s * reach) / self.cell)) for s in (-1, 1))
        low_y, high_y = (int(math.floor((disc[1] + s * reach) / self.cell)) for s in (-1, 1))
        for i in range(low_x, high_x + 1):
            for j in range(low_y, high_y + 1):
                yield from self.cells.get((i, j), ())

    def add(self, disc):
        key = (int(math.floor(disc[0] / self.cell)), int(math.floor(disc[1] / self.cell)))
        self.cells.setdefault(key, []).append(disc)
        self.largest = max(self.largest, disc[2])


def kind_counts(n):
    """Exact number of balls per kind: diffuse and mirror rounded, glass the rest."""
    counts = {}
    for kind, share in KIND_SHARES[:-1]:
        counts[kind] = int(round(n * share))
    counts[KIND_SHARES[-1][0]] = n - sum(counts.values())
    return counts


def place_balls(rng, n, framing, scale):
    """Return [(x, z, radius)] of n non-overlapping balls inside the framing."""
    grid = Grid()
    balls = []
    # Screen radii shrink as 1/scale; about one ball per cell.
    discs = ScreenGrid(0.1 / scale)
    attempts = 0
    limit = 20000 + 5000 * n
    while len(balls) < n:
        attempts += 1
        if attempts > limit:
            raise PlacementError("could place only %d of %d balls after %d tries"
                                 % (len(balls), n, limit))
        radius = rng.uniform(R_MIN, R_MAX)
        # Uniform on screen rather than on the table, so that the near part of
        # the table, small but large on screen, gets its share of the balls.
        x, z = framing.on_table(rng.uniform(-NDC_X_LIMIT, NDC_X_LIMIT),
                                rng.uniform(NDC_BOTTOM, NDC_TOP))
        x, z, radius = rnd(x), rnd(z), rnd(radius)
        if not framing.frames_ball(x, z, radius) or not grid.fits(x, z, radius):
            continue
        disc = framing.disc(x, z, radius)
        if any(hides(disc, d) if disc[3] < d[3] else hides(d, disc)
               for d in discs.near(disc)):
            continue
        grid.add(x, z, radius)
        balls.append((x, z, radius))
        discs.add(disc)
    return balls


def build_scene(n_balls=REFERENCE_BALLS, seed=DEFAULT_SEED, size=(2000, 2000), depth=5):
    """Return the scene as a dict in SCENE.md's format."""
    if n_balls < 0:
        raise ValueError("number of balls must be >= 0")
    rng = random.Random(seed)
    scale = math.sqrt(max(n_balls, 1) / REFERENCE_BALLS)
    eye = tuple(scale * c for c in EYE)
    look_at = tuple(scale * c for c in LOOK_AT)
    framing = Framing(eye, look_at, FOV)

    counts = kind_counts(n_balls)
    kinds = [kind for kind, _ in KIND_SHARES for _ in range(counts[kind])]
    rng.shuffle(kinds)
    balls = place_balls(rng, n_balls, framing, scale)
    spheres = [{"center": [x, r, z], "radius": r, "material": make_material(rng, kind)}
               for (x, z, r), kind in zip(balls, kinds)]

    return {
        "format": "rtcl-scene",
        "version": 1,
        "image": {"width": size[0], "height": size[1]},
        "camera": {"eye": rvec(eye), "look_at": rvec(look_at), "up": [0, 1, 0], "fov": FOV},
        "background": [0.12, 0.16, 0.24],
        "ambient": [0.1, 0.1, 0.1],
        "max_depth": depth,
        "epsilon": 1e-4,
        # Key light high and behind the camera on its right (-x is screen right
        # when looking along +z), fill light lower on its left.
        "lights": [{"position": rvec((-12 * scale, 20 * scale, -18 * scale)),
                    "color": [0.7, 0.7, 0.7]},
                   {"position": rvec((16 * scale, 12 * scale, -8 * scale)),
                    "color": [0.4, 0.4, 0.45]}],
        "spheres": spheres,
        "planes": [{"point": [0, 0, 0], "normal": [0, 1, 0],
                    "material": {"color": [0.9, 0.9, 0.85], "diffuse": 0.8,
                                 "specular": 0.1, "reflect": 0.25},
                    "checker": {"size": 2, "color": [0.15, 0.15, 0.15]}}],
    }


def compact(value):
    return json.dumps(value, separators=(", ", ": "))


def to_json(scene):
    """Serialise with one top-level key, light, sphere or plane per line."""
    lines = []
    for key, value in scene.items():
        if isinstance(value, list) and value and isinstance(value[0], dict):
            items = ",\n".join("    " + compact(v) for v in value)
            lines.append("  %s: [\n%s\n  ]" % (json.dumps(key), items))
        else:
            lines.append("  %s: %s" % (json.dumps(key), compact(value)))
    return "{\n" + ",\n".join(lines) + "\n}\n"
