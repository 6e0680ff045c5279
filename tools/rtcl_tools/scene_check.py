"""The scene validator's messages ("PATH: what is wrong", rtcl's wording) and its
checks of fields, numbers and vectors, as host/scene/scene_check.c words and checks them;
tools/rtcl_tools/scene.py reads the sections of docs/SCENE.md with them."""

import math
import sys

MIN_MAGNITUDE, MAX_MAGNITUDE = 1e-18, 1e18   # SCENE.md: the device computes in float
NAME_MAX = 64                                # longer keys are cut in messages
SUGGEST_MAX_LENGTH = 64                      # host/base/suggest.h


class SceneError(ValueError):
    """A scene that breaks a rule of SCENE.md; the message names the place."""


# ---- messages ----------------------------------------------------------------------

def _escaped(text, quoted=True):
    """Returns text with control characters (and quotes) escaped, cut after NAME_MAX."""
    cut = len(text) > NAME_MAX
    out = []
    for char in text[:NAME_MAX]:
        if quoted and char in '"\\':
            out.append("\\" + char)
        elif char == "\n":
            out.append("\\n")
        elif char == "\t":
            out.append("\\t")
        elif ord(char) < 0x20 or ord(char) == 0x7f:
            out.append("\\x%02x" % ord(char))
        else:
            out.append(char)
    return "".join(out) + ("..." if cut else "")


def child(path, key):
    """Returns the path of key (a str) or index (an int) below path ('' = the document)."""
    if isinstance(key, int):
        return f"{path}[{key}]"
    if not path:
        return key
    if key.isidentifier() and key.isascii():
        return f"{path}.{key}"
    return f'{path}["{_escaped(key)}"]'


def fail(path, what):
    raise SceneError(f"{path or '(top level)'}: {what}")


def format_number(value):
    """Returns the shortest %g text that reads back as value (rtcl's fmt_num)."""
    for precision in range(6, 18):
        text = "%.*g" % (precision, value)
        if float(text) == value:
            break
    return text


def format_vector(values):
    return "[" + ", ".join(format_number(v) for v in values) + "]"


def type_name(value):
    if isinstance(value, bool) or value is None:
        return {True: "true", False: "false", None: "null"}[value]
    for kind, name in ((dict, "an object"), (list, "an array"), (str, "a string"),
                       (int, "an integer"), (float, "a real number")):
        if isinstance(value, kind):
            return name
    return "an unknown JSON value"


# ---- values --------------------------------------------------------------------------

def distance(a, b):
    """The Damerau-Levenshtein distance (adjacent swaps count one), as
    host/base/suggest.c computes it (which gives up on words over 64 characters)."""
    if len(a) > SUGGEST_MAX_LENGTH or len(b) > SUGGEST_MAX_LENGTH:
        return math.inf
    rows = [list(range(len(b) + 1))]
    for i in range(1, len(a) + 1):
        row = [i] + [0] * len(b)
        for j in range(1, len(b) + 1):
            up = rows[-1]
            row[j] = min(up[j] + 1, row[j - 1] + 1, up[j - 1] + (a[i - 1] != b[j - 1]))
            if i > 1 and j > 1 and a[i - 1] == b[j - 2] and a[i - 2] == b[j - 1]:
                row[j] = min(row[j], rows[-2][j - 2] + 1)
        rows.append(row)
    return rows[-1][-1]


def did_you_mean(word, names):
    """'; did you mean "NAME"?' for the nearest of names within host/base/suggest.c's
    limit (one edit up to five characters, two from six), else ''."""
    limit = min(max(len(word) // 3, 1), 2)
    best = None
    for name in names:
        d = distance(word, name)
        if 0 < d <= limit and (best is None or d < best[0]):
            best = (d, name)
    return f'; did you mean "{best[1]}"?' if best else ""


def check_keys(value, path, allowed):
    if not isinstance(value, dict):
        fail(path, f"must be an object, got {type_name(value)}")
    for key in value:
        if key not in allowed:
            fail(path, f'unknown key "{_escaped(key)}"' + did_you_mean(key, allowed))
    return value


def required(obj, key, path):
    if key not in obj:
        fail(child(path, key), "required field is missing")
    return obj[key]


class Written(float):
    """A JSON number that keeps its text, to name a number that underflows."""

    def __new__(cls, text):
        number = super().__new__(cls, text)
        number.text = text
        return number


def underflow_text(value):
    """The text of a number written nonzero that reads as 0 or a denormal, as
    rtcl quotes it; None for any other number."""
    text = getattr(value, "text", None)
    x = float(value)
    if text is None or (x != 0 and abs(x) >= sys.float_info.min):
        return None
    if not any(c in "123456789" for c in text.lower().split("e")[0]):
        return None             # written as zero: 0.0, 0e-9
    return text if len(text) < 40 else f"a {len(text)}-character number"


def number(value, path, kind="any"):
    """Returns value as a float if it is a number in range kind (rtcl's check_number)."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        fail(path, f"must be a number, got {type_name(value)}")
    try:
        x = float(value)
    except OverflowError:
        x = math.inf if value > 0 else -math.inf
    if not math.isfinite(x):
        fail(path, f"must be finite, got {format_number(x)}")
    written = underflow_text(value) if kind in ("positive", "fov") else None
    if written and kind == "positive":
        fail(path, f"must be between 1e-18 and 1e+18 (rtcl computes in float), got {written}, "
                   "which underflows to 0")
    if written:
        fail(path, f"must be > 0 and < 180, got {written}, which underflows to 0")
    ranges = {"positive": (x > 0, "must be > 0"), "non-negative": (x >= 0, "must be >= 0"),
              "unit": (0 <= x <= 1, "must be between 0 and 1"),
              "fov": (0 < x < 180, "must be > 0 and < 180")}
    if kind in ranges and not ranges[kind][0]:
        fail(path, f"{ranges[kind][1]}, got {format_number(x)}")
    if kind != "direction" and x != 0 and not MIN_MAGNITUDE <= abs(x) <= MAX_MAGNITUDE:
        zero = "" if kind in ("positive", "fov") else "0 or "
        scope = " in magnitude" if kind == "any" else ""
        fail(path, f"must be {zero}between 1e-18 and 1e+18{scope} (rtcl computes in float), "
                   f"got {format_number(x)}")
    return x


def integer(value, path, low, high):
    """Returns value if it is a JSON integer (not 2.0) in low ... high."""
    if isinstance(value, float):
        text = format_number(value)
        fail(path, f"must be an integer, got {text if set(text) & set('.eni') else text + '.0'}")
    if isinstance(value, bool) or not isinstance(value, int):
        fail(path, f"must be an integer, got {type_name(value)}")
    if not low <= value <= high:
        fail(path, f"must be between {low} and {high}, got {value}")
    return value


def vec3(value, path, kind="any"):
    """Returns a vec3 (kind "any" or "direction") or a colour ("non-negative") as a tuple."""
    if not isinstance(value, list):
        fail(path, f"must be an array of 3 numbers, got {type_name(value)}")
    if len(value) != 3:
        fail(path, f"must be an array of 3 numbers, got {len(value)} "
                   f"element{'' if len(value) == 1 else 's'}")
    return tuple(number(part, child(path, i), kind) for i, part in enumerate(value))


def optional(obj, key, path, read, default, *args):
    """Returns read(obj[key], path.key, *args), or default when key is absent."""
    return read(obj[key], child(path, key), *args) if key in obj else default


def scale_to_unit_max(v):
    """Returns v scaled so that its largest part has magnitude 1; None for zero."""
    largest = max(abs(x) for x in v)
    return None if largest == 0 else tuple(x / largest for x in v)


def length(v):
    return math.sqrt(sum(x * x for x in v))
