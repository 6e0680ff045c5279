"""Binary PPM pixels, compared while ignoring headers (rtcl's name the kernel)."""


def pixels(path):
    """Returns ((width, height), pixel bytes) of a binary PPM, skipping comments."""
    with open(path, "rb") as f:
        data = f.read()
    fields, pos = [], 0
    while len(fields) < 4:  # P6, width, height, maxval
        while data[pos:pos + 1].isspace():
            pos += 1
        if data[pos:pos + 1] == b"#":
            pos = data.index(b"\n", pos) + 1
            continue
        end = pos
        while not data[end:end + 1].isspace():
            end += 1
        fields.append(data[pos:end])
        pos = end
    return (int(fields[1]), int(fields[2])), data[pos + 1:]


def differences(reference, other):
    """Returns (channel values that differ, largest difference)."""
    diffs = [abs(a - b) for a, b in zip(reference, other) if a != b]
    return len(diffs), max(diffs, default=0)
