"""Pictures as a person's eye would read them, for the checks of weaver's
PNGs (check_slice.py, check_serve.py): a PNG decoded with Python's zlib
alone (not weaver's code), and the viridis scale weaver colours by."""
import struct
import zlib

VIRIDIS = [(68, 1, 84), (72, 40, 120), (62, 74, 137), (49, 104, 142), (38, 130, 142),
           (31, 158, 137), (53, 183, 121), (110, 206, 88), (181, 222, 43), (253, 231, 37)]


def fail(message):
    raise ValueError(message)


def viridis(t):
    t = min(max(t, 0.0), 1.0) * 9
    i = min(8, int(t))
    f = t - i
    return tuple(int(round(a + (b - a) * f + 1e-9)) if (a + (b - a) * f) % 1 != 0.5 else
                 int(a + (b - a) * f + 0.5) for a, b in zip(VIRIDIS[i], VIRIDIS[i + 1]))


def read_png(path):
    """(width, height, rows, text) of an 8-bit RGB PNG: a path or its bytes."""
    data = path if isinstance(path, bytes) else open(path, "rb").read()
    if data[:8] != b"\x89PNG\r\n\x1a\n":
        fail("not a PNG signature")
    at, idat, text = 8, b"", {}
    while at < len(data):
        n, kind = struct.unpack(">I4s", data[at:at + 8])
        body = data[at + 8:at + 8 + n]
        (crc,) = struct.unpack(">I", data[at + 8 + n:at + 12 + n])
        if zlib.crc32(kind + body) != crc:
            fail(f"bad CRC in chunk {kind}")
        if kind == b"IHDR":
            w, h, depth, color = struct.unpack(">IIBB", body[:10])
            if (depth, color) != (8, 2):
                fail("not 8-bit RGB")
        elif kind == b"IDAT":
            idat += body
        elif kind == b"tEXt":
            k, v = body.split(b"\0", 1)
            text[k.decode()] = v.decode()
        at += 12 + n
    raw = zlib.decompress(idat)
    stride = 3 * w
    rows, prev = [], bytearray(stride)
    for y in range(h):
        f, line = raw[y * (stride + 1)], bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - 3] if i >= 3 else 0
            b, c = prev[i], prev[i - 3] if i >= 3 else 0
            if f == 1:
                line[i] = (line[i] + a) & 255
            elif f == 2:
                line[i] = (line[i] + b) & 255
            elif f == 3:
                line[i] = (line[i] + (a + b) // 2) & 255
            elif f == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
            elif f != 0:
                fail(f"unknown filter {f}")
        rows.append(bytes(line))
        prev = line
    return w, h, rows, text


def pixel(rows, x, y):
    return tuple(rows[y][3 * x:3 * x + 3])


