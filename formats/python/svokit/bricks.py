"""Brick samples (formats/svo.md, "Samples"): the layout of a level's distinct samples over its
nodes, bricks assembled from it, and the voxel level's bricks derived from the voxels."""

import numpy as np

from . import codecs

F32 = np.float32


def _slot(d):
    return (d[0] + 1) + 3 * (d[1] + 1) + 9 * (d[2] + 1)


def neighbours(keys, level, among=None):
    """Per node of ``keys`` (sorted Morton keys at ``level``) and offset d ∈ {−1, 0, 1}³ (column
    (dx + 1) + 3(dy + 1) + 9(dz + 1)): the index in ``among`` (sorted keys; ``keys`` when None) of
    the node at d, or −1."""
    keys = np.asarray(keys, dtype=np.uint64)
    among = keys if among is None else np.asarray(among, dtype=np.uint64)
    out = np.full((len(keys), 27), -1, np.int64)
    limit = np.uint64(8) ** np.uint64(level) if level < 22 else None
    for dz in (-1, 0, 1):
        for dy in (-1, 0, 1):
            for dx in (-1, 0, 1):
                k = codecs.morton_offset(keys, (dx, dy, dz))
                at = np.searchsorted(among, k)
                ok = at < len(among)
                if limit is not None:
                    ok &= k < limit
                at_c = np.minimum(at, max(len(among) - 1, 0))
                if len(among):
                    ok &= among[at_c] == k
                out[:, _slot((dx, dy, dz))] = np.where(ok, at_c, -1)
    return out


def _brick_positions(side):
    k = np.arange(side ** 3)
    return np.stack([k % side, k // side % side, k // (side * side)], axis=1)


class Layout:
    """Where each node's samples sit in a level's distinct samples: per node, its (s − 1)³ home
    samples in brick order, then its orphans (lattice points whose home node does not exist,
    stored by the first existing node among home − f) in brick order."""

    def __init__(self, keys, level, side):
        m = side - 1
        self.side = side
        nb = neighbours(keys, level)
        n = len(nb)
        pos = _brick_positions(side)
        self.home = np.all(pos < m, axis=1)
        self.outer = np.flatnonzero(~self.home)  # brick positions of possible orphans, in order
        self.outer_slot = np.full(side ** 3, -1)
        self.outer_slot[self.outer] = np.arange(len(self.outer))
        # Per outer position: e (its home's offset) and the boundary axes f may take.
        self.e = (pos[self.outer] == m).astype(np.int64)
        boundary = (pos[self.outer] == 0) | (pos[self.outer] == m)
        self.home_node = np.empty((n, len(self.outer)), np.int64)
        self.holder = np.full((n, len(self.outer)), -1, np.int64)  # node storing an orphan
        self.holder_f = np.zeros((n, len(self.outer)), np.int64)
        for j, e in enumerate(self.e):
            self.home_node[:, j] = nb[:, _slot(e)]
            orphan = self.home_node[:, j] < 0
            for f in range(1, 8):
                fv = np.array([f & 1, f >> 1 & 1, f >> 2 & 1])
                if np.any(fv.astype(bool) & ~boundary[j]):
                    continue
                g = nb[:, _slot(e - fv)]
                take = orphan & (self.holder[:, j] < 0) & (g >= 0)
                self.holder[take, j] = g[take]
                self.holder_f[take, j] = f
        e_bits = self.e[:, 0] + 2 * self.e[:, 1] + 4 * self.e[:, 2]
        stored = (self.holder >= 0) & (self.holder_f == e_bits[None, :])
        self.orphan_rank = np.cumsum(stored, axis=1) - 1
        counts = m ** 3 + stored.sum(axis=1)
        self.start = np.zeros(n + 1, np.int64)
        np.cumsum(counts, out=self.start[1:])
        self.samples = int(self.start[-1])

    def brick_indices(self):
        """Per node (rows) and brick sample (columns, brick order): the sample's index among the
        level's distinct samples."""
        side, m = self.side, self.side - 1
        pos = _brick_positions(side)
        n = len(self.start) - 1
        out = np.empty((n, side ** 3), np.int64)
        for k in range(side ** 3):
            kp = pos[k]
            if self.home[k]:
                out[:, k] = self.start[:-1] + (kp[0] + m * (kp[1] + m * kp[2]))
                continue
            j = self.outer_slot[k]
            e = self.e[j]
            local = kp - m * e
            home = self.home_node[:, j]
            col = np.where(home >= 0, self.start[np.maximum(home, 0)] + (local[0] + m * (local[1] + m * local[2])), -1)
            orphan = home < 0
            if orphan.any():
                g = self.holder[orphan, j]
                f = self.holder_f[orphan, j]
                fv = np.stack([f & 1, f >> 1 & 1, f >> 2 & 1], axis=1)
                kk = kp[None, :] + m * (fv - e[None, :])
                slot = self.outer_slot[kk[:, 0] + side * (kk[:, 1] + side * kk[:, 2])]
                col[orphan] = self.start[g] + m ** 3 + self.orphan_rank[g, slot]
            out[:, k] = col
        return out


def assemble(layout, opacity, color=None, normal=None):
    """Bricks (nodes × side³) of each given plane of a level's distinct samples."""
    idx = layout.brick_indices()
    return tuple(None if a is None else np.asarray(a)[idx] for a in (opacity, color, normal))


def voxel_bricks(keys, depth, side, around, colors=None, normals=None):
    """The voxel level's bricks by filter 2's level-D rule: each sample averages the m cells whose
    closed cube holds it (binary32 sums of the filled ones in z, y, x order, times 1/m), encoded.

    ``keys``: the voxels to make bricks for (sorted Morton keys, level D); ``around``: sorted keys
    of every voxel they may touch (themselves included), with ``colors`` (linear RGBA, float32, per
    voxel of ``around``, or one row for all) and ``normals`` (float32 unit vectors per voxel of
    ``around``) as given.
    Returns (opacity, color, normal), each nodes × side³ (color and normal None when not given).
    """
    m = side - 1
    nb = neighbours(keys, depth, around)
    n = len(nb)
    s3 = side ** 3
    opacity = np.zeros((n, s3), np.uint8)
    color = None if colors is None else np.zeros((n, s3), np.uint32)
    normal = None if normals is None else np.zeros((n, s3), np.uint16)
    pos = _brick_positions(side)

    for k in range(s3):
        # Per axis, the cells whose closed extent holds the sample: at a cell boundary, the cells
        # before and after it; inside (side 3's midpoints), the voxel's own.
        ranges = []
        for a in range(3):
            if pos[k, a] == 0:
                ranges.append((-1, 0))
            elif pos[k, a] == m:
                ranges.append((0, 1))
            else:
                ranges.append((0,))
        cells = [(dx, dy, dz) for dz in ranges[2] for dy in ranges[1] for dx in ranges[0]]
        inv = F32(1) / F32(len(cells))
        o = np.zeros(n, F32)
        c = None if colors is None else np.zeros((n, 4), F32)
        v = None if normals is None else np.zeros((n, 3), F32)
        for offset in cells:
            at = nb[:, _slot(offset)]
            filled = at >= 0
            o = o + filled.astype(F32)
            if c is not None:
                row = colors[0][None, :] if len(colors) == 1 else colors[np.maximum(at, 0)]
                c = c + np.where(filled[:, None], row, F32(0))
            if v is not None:
                v = v + np.where(filled[:, None], normals[np.maximum(at, 0)], F32(0))
        o = o * inv
        opacity[:, k] = codecs.unorm8(o)
        live = opacity[:, k] != 0
        with np.errstate(invalid="ignore", divide="ignore"):
            rinv = F32(1) / np.where(live, o, F32(1))
        if c is not None:
            c = c * inv
            color[:, k] = np.where(live, codecs.encode_rgba8(c * rinv[:, None]), 0)
        if v is not None:
            v = v * inv  # premultiplied: its direction is the normal's
            length = np.sqrt((v[:, 0] * v[:, 0] + v[:, 1] * v[:, 1]) + v[:, 2] * v[:, 2])
            ok = length > F32(1e-12)
            safe = np.where(ok, length, F32(1))
            unit = np.where(ok[:, None], v / safe[:, None], F32(0))
            normal[:, k] = np.where(live, codecs.oct_encode(unit, 8), 0)
    return opacity, color, normal
