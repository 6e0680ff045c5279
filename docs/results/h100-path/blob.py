"""A >= 1 M-triangle displaced icosphere as binary PLY (level 8: 1,310,720
triangles), the issue 40 speed scene's 'rough gold' object."""
import sys, numpy as np
level = int(sys.argv[2]) if len(sys.argv) > 2 else 8
t = (1 + 5 ** 0.5) / 2
v = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t), (0, 1, -t),
     (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
f = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4), (11, 10, 2),
     (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9), (4, 9, 5), (2, 4, 11),
     (6, 2, 10), (8, 6, 7), (9, 8, 1)]
V = np.array(v, float); V /= np.linalg.norm(V, axis=1)[:, None]; F = np.array(f, np.int64)
for _ in range(level):
    e = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]); e.sort(axis=1)
    u, inv = np.unique(e, axis=0, return_inverse=True); inv = inv.reshape(3, -1)
    m = V[u[:, 0]] + V[u[:, 1]]; m /= np.linalg.norm(m, axis=1)[:, None]
    a, b, c = F[:, 0], F[:, 1], F[:, 2]; ab, bc, ca = (inv[0] + len(V), inv[1] + len(V), inv[2] + len(V))
    V = np.concatenate([V, m])
    F = np.concatenate([np.stack([a, ab, ca], 1), np.stack([b, bc, ab], 1), np.stack([c, ca, bc], 1), np.stack([ab, bc, ca], 1)])
x, y, z = V[:, 0], V[:, 1], V[:, 2]
r = 1 + 0.08 * np.sin(9 * x) * np.sin(7 * y + 1) * np.sin(8 * z + 2) + 0.03 * np.sin(31 * x + 23 * y)
V = V * r[:, None] * 0.45 + np.array([0, -0.5, 0])
with open(sys.argv[1], "wb") as out:
    out.write(b"ply\nformat binary_little_endian 1.0\nelement vertex %d\nproperty float x\nproperty float y\nproperty float z\nelement face %d\nproperty list uchar int vertex_indices\nend_header\n" % (len(V), len(F)))
    out.write(V.astype("<f4").tobytes())
    rec = np.zeros(len(F), dtype=[("n", "u1"), ("i", "<i4", 3)]); rec["n"] = 3; rec["i"] = F
    out.write(rec.tobytes())
print(len(V), "vertices", len(F), "triangles")
