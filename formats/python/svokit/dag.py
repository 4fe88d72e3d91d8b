"""Readers of the sparse voxel DAG files svo-export writes (formats/dag.md): HashDAG's basic_dag
(``x.dag.bin`` and ``x.uncompressed_colors.bin``) and SymVox's ``.svdag``, expanded to voxels as
those renderers walk them. Written from the layouts' own descriptions, independently of svokit's
C++ writers.

Both number a node's children ``4x + 2y + z``; the voxels come out in that depth-first order (the
order of HashDAG's colours) as integer (x, y, z) rows.
"""

import struct

import numpy as np

from .errors import FormatError

# Child (or voxel of a 2³ block) c = 4x + 2y + z: its (x, y, z) offset.
_OCTANT = np.array([[(c >> 2) & 1, (c >> 1) & 1, c & 1] for c in range(8)], np.int64)
# Per child c and mask m, the children of m below c and above c: where c's pointer is when the
# pointers are stored ascending (HashDAG) or descending (SymVox).
_BELOW = np.array([[bin(m & ((1 << c) - 1)).count("1") for m in range(256)] for c in range(8)])
_ABOVE = np.array([[bin(m >> (c + 1)).count("1") for m in range(256)] for c in range(8)])


class HashDag:
    """A ``.dag.bin``: the cube ``bmin`` .. ``bmax``, ``levels`` (grid 2^levels a side) and the node
    array ``words`` (uint32, root at 0)."""

    def __init__(self, bmin, bmax, levels, words):
        self.bmin, self.bmax, self.levels, self.words = bmin, bmax, levels, words


class HashDagColors:
    """An ``uncompressed_colors.bin``: ``top_levels``, ``enclosed`` (voxel counts of the nodes above
    ``top_levels``) and ``rgba`` (uint8 rows R, G, B, A in depth-first voxel order)."""

    def __init__(self, top_levels, enclosed, rgba):
        self.top_levels, self.enclosed, self.rgba = top_levels, enclosed, rgba


class Svdag:
    """A ``.svdag``: the box ``bmin`` .. ``bmax``, the root cube's ``root_side``, ``levels``, the
    header's ``nodes`` and ``first_leaf`` and the node array ``words`` (root at 0)."""

    def __init__(self, bmin, bmax, root_side, levels, nodes, first_leaf, words):
        self.bmin, self.bmax, self.root_side, self.levels = bmin, bmax, root_side, levels
        self.nodes, self.first_leaf, self.words = nodes, first_leaf, words


def _read(path):
    with open(path, "rb") as f:
        return f.read()


def read_hashdag(path):
    data = _read(path)
    if len(data) < 60:
        raise FormatError(f"{path}: {len(data)} bytes, shorter than a .dag.bin header")
    bmin = struct.unpack_from("<3d", data, 0)
    bmax = struct.unpack_from("<3d", data, 24)
    (levels,) = struct.unpack_from("<I", data, 48)
    (n,) = struct.unpack_from("<Q", data, 52)
    if not 3 <= levels <= 21 or len(data) != 60 + 4 * n:
        raise FormatError(f"{path}: {levels} levels and {n} words in {len(data)} bytes")
    return HashDag(bmin, bmax, levels, np.frombuffer(data, "<u4", n, 60))


def read_hashdag_colors(path):
    data = _read(path)
    (top_levels,) = struct.unpack_from("<I", data, 0)
    (e,) = struct.unpack_from("<Q", data, 4)
    enclosed = np.frombuffer(data, "<u8", e, 12)
    (c,) = struct.unpack_from("<Q", data, 12 + 8 * e)
    if len(data) != 20 + 8 * e + 4 * c:
        raise FormatError(f"{path}: {e} counts and {c} colours in {len(data)} bytes")
    rgba = np.frombuffer(data, np.uint8, 4 * c, 20 + 8 * e).reshape(-1, 4)
    return HashDagColors(top_levels, enclosed, rgba)


def read_svdag(path):
    data = _read(path)
    if len(data) < 44:
        raise FormatError(f"{path}: {len(data)} bytes, shorter than a .svdag header")
    bmin = struct.unpack_from("<3f", data, 0)
    bmax = struct.unpack_from("<3f", data, 12)
    (root_side,) = struct.unpack_from("<f", data, 24)
    levels, nodes, first_leaf, count = struct.unpack_from("<4I", data, 28)
    if len(data) != 44 + 4 * count:
        raise FormatError(f"{path}: {count} words in {len(data)} bytes")
    words = np.frombuffer(data, "<u4", count, 44)
    return Svdag(bmin, bmax, root_side, levels, nodes, first_leaf, words)


def _children(words, nodes, xyz, descending):
    """The children of ``nodes`` (word indices, in depth-first order, at ``xyz``) in depth-first
    order: each node's in ascending child index, its pointers stored ascending or descending."""
    masks = (words[nodes] & 0xFF).astype(np.int64)
    rows, kids, cells = [], [], []
    for c in range(8):
        has = np.nonzero((masks >> c) & 1)[0]
        slot = 1 + (_ABOVE if descending else _BELOW)[c][masks[has]]
        rows.append(has * 8 + c)
        kids.append(words[nodes[has] + slot].astype(np.int64))
        cells.append(2 * xyz[has] + _OCTANT[c])
    order = np.argsort(np.concatenate(rows), kind="stable")
    return np.concatenate(kids)[order], np.concatenate(cells)[order], np.concatenate(rows)[order] // 8


def _expand(words, levels, leaf_level, descending, leaf_voxels):
    """Voxels (x, y, z rows, depth-first) and, per level, each visited node's word index and the
    index of its parent among the level above's."""
    nodes = np.zeros(1, np.int64)
    xyz = np.zeros((1, 3), np.int64)
    visits = [(nodes, None)]
    for _ in range(leaf_level):
        nodes, xyz, parent = _children(words, nodes, xyz, descending)
        visits.append((nodes, parent))
    return leaf_voxels(words, nodes, xyz), visits


def _hashdag_leaf_voxels(words, nodes, xyz):
    bits = words[nodes].astype(np.uint64) | (words[nodes + 1].astype(np.uint64) << np.uint64(32))
    out_rows, out_cells = [], []
    for b in range(64):
        has = np.nonzero((bits >> np.uint64(b)) & np.uint64(1))[0]
        out_rows.append(has * 64 + b)
        out_cells.append(4 * xyz[has] + 2 * _OCTANT[b >> 3] + _OCTANT[b & 7])
    order = np.argsort(np.concatenate(out_rows), kind="stable")
    return np.concatenate(out_cells)[order]


def hashdag_voxels(dag, with_visits=False):
    """The voxels of a HashDAG file as (x, y, z) rows in its depth-first (colour) order."""
    voxels, visits = _expand(dag.words, dag.levels, dag.levels - 2, False, _hashdag_leaf_voxels)
    return (voxels, visits) if with_visits else voxels


def _svdag_leaf_voxels(words, nodes, xyz):
    masks = (words[nodes] & 0xFF).astype(np.int64)
    out_rows, out_cells = [], []
    for c in range(8):
        has = np.nonzero((masks >> c) & 1)[0]
        out_rows.append(has * 8 + c)
        out_cells.append(2 * xyz[has] + _OCTANT[c])
    order = np.argsort(np.concatenate(out_rows), kind="stable")
    return np.concatenate(out_cells)[order]


def svdag_voxels(dag):
    """The voxels of a SymVox file as (x, y, z) rows in depth-first order."""
    voxels, _ = _expand(dag.words, dag.levels, dag.levels - 1, True, _svdag_leaf_voxels)
    return voxels


DAG_COLORS_MAGIC = b"\x89DGC\r\n\x1a\n"


def read_packed_colors(path):
    """svokit's packed colours (``x.dagcolors``): uint8 rows R, G, B, A (sRGB colour, linear
    alpha) in the DAG's depth-first order, and the level they are of."""
    import zstandard

    from .container import Container

    c = Container(path, DAG_COLORS_MAGIC, 1)
    try:
        head = c.payload("HEAD")
        if len(head) != 20:
            c.fail(f"HEAD of {len(head)} bytes")
        count, block, level, _ = struct.unpack_from("<QIII", head, 0)
        table = np.frombuffer(c.payload("BLKS"), np.dtype([("offset", "<u8"), ("size", "<u4"),
                                                          ("count", "<u4")]))
        data = c.payload("DATA")
        if int(table["count"].sum()) != count or np.any(table["count"][:-1] != block):
            c.fail(f"blocks of {list(table['count'][:3])}... colours for {count}")
        out = np.empty((count, 4), np.uint8)
        at = 0
        for offset, size, n in table:
            planes = zstandard.ZstdDecompressor().decompress(bytes(data[offset:offset + size]),
                                                            max_output_size=4 * int(n))
            if len(planes) != 4 * n:
                c.fail(f"a block of {len(planes)} bytes for {n} colours")
            deltas = np.frombuffer(planes, np.uint8).reshape(4, n)
            out[at:at + n] = np.cumsum(deltas, axis=1, dtype=np.uint64).astype(np.uint8).T
            at += n
        return out, level
    finally:
        c.close()


class Ssvdag:
    """A ``.ssvdag`` (SymVox's symmetry-aware DAG): the box, ``root_side``, ``levels``, the header's
    ``nodes``, the u16 ``inner`` nodes, the 4³ ``leaves`` (uint64, bit 16x + 4y + z) and each inner
    level's start in ``inner``."""

    def __init__(self, bmin, bmax, root_side, levels, nodes, inner, leaves, level_offsets):
        self.bmin, self.bmax, self.root_side, self.levels = bmin, bmax, root_side, levels
        self.nodes, self.inner, self.leaves, self.level_offsets = nodes, inner, leaves, level_offsets


def read_ssvdag(path):
    data = _read(path)
    if len(data) < 40:
        raise FormatError(f"{path}: {len(data)} bytes, shorter than a .ssvdag header")
    bmin = struct.unpack_from("<3f", data, 0)
    bmax = struct.unpack_from("<3f", data, 12)
    (root_side,) = struct.unpack_from("<f", data, 24)
    levels, nodes, n16 = struct.unpack_from("<3I", data, 28)
    at = 40
    inner = np.frombuffer(data, "<u2", n16, at)
    at += 2 * n16
    (nb,) = struct.unpack_from("<I", data, at)
    leaves = np.frombuffer(data[at + 4:at + 4 + nb], "<u8")
    at += 4 + nb
    (nl,) = struct.unpack_from("<I", data, at)
    offsets = np.frombuffer(data, "<u4", nl, at + 4)
    if nb % 8 or nl != levels - 2 or len(data) != at + 4 + 4 * nl:
        raise FormatError(f"{path}: {n16} inner words, {nb} leaf bytes, {nl} levels in {len(data)} bytes")
    return Ssvdag(bmin, bmax, root_side, levels, nodes, inner, leaves, offsets)


# u16 words of a pointer by its 2-bit code: none, 16-bit, 32-bit (twice).
_POINTER_SIZE = np.array([0, 1, 2, 2])


def ssvdag_voxels(dag):
    """The voxels of a SymVox symmetry-aware file as (x, y, z) rows, in no particular order."""
    inner = dag.inner.astype(np.int64)
    nodes = np.zeros(1, np.int64)  # u16 index of each node of the level
    xyz = np.zeros((1, 3), np.int64)
    mirror = np.zeros(1, np.int64)  # accumulated reflection, 4mx + 2my + mz
    for level in range(dag.levels - 2):
        header = inner[nodes]
        codes = np.stack([(header >> (2 * c)) & 3 for c in range(8)], 1)
        sizes = _POINTER_SIZE[codes]
        from_child = np.cumsum(sizes[:, ::-1], axis=1)[:, ::-1]  # words of children c … 7
        kids, cells, mirrors = [], [], []
        for c in range(8):  # world child c is stored child c ^ M
            stored = c ^ mirror
            code = codes[np.arange(len(nodes)), stored]
            has = np.nonzero(code)[0]
            s = stored[has]
            before = from_child[has, s] - sizes[has, s]
            first = inner[nodes[has] + 1 + before]
            wide = code[has] >= 2
            second = np.where(wide, inner[np.minimum(nodes[has] + 2 + before, len(inner) - 1)], 0)
            address = np.where(wide, ((first & 0x1FFF) << 16) | second | ((code[has] & 1) << 29), first & 0x1FFF)
            field = (first >> 13) & 7  # x, y, z in bits 0, 1, 2
            m = ((field & 1) << 2) | (field & 2) | ((field >> 2) & 1)
            if level + 1 < dag.levels - 2:
                address = address + int(dag.level_offsets[level + 1])
            kids.append(address)
            cells.append(2 * xyz[has] + _OCTANT[c])
            mirrors.append(mirror[has] ^ m)
        nodes, xyz, mirror = np.concatenate(kids), np.concatenate(cells), np.concatenate(mirrors)
    bits = dag.leaves[nodes]
    out = []
    for b in range(64):
        X, Y, Z = b >> 4, (b >> 2) & 3, b & 3
        # World voxel (X, Y, Z) of a leaf seen through M is its stored voxel reflected by M.
        sx = np.where(mirror & 4, 3 - X, X)
        sy = np.where(mirror & 2, 3 - Y, Y)
        sz = np.where(mirror & 1, 3 - Z, Z)
        on = (bits >> (16 * sx + 4 * sy + sz).astype(np.uint64)) & np.uint64(1)
        has = np.nonzero(on)[0]
        out.append(4 * xyz[has] + np.array([X, Y, Z]))
    return np.concatenate(out)
