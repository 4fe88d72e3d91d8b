"""Value codecs of the formats, vectorized: LEB128 varints, Morton keys, binary16 colours,
octahedral normals, 8-bit sRGB and delta-coded byte planes (formats/svo.md, formats/vfrag.md).

Float arithmetic is binary32 step by step where the spec says so, so that derived samples equal
the C++ writer's byte for byte (numpy rounds each operation and never fuses a multiply-add).
"""

import ctypes
import ctypes.util

import numpy as np

F32 = np.float32


def varint(data, pos):
    """One LEB128 varint at ``pos`` of ``data``: (value, next position), or None if malformed."""
    value = shift = 0
    for i in range(10):
        if pos + i >= len(data):
            return None
        b = data[pos + i]
        if i == 9 and b > 1:
            return None
        value |= (b & 0x7F) << shift
        shift += 7
        if not b & 0x80:
            return value, pos + i + 1
    return None


def varints(data, count):
    """The first ``count`` LEB128 varints of the bytes ``data``: (uint64 array, bytes used), or
    None when there are fewer or one is longer than 10 bytes."""
    b = np.frombuffer(data, dtype=np.uint8)
    ends = np.flatnonzero(b < 0x80)
    if len(ends) < count:
        return None
    if count == 0:
        return np.zeros(0, np.uint64), 0
    ends = ends[:count]
    used = int(ends[-1]) + 1
    starts = np.empty(count, np.int64)
    starts[0] = 0
    starts[1:] = ends[:-1] + 1
    lengths = ends - starts + 1
    if lengths.max() > 10:
        return None
    b = b[:used]
    index = np.repeat(np.arange(count), lengths)
    within = np.arange(used) - starts[index]
    if np.any((within == 9) & (b > 1)):
        return None
    parts = (b & 0x7F).astype(np.uint64) << (7 * within).astype(np.uint64)
    return np.add.reduceat(parts, starts), used


def gap_keys(gaps):
    """Ascending keys from gaps key[i] − key[i−1] − 1 with key[−1] = −1."""
    return np.cumsum(gaps + np.uint64(1), dtype=np.uint64) - np.uint64(1)


def _spread(v):
    v = v.astype(np.uint64) & np.uint64(0x1FFFFF)
    v = (v | (v << np.uint64(32))) & np.uint64(0x1F00000000FFFF)
    v = (v | (v << np.uint64(16))) & np.uint64(0x1F0000FF0000FF)
    v = (v | (v << np.uint64(8))) & np.uint64(0x100F00F00F00F00F)
    v = (v | (v << np.uint64(4))) & np.uint64(0x10C30C30C30C30C3)
    v = (v | (v << np.uint64(2))) & np.uint64(0x1249249249249249)
    return v


def _compact(v):
    v = v & np.uint64(0x1249249249249249)
    v = (v | (v >> np.uint64(2))) & np.uint64(0x10C30C30C30C30C3)
    v = (v | (v >> np.uint64(4))) & np.uint64(0x100F00F00F00F00F)
    v = (v | (v >> np.uint64(8))) & np.uint64(0x1F0000FF0000FF)
    v = (v | (v >> np.uint64(16))) & np.uint64(0x1F00000000FFFF)
    v = (v | (v >> np.uint64(32))) & np.uint64(0x1FFFFF)
    return v


_AXIS_BITS = [np.uint64(sum(1 << (3 * i + a) for i in range(21))) for a in range(3)]


def morton_offset(keys, offset):
    """Keys of the nodes at ``offset`` (dx, dy, dz, each −1, 0 or 1) from ``keys``, by dilated
    integer arithmetic; a step out of the level's cube gives a key ≥ 8^level (a carry or a borrow
    reaches the bits above the level's)."""
    out = keys.copy()
    for a, d in enumerate(offset):
        if d == 0:
            continue
        mask = _AXIS_BITS[a]
        part = out & mask
        if d > 0:
            part = ((part | ~mask) + np.uint64(1 << a)) & mask
        else:
            part = (part - np.uint64(1 << a)) & mask
        out = (out & ~mask) | part
    return out


def morton_encode(xyz):
    """Morton keys (x in bit 0) of an N×3 array of non-negative coordinates below 2²¹."""
    xyz = np.asarray(xyz)
    return _spread(xyz[:, 0]) | (_spread(xyz[:, 1]) << np.uint64(1)) | (_spread(xyz[:, 2]) << np.uint64(2))


def morton_decode(keys):
    """N×3 int64 coordinates of Morton keys."""
    keys = np.asarray(keys, dtype=np.uint64)
    out = np.empty((len(keys), 3), np.int64)
    for a in range(3):
        out[:, a] = _compact(keys >> np.uint64(a))
    return out


def undelta_planes(raw, lanes, count, lane_bytes):
    """Values from lane-after-lane deltas: ``lanes`` lanes of ``count`` values of ``lane_bytes``
    bytes (1 or 2), each the difference mod 2^(8·lane_bytes) to the previous value of its lane;
    two-byte lanes stored as a plane of low bytes, then one of high bytes. Returns count×lanes."""
    b = np.frombuffer(raw, dtype=np.uint8)
    n = lanes * count
    if lane_bytes == 1:
        d = b.reshape(lanes, count)
        return np.cumsum(d, axis=1, dtype=np.uint8).T.copy()
    d = (b[:n].astype(np.uint16) | (b[n:].astype(np.uint16) << np.uint16(8))).reshape(lanes, count)
    return np.cumsum(d, axis=1, dtype=np.uint16).T.copy()


def oct_decode(codes, bits):
    """Unit float32 vectors (N×3) of octahedral codes with ``bits`` bits per axis (x low); code 0
    decodes to the zero vector."""
    codes = np.asarray(codes, dtype=np.uint32)
    half = 1 << (bits - 1)
    mask = np.uint32((1 << bits) - 1)
    x = ((codes & mask).astype(np.int32) - half).astype(F32) / F32(half - 1)
    y = (((codes >> np.uint32(bits)) & mask).astype(np.int32) - half).astype(F32) / F32(half - 1)
    z = (F32(1) - np.abs(x)) - np.abs(y)
    low = z < 0
    fx = (F32(1) - np.abs(y)) * np.where(x < 0, F32(-1), F32(1))
    fy = (F32(1) - np.abs(x)) * np.where(y < 0, F32(-1), F32(1))
    x = np.where(low, fx, x)
    y = np.where(low, fy, y)
    inv = F32(1) / np.sqrt((x * x + y * y) + z * z)
    out = np.stack([x * inv, y * inv, z * inv], axis=1)
    out[codes == 0] = 0
    return out


def _oct_snorm(v, bits):
    half = F32(1 << (bits - 1))
    return (np.minimum(np.maximum(v, F32(-1)), F32(1)) * (half - F32(1)) + (half + F32(0.5))).astype(np.uint32)


def oct_encode(n, bits):
    """Octahedral codes of float32 vectors (N×3) of any length; 0 for zero or non-finite ones."""
    n = np.asarray(n, dtype=F32)
    with np.errstate(invalid="ignore", divide="ignore"):
        l1 = (np.abs(n[:, 0]) + np.abs(n[:, 1])) + np.abs(n[:, 2])
        ok = (l1 > F32(1e-20)) & np.isfinite(l1)
        safe = np.where(ok, l1, F32(1))
        x, y, z = n[:, 0] / safe, n[:, 1] / safe, n[:, 2]
    fx = (F32(1) - np.abs(y)) * np.where(x < 0, F32(-1), F32(1))
    fy = (F32(1) - np.abs(x)) * np.where(y < 0, F32(-1), F32(1))
    low = z < 0
    code = _oct_snorm(np.where(low, fx, x), bits) | (_oct_snorm(np.where(low, fy, y), bits) << np.uint32(bits))
    return np.where(ok, code, np.uint32(0))


def unorm8(v):
    """binary32 values in [0, 1] to bytes: ⌊clamp(v)·255 + ½⌋ (NaN and negatives to 0)."""
    v = np.asarray(v, dtype=F32)
    with np.errstate(invalid="ignore"):
        c = np.where(v > 0, np.minimum(v, F32(1)), F32(0))
    return (c * F32(255) + F32(0.5)).astype(np.uint8)


def _powf():
    """libm's powf, which the C++ codec's tables are computed with, when ctypes can load it."""
    name = ctypes.util.find_library("m")
    try:
        f = ctypes.CDLL(name).powf
    except (OSError, AttributeError, TypeError):  # pragma: no cover - every glibc has it
        return lambda a, b: F32(np.float64(a) ** np.float64(b))
    f.restype = ctypes.c_float
    f.argtypes = [ctypes.c_float, ctypes.c_float]
    return lambda a, b: F32(f(float(a), float(b)))


def _srgb_to_linear(c, powf):
    c = F32(c)
    if c <= F32(0.04045):
        return c / F32(12.92)
    return powf((c + F32(0.055)) / F32(1.055), F32(2.4))


def _srgb_tables():
    powf = _powf()
    decode = np.array([_srgb_to_linear(F32(i) / F32(255), powf) for i in range(256)], F32)
    mid = np.array([_srgb_to_linear((F32(i) + F32(0.5)) / F32(255), powf) for i in range(255)], F32)
    return decode, mid


SRGB_DECODE, SRGB_MIDPOINTS = _srgb_tables()


def srgb8(linear):
    """Nearest 8-bit sRGB codes of binary32 linear values (clamped to [0, 1], NaN to 0)."""
    v = np.asarray(linear, dtype=F32)
    with np.errstate(invalid="ignore"):
        v = np.where(v > 0, np.minimum(v, F32(1)), F32(0))
    return np.searchsorted(SRGB_MIDPOINTS, v, side="right").astype(np.uint32)


def decode_rgba8(codes):
    """Linear float32 RGBA (N×4) of RGBA8 codes (sRGB RGB, linear alpha; R in the low byte)."""
    codes = np.asarray(codes, dtype=np.uint32)
    out = np.empty((len(codes), 4), F32)
    for c in range(3):
        out[:, c] = SRGB_DECODE[(codes >> np.uint32(8 * c)) & np.uint32(0xFF)]
    out[:, 3] = (codes >> np.uint32(24)).astype(F32) * (F32(1) / F32(255))
    return out


def encode_rgba8(rgba):
    """RGBA8 codes of linear float32 RGBA (N×4)."""
    rgba = np.asarray(rgba, dtype=F32)
    return (srgb8(rgba[:, 0]) | (srgb8(rgba[:, 1]) << np.uint32(8)) | (srgb8(rgba[:, 2]) << np.uint32(16))
            | (unorm8(rgba[:, 3]).astype(np.uint32) << np.uint32(24)))
