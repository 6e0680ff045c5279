"""3-vectors as tuples, for the scene generator and the POV-Ray converter."""

import math


def sub(a, b):
    return tuple(x - y for x, y in zip(a, b))


def dot(a, b):
    return sum(x * y for x, y in zip(a, b))


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def scale(a, s):
    return tuple(x * s for x in a)


def normalize(a):
    n = math.sqrt(dot(a, a))
    return tuple(x / n for x in a)
