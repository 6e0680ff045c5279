"""Binary PPM pixels, compared while ignoring headers (rtcl's name the kernel)."""

from .images import header_fields


def pixels(path):
    """Returns ((width, height), pixel bytes) of a binary PPM, skipping comments."""
    with open(path, "rb") as f:
        data = f.read()
    fields, pos = header_fields(data, 4)  # P6, width, height, maxval
    return (int(fields[1]), int(fields[2])), data[pos:]


def differences(reference, other):
    """Returns (channel values that differ, largest difference)."""
    diffs = [abs(a - b) for a, b in zip(reference, other) if a != b]
    return len(diffs), max(diffs, default=0)
