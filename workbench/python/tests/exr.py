"""A small OpenEXR reader for the tests: what `flarebench render -o x.exr` and
`flarebench dataset` write.

That is one part of scan lines, channels of 32-bit floats or unsigned ints (a dataset's
`ghost_id`), uncompressed or ZIP/ZIPS compressed (the OpenEXR 2 file layout: a header of
attributes, a table of chunk offsets, then chunks of `y`, size, data). Nothing else is read;
anything else raises ValueError. Only the standard library and NumPy are used, so the tests
need no OpenEXR package.
"""

import struct
import zlib

import numpy as np

MAGIC = 20000630
# Compression codes (ImfCompression.h) and the scan lines per chunk of each kind read here.
LINES_PER_CHUNK = {0: 1, 2: 1, 3: 16}  # NONE, ZIPS, ZIP
# A channel's pixel type (UINT 0, HALF 1, FLOAT 2) → its NumPy type; HALF is not read here.
PIXEL_TYPES = {0: "<u4", 2: "<f4"}


def _attributes(data):
    """The header's attributes as {name: (type, bytes)}, and the offset after them."""
    pos = 8
    attrs = {}
    while data[pos] != 0:
        end = data.index(b"\0", pos)
        name = data[pos:end].decode()
        tend = data.index(b"\0", end + 1)
        kind = data[end + 1 : tend].decode()
        (size,) = struct.unpack_from("<i", data, tend + 1)
        value = data[tend + 5 : tend + 5 + size]
        attrs[name] = (kind, value)
        pos = tend + 5 + size
    return attrs, pos + 1


def _channels(value):
    """Channel names and pixel types of a `chlist`, in file (alphabetical) order."""
    out = []
    pos = 0
    while value[pos] != 0:
        end = value.index(b"\0", pos)
        name = value[pos:end].decode()
        (ptype,) = struct.unpack_from("<i", value, end + 1)
        out.append((name, ptype))
        pos = end + 1 + 16
    return out


def _unzip(raw, expected):
    """ZIP chunk data: zlib, then OpenEXR's byte predictor and interleave undone."""
    t = np.frombuffer(zlib.decompress(raw), dtype=np.uint8).astype(np.int64)
    if t.size != expected:
        raise ValueError(f"a chunk inflates to {t.size} bytes, not {expected}")
    # t[i] = t[i-1] + t[i] - 128 (mod 256) for i > 0, t[0] unchanged: a running sum.
    t = ((np.cumsum(t - 128) + 128) & 0xFF).astype(np.uint8)
    half = (expected + 1) // 2
    out = np.empty(expected, dtype=np.uint8)
    out[0::2] = t[:half]
    out[1::2] = t[half:]
    return out.tobytes()


def read_channels(path):
    """Every channel of the image at `path` by name: H×W arrays, float32 or uint32."""
    with open(path, "rb") as f:
        data = f.read()
    magic, version = struct.unpack_from("<ii", data, 0)
    if magic != MAGIC or version & 0xFF != 2 or version & ~0xFF:
        raise ValueError(f"{path}: not a single-part scan-line OpenEXR 2 file")
    attrs, pos = _attributes(data)
    xmin, ymin, xmax, ymax = struct.unpack("<iiii", attrs["dataWindow"][1])
    width, height = xmax - xmin + 1, ymax - ymin + 1
    compression = attrs["compression"][1][0]
    if compression not in LINES_PER_CHUNK:
        raise ValueError(f"{path}: compression {compression} is not read here")
    channels = _channels(attrs["channels"][1])
    if any(ptype not in PIXEL_TYPES for _, ptype in channels):
        raise ValueError(f"{path}: a channel is neither 32-bit float nor uint: {channels}")
    lines = LINES_PER_CHUNK[compression]
    chunks = (height + lines - 1) // lines
    offsets = struct.unpack_from(f"<{chunks}Q", data, pos)
    # Every type read here is 4 bytes: a line holds each channel's `width` samples in turn.
    planes = np.empty((height, len(channels), width * 4), dtype=np.uint8)
    for offset in offsets:
        y, size = struct.unpack_from("<ii", data, offset)
        raw = data[offset + 8 : offset + 8 + size]
        n = min(lines, ymax + 1 - y)
        expected = n * len(channels) * width * 4
        block = raw if size == expected else _unzip(raw, expected)
        row = y - ymin
        planes[row : row + n] = np.frombuffer(block, dtype=np.uint8).reshape(
            n, len(channels), width * 4
        )
    return {
        name: np.ascontiguousarray(planes[:, k, :]).view(PIXEL_TYPES[ptype]).astype(
            PIXEL_TYPES[ptype][1:]
        )
        for k, (name, ptype) in enumerate(channels)
    }


def read_layer(channels, layer=""):
    """The RGB layer `layer` (`""` the image, `"ghosts"`, `"light0"`, …) of `read_channels`'
    result as an H×W×3 float32 array."""
    prefix = f"{layer}." if layer else ""
    return np.stack([channels[prefix + c] for c in "RGB"], axis=-1).astype(np.float32)


def read_exr(path):
    """The image at `path` as an H×W×3 float32 array (channels R, G, B)."""
    channels = read_channels(path)
    if any(a.dtype != np.float32 for a in channels.values()):
        raise ValueError(f"{path}: a channel is not 32-bit float: {sorted(channels)}")
    return read_layer(channels)
