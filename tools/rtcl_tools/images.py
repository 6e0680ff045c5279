"""The images rtcl writes, read and compared: PPM, PFM and PNG with the standard
library alone (rtcl's own writers: host/output/image_common.c, host/output/image_png.c); any
other format (EXR, HDR, TIFF, ...) through OpenImageIO's idiff, when installed.

Values are compared on one scale, 0 ... 1 for the full range of an integer
format (255 for 8 bits), as floats for PFM: the largest absolute difference and
PSNR = 10 log10(1 / mean squared difference) over every channel value.
"""

import array
import dataclasses
import math
import re
import shutil
import subprocess
import sys
import zlib

from .files import open_input

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
PNG_CHANNELS = {0: 1, 2: 3, 4: 2, 6: 4}   # colour type: channels (no palette)


class ImageError(Exception):
    """An image that cannot be read or compared (one line, naming the file)."""


class SizeDiffers(Exception):
    """Two images of different sizes or channel counts: a result (they differ), not
    an error; the message is the report line."""

    def __init__(self, path, reference_path, shape, reference_shape):
        super().__init__(f"{path}: size {shape[0]}x{shape[1]} ({shape[2]} channels) differs "
                         f"from {reference_shape[0]}x{reference_shape[1]} "
                         f"({reference_shape[2]} channels) of {reference_path}")


@dataclasses.dataclass
class Image:
    width: int
    height: int
    channels: int
    values: object          # bytes, array('H') or array('f'), rows from the top
    maxval: int | None      # the integer range (255, 65535), None for floats


@dataclasses.dataclass
class Comparison:
    differing: int          # channel values (native) or pixels (idiff) that differ
    unit: str               # "values" or "pixels"
    max_abs: float          # on the 0 ... 1 scale
    psnr: float             # dB, inf when identical
    max_levels: int | None  # the largest difference in 8-bit levels, for 8-bit images


def native_format(data):
    """Returns 'ppm', 'pfm' or 'png' from an image's first bytes, else None."""
    if data.startswith(PNG_SIGNATURE):
        return "png"
    if data[:2] in (b"PF", b"Pf"):
        return "pfm"
    if data[:2] == b"P6":
        return "ppm"
    return None


def read(path):
    """Returns the Image of a PPM, PFM or PNG file; ImageError otherwise."""
    try:
        with open_input(path) as stream:
            data = stream.read()
    except OSError as error:
        raise ImageError(f"{path}: cannot read: {error.strerror}") from None
    kind = native_format(data)
    try:
        if kind == "png":
            return read_png(data)
        if kind in ("ppm", "pfm"):
            return read_netpbm(data, kind)
    except (ValueError, IndexError, zlib.error) as error:
        raise ImageError(f"{path}: not a readable {kind.upper()} file: {error}") from None
    raise ImageError(f"{path}: not a PPM, PFM or PNG file")


def header_fields(data, count):
    """Returns (the first count whitespace-separated header fields, the offset of the
    byte after the last one's single whitespace), skipping '#' comment lines."""
    fields, pos = [], 0
    while len(fields) < count:
        while data[pos:pos + 1].isspace():
            pos += 1
        if data[pos:pos + 1] == b"#":
            pos = data.index(b"\n", pos) + 1
            continue
        end = pos
        while end < len(data) and not data[end:end + 1].isspace():
            end += 1
        if end == pos:
            raise ValueError("truncated header")
        fields.append(data[pos:end].decode("ascii"))
        pos = end
    return fields, pos + 1


def read_netpbm(data, kind):
    """PPM (P6, 8 or 16 bits) or PFM (PF: RGB, Pf: grey; rows from the bottom)."""
    fields, pos = header_fields(data, 4)
    width, height = int(fields[1]), int(fields[2])
    channels = 1 if fields[0] == "Pf" else 3
    count = width * height * channels
    if kind == "ppm":
        maxval = int(fields[3])
        if maxval < 256:
            values = data[pos:pos + count]
        else:
            values = array.array("H", data[pos:pos + 2 * count])
            if sys.byteorder == "little":
                values.byteswap()   # PPM stores 16 bits big-endian
        if len(values) != count:
            raise ValueError(f"{len(values)} of {count} values")
        return Image(width, height, channels, values, maxval)
    scale = float(fields[3])
    values = array.array("f", data[pos:pos + 4 * count])
    if len(values) != count:
        raise ValueError(f"{len(values)} of {count} values")
    if (scale < 0) != (sys.byteorder == "little"):
        values.byteswap()
    row = width * channels
    rows = [values[start:start + row] for start in range(0, count, row)]
    flipped = array.array("f")
    for part in reversed(rows):
        flipped.extend(part)
    return Image(width, height, channels, flipped, None)


def png_chunks(data):
    """Yields (type, payload) of each PNG chunk."""
    pos = len(PNG_SIGNATURE)
    while pos + 8 <= len(data):
        length = int.from_bytes(data[pos:pos + 4], "big")
        kind = data[pos + 4:pos + 8]
        yield kind, data[pos + 8:pos + 8 + length]
        pos += 12 + length


def read_png(data):
    """Grey, grey+alpha, RGB or RGBA PNG of 8 or 16 bits, not interlaced."""
    header, compressed = None, []
    for kind, payload in png_chunks(data):
        if kind == b"IHDR":
            header = payload
        elif kind == b"IDAT":
            compressed.append(payload)
    if header is None or len(header) != 13:
        raise ValueError("no IHDR chunk")
    width, height = int.from_bytes(header[0:4], "big"), int.from_bytes(header[4:8], "big")
    depth, colour, interlace = header[8], header[9], header[12]
    if depth not in (8, 16) or colour not in PNG_CHANNELS or interlace:
        raise ValueError(f"bit depth {depth}, colour type {colour}, interlace {interlace} "
                         "(read here: 8 or 16 bits, no palette, not interlaced)")
    channels = PNG_CHANNELS[colour]
    pixel_bytes = channels * depth // 8
    raw = zlib.decompress(b"".join(compressed))
    stride = width * pixel_bytes
    if len(raw) != height * (stride + 1):
        raise ValueError(f"{len(raw)} bytes of pixel data, expected {height * (stride + 1)}")
    out = bytearray(height * stride)
    above = bytes(stride)
    for y in range(height):
        start = y * (stride + 1)
        row = unfilter(raw[start], raw[start + 1:start + 1 + stride], above, pixel_bytes)
        out[y * stride:(y + 1) * stride] = row
        above = row
    if depth == 8:
        return Image(width, height, channels, bytes(out), 255)
    values = array.array("H", bytes(out))
    if sys.byteorder == "little":
        values.byteswap()
    return Image(width, height, channels, values, 65535)


def unfilter(kind, line, above, bpp):
    """Returns one PNG scanline with its filter (0 ... 4) undone."""
    if kind == 0:
        return bytes(line)
    if kind == 2:   # Up: what rtcl writes on every row
        return bytes((x + b) & 255 for x, b in zip(line, above))
    row = bytearray(line)
    for i in range(len(row)):
        a = row[i - bpp] if i >= bpp else 0
        b = above[i]
        if kind == 1:
            row[i] = (row[i] + a) & 255
        elif kind == 3:
            row[i] = (row[i] + (a + b) // 2) & 255
        elif kind == 4:
            c = above[i - bpp] if i >= bpp else 0
            p = a + b - c
            pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
            predictor = a if pa <= pb and pa <= pc else b if pb <= pc else c
            row[i] = (row[i] + predictor) & 255
        else:
            raise ValueError(f"unknown filter type {kind}")
    return bytes(row)


def compare(reference, other):
    """Returns the Comparison of two Images of one size and channel count."""
    if reference.values == other.values and reference.maxval == other.maxval:
        return Comparison(0, "values", 0.0, math.inf, 0 if reference.maxval == 255 else None)
    scale_a = 1.0 / reference.maxval if reference.maxval else 1.0
    scale_b = 1.0 / other.maxval if other.maxval else 1.0
    differing, largest, squares = 0, 0.0, 0.0
    for a, b in zip(reference.values, other.values):
        if a != b or scale_a != scale_b:
            difference = abs(a * scale_a - b * scale_b)
            if difference:
                differing += 1
                squares += difference * difference
                largest = max(largest, difference)
    mse = squares / max(1, len(reference.values))
    psnr = math.inf if mse == 0 else 10 * math.log10(1 / mse)
    levels = round(largest * 255) if reference.maxval == other.maxval == 255 else None
    return Comparison(differing, "values", largest, psnr, levels)


def idiff_program():
    return shutil.which("idiff")


def oiio_program(name):
    """Returns OpenImageIO's program name (idiff, iinfo) on PATH; ImageError without it."""
    program = shutil.which(name)
    if program is None:
        raise ImageError(f"only PPM, PFM and PNG are read without OpenImageIO's {name} "
                         "(apt-get install openimageio-tools)")
    return program


def last_lines(output, count=2):
    lines = [line.strip() for line in output.splitlines() if line.strip()]
    return " ".join(lines[-count:])


def oiio_shape(path):
    """Returns (width, height, channels) of the first image of the file at path as
    OpenImageIO's iinfo reads it; ImageError when it cannot."""
    try:
        result = subprocess.run([oiio_program("iinfo"), str(path)], capture_output=True,
                                text=True, timeout=300)
    except subprocess.TimeoutExpired:
        raise ImageError(f"{path}: iinfo did not finish in 300 s") from None
    match = re.search(r":\s+(\d+)\s+x\s+(\d+),\s+(\d+)\s+channel", result.stdout)
    if result.returncode != 0 or match is None:
        raise ImageError(f"{path}: OpenImageIO cannot read it: "
                         f"{last_lines(result.stdout + result.stderr) or 'iinfo failed'}")
    return tuple(int(value) for value in match.groups())


def compare_with_idiff(reference_path, path, threshold, reference_shape=None):
    """Returns the Comparison that OpenImageIO's idiff makes of two files of any
    format it reads; ImageError when it cannot read one.  Their sizes are compared
    first (iinfo; reference_shape when known): idiff compares images of different
    sizes over their common part and answers FAILURE, which is no comparison."""
    for name in (reference_path, path):
        try:
            open_input(name).close()
        except OSError as error:
            raise ImageError(f"{name}: cannot read: {error.strerror}") from None
    program = oiio_program("idiff")
    shapes = (reference_shape or oiio_shape(reference_path), oiio_shape(path))
    if shapes[0] != shapes[1]:
        raise SizeDiffers(path, reference_path, shapes[1], shapes[0])
    limit = f"{threshold:g}" if threshold else "0"
    result = subprocess.run([program, "-fail", limit, "-warn", limit, reference_path, path],
                            capture_output=True, text=True)
    output = result.stdout + result.stderr
    if result.returncode == 3:
        raise ImageError(f"{path}: size or channels differ from {reference_path}")
    if result.returncode > 3 or (result.returncode == 2 and "Max error" not in output):
        raise ImageError(f"{path}: idiff cannot compare it: {last_lines(output)}")
    if "Max error" not in output:
        return Comparison(0, "pixels", 0.0, math.inf, None)
    largest = float(re.search(r"Max error\s*=\s*([-+0-9.eE]+|inf|nan)", output).group(1))
    psnr_match = re.search(r"Peak SNR\s*=\s*([-+0-9.eE]+|inf|nan)", output)
    over = re.search(r"(\d+) pixels \([0-9.]+%\) over", output)
    return Comparison(int(over.group(1)) if over else 0, "pixels", largest,
                      float(psnr_match.group(1)) if psnr_match else math.inf, None)
