"""The .svo reader (formats/svo.md, versions 2 and 3): the header, META, the top chunk and the
pages, decoded into numpy arrays; the octree's levels, voxels and bricks assembled from them."""

import json
import struct
from collections import namedtuple

import numpy as np
import zstandard

from . import bricks as brick_ops
from . import codecs
from .container import Container, crc32c
from .errors import FormatError

MAGIC = b"\x89SVO\r\n\x1a\n"
NEWEST_VERSION = 3

FLAG_COLOR, FLAG_NORMAL, FLAG_CONTOURS, FLAG_SHARED_COLOR, FLAG_SOLID = 1, 2, 4, 8, 16
FLAG_PRUNED = 32
_KNOWN_FLAGS = 63
_STREAM_LIMIT, _CHUNK_LIMIT = 1 << 30, 4 << 30

# Stream kinds of a chunk.
MASKS, CONTOUR_BITS, THICKNESS, POSITION, CONTOUR_NORMALS = 1, 2, 3, 4, 5
OPACITY, COLORS, NORMALS, VOXEL_COLORS, VOXEL_NORMALS = 6, 7, 8, 9, 10
HALO_KEYS, HALO_COLORS, HALO_NORMALS, FULL_MASKS = 11, 12, 13, 14

Grid = namedtuple("Grid", "origin voxel_size dims mode")
Grid.__doc__ = """The voxel grid: world ``origin`` of voxel (0, 0, 0)'s least corner, ``voxel_size``,
``dims`` (voxels per axis) and ``mode`` (0 conservative, 1 thin)."""

PAGE_TABLE = np.dtype([("key", "<u8"), ("offset", "<u8"), ("stored_bytes", "<u4"),
                       ("crc32c", "<u4"), ("voxels", "<u8")])


class ChunkLevel:
    """One level of a chunk: ``keys`` (Morton at ``level``, ascending), ``masks`` and
    ``full_masks`` (uint8 per node; empty at the voxel level), ``contours`` (uint32 word per node,
    0 for none) and the level's distinct samples (``opacity``, ``color``, ``normal``), in layout
    order; ``layout`` places them in the nodes' bricks."""

    def __init__(self, level, keys):
        self.level = level
        self.keys = keys
        self.masks = np.zeros(0, np.uint8)
        self.full_masks = np.zeros(0, np.uint8)
        self.contours = np.zeros(len(keys), np.uint32)
        self.opacity = np.zeros(0, np.uint8)
        self.color = np.zeros(0, np.uint32)
        self.normal = np.zeros(0, np.uint16)
        self.layout = None


class Chunk:
    """A decoded chunk: the top chunk or a page. ``levels`` from ``root_level`` on; a page's voxel
    attributes (``voxel_colors`` binary16 RGBA bits, ``voxel_normals`` u16 octahedral code pairs)
    and its halo (``halo_keys``, ``halo_colors``, ``halo_normals``)."""

    def __init__(self, root_level, root_key):
        self.root_level = root_level
        self.root_key = root_key
        self.levels = []
        empty2 = np.zeros((0, 2), np.uint16)
        self.voxel_colors = np.zeros((0, 4), np.uint16)
        self.voxel_normals = empty2
        self.halo_keys = np.zeros(0, np.uint64)
        self.halo_colors = np.zeros((0, 4), np.uint16)
        self.halo_normals = empty2

    def level(self, level):
        return self.levels[level - self.root_level]


class Voxels:
    """Voxels with their attributes, in key order: ``keys`` (Morton), ``coords`` (N×3 integer grid
    coordinates), ``colors`` (N×4 linear RGBA, float32, straight alpha) or None, ``normals``
    (N×3 unit float32, zero where none) or None, ``ao`` (N float32 in [0, 1]) or None."""

    def __init__(self, keys, colors, normals, ao):
        self.keys = keys
        self.coords = codecs.morton_decode(keys)
        self.colors, self.normals, self.ao = colors, normals, ao

    def __len__(self):
        return len(self.keys)


class Level:
    """A level of the whole octree: ``keys``, ``masks``, ``full_masks`` (empty at the voxel level),
    ``contours`` (word per node, 0 for none), bricks ``opacity`` (nodes × side³ uint8),
    ``color`` (RGBA8) and ``normal`` (8-bit octahedral codes) where the file has them, ``ao``
    (uint8 per node) when baked."""

    def __init__(self, level):
        self.level = level


class SvoFile:
    """An open .svo. The frame, HEAD, PTAB, META and the top chunk are checked on opening; a page
    is checked when it is read."""

    def __init__(self, path):
        self._c = Container(path, MAGIC, NEWEST_VERSION, lazy=("PAGE",))
        try:
            self._open()
        except FormatError:
            self._c.close()
            raise

    def _open(self):
        c = self._c
        self.path = c.path
        self.version = c.version
        if c.version < 2:
            c.fail("version 1 has no pages; read it with svokit's C++ readers (ReadSvo)")
        if c.flags != 0:
            c.fail(f"container flags {c.flags} (must be 0)")
        self.grid = _read_grid(c)
        self._read_head()
        self._read_page_table()
        meta = c.payload("META", required=False)
        try:
            self.meta = None if meta is None else json.loads(bytes(meta).decode("utf-8"))
        except (UnicodeDecodeError, ValueError):
            c.fail("META is not UTF-8 JSON")
        self._dctx = zstandard.ZstdDecompressor()
        self._top = None
        if self.page_level > 0:
            self._top = self._decode_chunk(c.payload("TOPL"), 0, 0, "the top chunk", is_page=False)
            if not np.array_equal(self._top.page_keys, self.page_table["key"]):
                c.fail("the top chunk's pages differ from the page table")
        self._ao = None

    # --- the header -------------------------------------------------------------------------

    def _read_head(self):
        c = self._c
        head = c.payload("HEAD")
        if len(head) < 40:
            c.fail(f"HEAD of {len(head)} bytes")
        depth, side, flags, page_level, pages = struct.unpack_from("<IIIIQ", head, 0)
        shared = np.frombuffer(head[24:32], dtype="<u2").copy()
        level_count, codec = struct.unpack_from("<II", head, 32)
        if level_count != depth + 1 or len(head) != 40 + 24 * level_count:
            c.fail(f"HEAD of {len(head)} bytes for depth {depth}")
        if depth != _grid_depth(self.grid.dims):
            c.fail(f"depth {depth} does not fit a grid of {list(self.grid.dims)} voxels")
        if side not in (0, 2, 3):
            c.fail(f"brick side {side}")
        if flags & ~_KNOWN_FLAGS:
            c.fail(f"unknown HEAD flags {flags:#x}")
        if flags & FLAG_SHARED_COLOR and not flags & FLAG_COLOR:
            c.fail("a shared colour without colours")
        if not (page_level < depth or depth == 0):
            c.fail(f"page level {page_level} not below depth {depth}")
        counts = np.frombuffer(head[40:], dtype="<u8").reshape(level_count, 3)
        for level, (nodes, contours, _) in enumerate(counts):
            # Below the page level a pruned octree's level may be empty: its leaves lie above.
            least = 0 if flags & FLAG_PRUNED and level > page_level else 1
            if not least <= nodes <= 8 ** level or contours > nodes:
                c.fail(f"level {level}: {nodes} nodes, {contours} contours")
            if contours and not flags & FLAG_CONTOURS:
                c.fail(f"level {level} has contours without the contour flag")
        if pages != counts[page_level, 0]:
            c.fail(f"{pages} pages but {counts[page_level, 0]} nodes at the page level")
        self.depth, self.brick_side, self.flags = depth, side, flags
        self.page_level, self.page_count, self.codec = page_level, pages, codec
        self.shared_color = shared
        self.level_nodes = counts[:, 0].astype(np.int64)
        self.level_contours = counts[:, 1].astype(np.int64)
        self.level_samples = counts[:, 2].astype(np.int64)

    def _read_page_table(self):
        c = self._c
        table = c.payload("PTAB")
        if len(table) != 32 * self.page_count:
            c.fail(f"PTAB of {len(table)} bytes for {self.page_count} pages")
        t = np.frombuffer(table, dtype=PAGE_TABLE).copy()
        page = c.sections["PAGE"]
        keys = t["key"]
        if len(t) and (np.any(keys[1:] <= keys[:-1]) or int(keys[-1]) >= 8 ** self.page_level):
            c.fail("page keys not ascending below 8^P")
        ends = np.cumsum(t["stored_bytes"].astype(np.uint64))
        starts = np.concatenate([[0], ends[:-1]]).astype(np.uint64)
        if not np.array_equal(t["offset"], starts) or (len(t) and int(ends[-1]) != page.size):
            c.fail("pages do not fill PAGE back to back")
        self.page_table = t

    has_color = property(lambda self: bool(self.flags & FLAG_COLOR))
    has_normal = property(lambda self: bool(self.flags & FLAG_NORMAL))
    has_contours = property(lambda self: bool(self.flags & FLAG_CONTOURS))
    is_solid = property(lambda self: bool(self.flags & FLAG_SOLID))
    is_pruned = property(lambda self: bool(self.flags & FLAG_PRUNED))
    has_ao = property(lambda self: "AOCC" in self._c.sections)

    def close(self):
        self._c.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    # --- chunks -----------------------------------------------------------------------------

    def top(self):
        """The top chunk (levels 0 .. P − 1), or None when the page level is 0."""
        return self._top

    def page(self, i, samples=True, contours=True):
        """Page ``i`` decoded, its checksum and every count checked; its brick samples and
        contours left out (and unchecked) when not asked for."""
        if not 0 <= i < self.page_count:
            raise IndexError(f"page {i} of {self.page_count}")
        e = self.page_table[i]
        base = self._c.sections["PAGE"].offset + int(e["offset"])
        data = self._c.data[base:base + int(e["stored_bytes"])]
        if crc32c(data) != int(e["crc32c"]):
            self._c.fail(f"page {i}: checksum mismatch")
        return self._decode_chunk(data, self.page_level, int(e["key"]), f"page {i}", True, samples, contours)

    def pages_in(self, lo, hi):
        """Indices of the pages whose cube meets the world box [lo, hi]."""
        g = self.grid
        size = float(g.voxel_size) * (1 << (self.depth - self.page_level))
        c = codecs.morton_decode(self.page_table["key"]).astype(np.float64)
        least = np.asarray(g.origin) + c * size
        hit = np.all((least <= np.asarray(hi)) & (least + size >= np.asarray(lo)), axis=1)
        return np.flatnonzero(hit)

    def _decode_chunk(self, data, root_level, root_key, name, is_page, samples=True, contours=True):
        def fail(problem):
            self._c.fail(f"{name}: {problem}")

        streams = self._streams(data, fail)
        last_held = self.depth if is_page else self.page_level - 1  # contours held to here
        mask_levels = (self.depth - root_level) if is_page else self.page_level
        chunk = Chunk(root_level, root_key)
        masks = streams.pop(MASKS, b"")
        full = streams.pop(FULL_MASKS, None)
        if full is not None and not self.is_solid:
            fail("full masks in a file that is not a solid")
        keys = np.array([root_key], np.uint64)
        used = 0
        for k in range(mask_levels + 1):
            level = root_level + k
            lv = ChunkLevel(level, keys)
            chunk.levels.append(lv)
            if k == mask_levels:
                break
            n = len(keys)
            if used + n > len(masks):
                fail("masks stream shorter than its nodes")
            m = np.frombuffer(masks, np.uint8, n, used)
            lv.masks = m
            lv.full_masks = np.zeros(n, np.uint8) if full is None else np.frombuffer(full, np.uint8, n, used)
            if full is not None and len(full) != len(masks):
                fail("full masks stream differs in size from the masks")
            # A node without children: a pruned leaf, or a solid's holding full leaves.
            childless = (m == 0) & (lv.full_masks == 0)
            if np.any(m & lv.full_masks):
                fail(f"level {level}: a child both full and not")
            if np.any(childless) and not self.is_pruned:
                fail(f"level {level}: a node without children")
            used += n
            bits = np.unpackbits(m[:, None], axis=1, bitorder="little")
            rows, cols = np.nonzero(bits)
            keys = (keys[rows] << np.uint64(3)) | cols.astype(np.uint64)
        if used != len(masks):
            fail("masks stream longer than its nodes")
        if not is_page:
            chunk.page_keys = chunk.levels.pop().keys  # level P: the pages' roots
        skipped = ((CONTOUR_BITS, THICKNESS, POSITION, CONTOUR_NORMALS) if not contours else ()) + \
            ((OPACITY, COLORS, NORMALS) if not samples else ())
        for kind in skipped:
            streams.pop(kind, None)
        if contours:
            self._decode_contours(chunk, streams, fail, last_held)
        if self.brick_side and samples:
            self._decode_samples(chunk, streams, fail)
        if is_page:
            self._decode_voxels(chunk, streams, fail)
        if streams:
            fail(f"stream {min(streams)} has no place here")
        return chunk

    def _streams(self, data, fail):
        if len(data) < 1:
            fail("empty chunk")
        count = data[0]
        pos, entries, total = 1, [], 0
        previous = 0
        for _ in range(count):
            if pos + 2 > len(data):
                fail("stream directory runs past the chunk")
            kind, codec = data[pos], data[pos + 1]
            pos += 2
            decoded = codecs.varint(data, pos)
            stored = decoded and codecs.varint(data, decoded[1])
            if not decoded or not stored:
                fail("malformed stream directory")
            (decoded, _), (stored, pos) = decoded, stored
            if not previous < kind <= FULL_MASKS:
                fail(f"stream kind {kind} out of order or unknown")
            if codec > 1:
                fail(f"stream {kind}: unknown codec {codec}")
            if decoded > _STREAM_LIMIT or decoded == 0 or (codec == 0 and stored != decoded):
                fail(f"stream {kind}: sizes {decoded}/{stored}")
            total += decoded
            previous = kind
            entries.append((kind, codec, decoded, stored))
        if total > _CHUNK_LIMIT:
            fail("streams larger than 4 GiB")
        out = {}
        for kind, codec, decoded, stored in entries:
            raw = data[pos:pos + stored]
            if len(raw) != stored:
                fail(f"stream {kind} runs past the chunk")
            pos += stored
            if codec == 1:
                try:
                    raw = self._dctx.decompress(bytes(raw), max_output_size=decoded)
                except zstandard.ZstdError as e:
                    fail(f"stream {kind}: {e}")
                if len(raw) != decoded:
                    fail(f"stream {kind}: {len(raw)} bytes decoded, {decoded} declared")
            out[kind] = bytes(raw)  # a copy: no array keeps the file's mapping
        if pos != len(data):
            fail("bytes after the last stream")
        return out

    def _decode_contours(self, chunk, streams, fail, last_held):
        bits_raw = streams.pop(CONTOUR_BITS, None)
        fields = [streams.pop(k, None) for k in (THICKNESS, POSITION, CONTOUR_NORMALS)]
        held = [lv for lv in chunk.levels if lv.level <= last_held]
        if not self.has_contours:
            if bits_raw is not None or any(f is not None for f in fields):
                fail("contour streams without the contour flag")
            return
        expect = sum((len(lv.keys) + 7) // 8 for lv in held)
        if bits_raw is None or len(bits_raw) != expect:
            fail("contour bits stream of the wrong size")
        used, has = 0, []
        for lv in held:
            n = len(lv.keys)
            b = np.frombuffer(bits_raw, np.uint8, (n + 7) // 8, used)
            used += (n + 7) // 8
            flags = np.unpackbits(b, bitorder="little")
            if np.any(flags[n:]):
                fail(f"level {lv.level}: contour bits past the last node")
            has.append(flags[:n].astype(bool))
        total = int(sum(h.sum() for h in has))
        if total == 0:
            if any(f is not None for f in fields):
                fail("contour fields without contours")
            return
        if any(f is None for f in fields) or len(fields[0]) != total or len(fields[1]) != total \
                or len(fields[2]) != 3 * total:
            fail("contour streams of the wrong size")
        t = np.frombuffer(fields[0], np.uint8).astype(np.uint32)
        p = np.frombuffer(fields[1], np.uint8).astype(np.uint32)
        nrm = np.cumsum(np.frombuffer(fields[2], np.uint8).reshape(3, total), axis=1, dtype=np.uint32) & 63
        if np.any(t > 127) or np.any(p > 127):
            fail("contour fields out of range")
        words = (t << 25) | (p << 18) | (nrm[0] << 12) | (nrm[1] << 6) | nrm[2]
        if np.any((nrm[0] == 0) & (nrm[1] == 0) & (nrm[2] == 0)):
            fail("a contour with a zero normal")
        at = 0
        for lv, h in zip(held, has):
            count = int(h.sum())
            lv.contours = np.zeros(len(lv.keys), np.uint32)
            lv.contours[h] = words[at:at + count]
            at += count

    def _decode_samples(self, chunk, streams, fail):
        opacity = streams.pop(OPACITY, b"")
        colors = streams.pop(COLORS, None)
        normals = streams.pop(NORMALS, None)
        sampled = [lv for lv in chunk.levels if lv.level < self.depth]
        at = 0
        for lv in sampled:
            lv.layout = brick_ops.Layout(lv.keys, lv.level, self.brick_side)
            n = lv.layout.samples
            if at + n > len(opacity):
                fail("opacity stream shorter than the layout's samples")
            lv.opacity = np.frombuffer(opacity, np.uint8, n, at)
            at += n
        if at != len(opacity):
            fail("opacity stream longer than the layout's samples")
        live = np.frombuffer(opacity, np.uint8) != 0
        count = int(live.sum())
        want_color = self.has_color and count
        want_normal = self.has_normal and count
        if (colors is not None) != bool(want_color) or (normals is not None) != bool(want_normal):
            fail("sample colour or normal stream present where it must not be, or absent")
        all_color = np.zeros(len(live), np.uint32)
        all_normal = np.zeros(len(live), np.uint16)
        if want_color:
            if len(colors) != 4 * count:
                fail("colour stream of the wrong size")
            planes = codecs.undelta_planes(colors, 4, count, 1).astype(np.uint32)
            all_color[live] = planes[:, 0] | planes[:, 1] << 8 | planes[:, 2] << 16 | planes[:, 3] << 24
        if want_normal:
            if len(normals) != 2 * count:
                fail("normal stream of the wrong size")
            planes = codecs.undelta_planes(normals, 2, count, 1).astype(np.uint16)
            all_normal[live] = planes[:, 0] | planes[:, 1] << 8
        at = 0
        for lv in sampled:
            n = lv.layout.samples
            lv.color = all_color[at:at + n] if self.has_color else np.zeros(0, np.uint32)
            lv.normal = all_normal[at:at + n] if self.has_normal else np.zeros(0, np.uint16)
            at += n

    def _decode_voxels(self, chunk, streams, fail):
        colors, normals = self._attributes(streams, VOXEL_COLORS, VOXEL_NORMALS,
                                           len(chunk.levels[-1].keys), "voxel", fail)
        chunk.voxel_colors, chunk.voxel_normals = colors, normals
        halo = streams.pop(HALO_KEYS, None)
        if halo is None:
            if HALO_COLORS in streams or HALO_NORMALS in streams:
                fail("halo attributes without halo keys")
            return
        count = codecs.varint(halo, 0)
        if count is None:
            fail("malformed halo keys")
        count, pos = count
        gaps = codecs.varints(bytes(halo[pos:]), count)
        if gaps is None or pos + gaps[1] != len(halo):
            fail("malformed halo keys")
        keys = codecs.gap_keys(gaps[0])
        side = 1 << (self.depth - self.page_level)
        lo = codecs.morton_decode([chunk.root_key])[0] * side
        xyz = codecs.morton_decode(keys)
        inside = np.all((xyz >= lo) & (xyz < lo + side), axis=1)
        near = np.all((xyz >= lo - 1) & (xyz <= lo + side), axis=1)
        if self.is_pruned and np.any(inside):
            # In a pruned octree a halo voxel may lie under one of the page's pruned leaves.
            under = np.zeros(len(keys), bool)
            for lv in chunk.levels[:-1]:
                leaves = lv.keys[(lv.masks == 0) & (lv.full_masks == 0)]
                shift = np.uint64(3 * (self.depth - lv.level))
                under |= np.isin(keys >> shift, leaves)
            inside &= ~under
        if np.any(inside) or not np.all(near):
            fail("halo keys inside the page or more than a voxel from it")
        chunk.halo_keys = keys
        chunk.halo_colors, chunk.halo_normals = self._attributes(streams, HALO_COLORS, HALO_NORMALS,
                                                                 count, "halo", fail)

    def _attributes(self, streams, color_kind, normal_kind, count, what, fail):
        """Binary16 RGBA bits (count×4) and octahedral code pairs (count×2) of voxels, from their
        lane-delta streams; empty where the file has none."""
        color = streams.pop(color_kind, None)
        normal = streams.pop(normal_kind, None)
        want_color = self.has_color and not self.flags & FLAG_SHARED_COLOR and count > 0
        if (color is not None) != want_color or (normal is not None) != (self.has_normal and count > 0):
            fail(f"{what} colour or normal stream present where it must not be, or absent")
        out = []
        for raw, lanes, name in ((color, 4, "colour"), (normal, 2, "normal")):
            if raw is None:
                out.append(np.zeros((0, lanes), np.uint16))
                continue
            if len(raw) != 2 * lanes * count:
                fail(f"{what} {name} stream of the wrong size")
            out.append(codecs.undelta_planes(raw, lanes, count, 2))
        return out

    # --- the octree -------------------------------------------------------------------------

    def chunks(self, level=None, samples=True):
        """The chunks holding ``level`` (every chunk when None), in key order."""
        if self._top is not None and (level is None or level < self.page_level):
            yield self._top
        if level is None or level >= self.page_level:
            for i in range(self.page_count):
                yield self.page(i, samples=samples)

    def voxel_bricks(self, chunk):
        """A page's voxel bricks (opacity, color, normal; each voxels × side³, color and normal
        None where the file has none), derived from its voxels and halo by filter 2's level D."""
        if not self.brick_side:
            return None, None, None
        keys = chunk.levels[-1].keys
        order = np.argsort(np.concatenate([keys, chunk.halo_keys]), kind="stable")
        neighbours = np.concatenate([keys, chunk.halo_keys])[order]
        colors = normals = None
        if self.has_color:
            if self.flags & FLAG_SHARED_COLOR:
                colors = self.shared_color.view(np.float16).astype(np.float32)[None, :]
            else:
                colors = np.concatenate([chunk.voxel_colors, chunk.halo_colors]).view(np.float16)
                colors = colors.astype(np.float32)[order]
        if self.has_normal:
            codes = np.concatenate([chunk.voxel_normals, chunk.halo_normals]).astype(np.uint32)
            normals = codecs.oct_decode(codes[:, 0] | codes[:, 1] << 16, 16)[order]
        return brick_ops.voxel_bricks(keys, self.depth, self.brick_side, neighbours, colors, normals)

    def level(self, level, bricks=True):
        """Level ``level`` of the whole octree (every chunk holding it read)."""
        if not 0 <= level <= self.depth:
            raise IndexError(f"level {level} of an octree of depth {self.depth}")
        parts = []
        for chunk in self.chunks(level, samples=bricks):
            lv = chunk.level(level)
            part = [lv.keys, lv.masks, lv.full_masks, lv.contours, None, None, None]
            if bricks and self.brick_side:
                if level < self.depth:
                    o, c, n = brick_ops.assemble(lv.layout, lv.opacity, lv.color if self.has_color else None,
                                                 lv.normal if self.has_normal else None)
                else:
                    o, c, n = self.voxel_bricks(chunk)
                part[4:] = [o, c, n]
            parts.append(part)
        out = Level(level)
        s3 = self.brick_side ** 3
        names = ["keys", "masks", "full_masks", "contours", "opacity", "color", "normal"]
        empty = [np.uint64, np.uint8, np.uint8, np.uint32, np.uint8, np.uint32, np.uint16]
        for j, name in enumerate(names):
            arrays = [p[j] for p in parts if p[j] is not None]
            if j >= 4 and not arrays:
                setattr(out, name, None)
                continue
            shape = (0, s3) if j >= 4 else (0,)
            setattr(out, name, np.concatenate(arrays) if arrays else np.zeros(shape, empty[j]))
        ao = self.ao()
        out.ao = None if ao is None else ao[level]
        return out

    def pruned_leaves(self, level):
        """Keys of the pruned leaves of ``level``: nodes above the voxels without children, whose
        brick and contour stand for the subtree pruning dropped."""
        if not self.is_pruned or not 0 <= level < self.depth:
            return np.zeros(0, np.uint64)
        lv = self.level(level, bricks=False)
        return lv.keys[(lv.masks == 0) & (lv.full_masks == 0)]

    def full_leaves(self, level):
        """Keys (at ``level``) of the full leaves among the children of level ``level`` − 1."""
        if not 1 <= level <= self.depth:
            return np.zeros(0, np.uint64)
        out = []
        for chunk in self.chunks(level - 1, samples=False):
            lv = chunk.level(level - 1)
            rows, cols = np.nonzero(np.unpackbits(lv.full_masks[:, None], axis=1, bitorder="little"))
            out.append((lv.keys[rows] << np.uint64(3)) | cols.astype(np.uint64))
        return np.concatenate(out) if out else np.zeros(0, np.uint64)

    def voxels(self, pages=None):
        """The voxels of the given pages (all when None) with colours, normals and baked AO."""
        pages = range(self.page_count) if pages is None else pages
        keys, colors, normals, starts = [], [], [], []
        at = 0
        voxel_start = np.concatenate([[0], np.cumsum(self.page_table["voxels"].astype(np.int64))])
        for i in pages:
            chunk = self.page(int(i), samples=False, contours=False)
            keys.append(chunk.levels[-1].keys)
            colors.append(chunk.voxel_colors)
            normals.append(chunk.voxel_normals)
            starts.append(np.arange(voxel_start[i], voxel_start[i + 1]))
            if len(keys[-1]) != voxel_start[i + 1] - voxel_start[i]:
                self._c.fail(f"page {i}: {len(keys[-1])} voxels, the page table says "
                             f"{voxel_start[i + 1] - voxel_start[i]}")
            at += len(keys[-1])
        keys = np.concatenate(keys) if keys else np.zeros(0, np.uint64)
        rgba = None
        if self.has_color:
            if self.flags & FLAG_SHARED_COLOR:
                one = self.shared_color.view(np.float16).astype(np.float32)
                rgba = np.broadcast_to(one, (len(keys), 4))
            else:
                rgba = np.concatenate(colors).view(np.float16).astype(np.float32)
        unit = None
        if self.has_normal:
            codes = np.concatenate(normals).astype(np.uint32)
            unit = codecs.oct_decode(codes[:, 0] | codes[:, 1] << 16, 16)
        ao = self.ao()
        if ao is not None:
            index = np.concatenate(starts) if starts else np.zeros(0, np.int64)
            ao = ao[self.depth][index].astype(np.float32) / np.float32(255)
        return Voxels(keys, rgba, unit, ao)

    def ao(self):
        """Baked AO (uint8 per node, 255 fully occluded) per level, or None when not baked."""
        if self._ao is not None or not self.has_ao:
            return self._ao
        section = self._c.payload("AOCC")
        if len(section) < 24:
            self._c.fail("AOCC shorter than its header")
        levels, codec, raw, stored = struct.unpack_from("<IIQQ", section, 0)
        if levels != self.depth + 1 or raw != int(self.level_nodes.sum()) or codec > 1 or \
                len(section) != 24 + stored or (codec == 0 and stored != raw):
            self._c.fail("AOCC header does not match HEAD")
        data = section[24:]
        if codec == 1:
            try:
                data = self._dctx.decompress(bytes(data), max_output_size=raw)
            except zstandard.ZstdError as e:
                self._c.fail(f"AOCC: {e}")
            if len(data) != raw:
                self._c.fail("AOCC decodes to the wrong size")
        values = np.frombuffer(data, np.uint8)
        ends = np.cumsum(self.level_nodes)
        self._ao = np.split(values, ends[:-1])
        return self._ao


def _read_grid(c):
    g = c.payload("GRID")
    if len(g) != 48:
        c.fail(f"GRID of {len(g)} bytes")
    ox, oy, oz, h = struct.unpack_from("<dddd", g, 0)
    dims = struct.unpack_from("<III", g, 32)
    (mode,) = struct.unpack_from("<I", g, 44)
    values = (ox, oy, oz, h)
    if not all(np.isfinite(values)) or not h > 0 or not all(1 <= d < (1 << 21) for d in dims) or mode > 1:
        c.fail("GRID out of range")
    return Grid((ox, oy, oz), h, dims, mode)


def _grid_depth(dims):
    longest = max(dims)
    return max(1, (longest - 1).bit_length())


def open(path):  # noqa: A001 - the package's entry point, as in svokit.open(path)
    """Opens an .svo file: ``svokit.open("scene.svo").voxels()``. Raises FormatError (a
    ValueError) naming the file and the problem for anything but a valid file."""
    return SvoFile(path)
