"""svo-export's DAG files (HashDAG, SymVox and its symmetry-aware form) read as their renderers read them (svokit.dag, written from formats/dag.md)
against the octree read by the Python reader: the same voxels, colours in HashDAG's depth-first
order, and every field a loader relies on (HashDAG's levels, root, voxel counts in the node
headers and enclosed-leaves array; SymVox's box, levels and node count).

Needs SVOKIT_BIN_DIR, SVOKIT_DATA_DIR and SVOKIT_CGAL_MESHES, as ctest sets them.
"""

import pathlib
import sys
import unittest

HERE = pathlib.Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))
sys.path.insert(0, str(HERE))

import numpy as np  # noqa: E402

import svokit  # noqa: E402
from svokit import codecs, dag  # noqa: E402
from tool_env import ToolCase  # noqa: E402


# name, mesh (folder variable, file), mesh2svo options, levels exported (None: the voxels).
CASES = [
    ("torus-pages", ("SVOKIT_DATA_DIR", "uv-torus.obj"), ["-r", "300", "--memory-limit", "64M"],
     [None, 7, 3]),
    ("room-no-bricks", ("SVOKIT_DATA_DIR", "box-room.ply"), ["-r", "160", "--bricks", "none"], [None, 5]),
    ("armadillo-geometry", ("SVOKIT_CGAL_MESHES", "armadillo.off"),
     ["-r", "200", "--attributes", "none", "--no-contours"], [None, 6]),
    ("armadillo-solid", ("SVOKIT_CGAL_MESHES", "armadillo.off"), ["-r", "150", "--fill", "solid"],
     [None, 6]),
]


def octree_voxels(f, level):
    """(x, y, z) rows of the octree's voxels at ``level``: its nodes there and a solid's full
    leaves above it, expanded."""
    parts = [codecs.morton_decode(f.level(level, bricks=False).keys)]
    for above in range(1, level + 1):
        full = f.full_leaves(above)
        if len(full) == 0:
            continue
        side = 1 << (level - above)
        corner = codecs.morton_decode(full) * side
        offsets = np.stack(np.meshgrid(*[np.arange(side)] * 3, indexing="ij"), -1).reshape(-1, 3)
        parts.append((corner[:, None, :] + offsets[None, :, :]).reshape(-1, 3))
    return np.concatenate(parts)


def as_set(rows):
    return set(map(tuple, np.asarray(rows).tolist()))


def counts_below(words, visits, leaf_counts):
    """Voxels below each visited node, per level (as ``visits`` lists them)."""
    counts = [None] * len(visits)
    counts[-1] = leaf_counts
    for lv in range(len(visits) - 1, 0, -1):
        up = np.zeros(len(visits[lv - 1][0]), np.int64)
        np.add.at(up, visits[lv][1], counts[lv])
        counts[lv - 1] = up
    return counts


class DagFiles(ToolCase):
    def make(self, name, mesh, options):
        out = self.dir / f"{name}.svo"
        self.run_tool("mesh2svo", self.mesh(*mesh), "-o", out, *options)
        return out

    def check_hashdag(self, f, path, level, want):
        h = dag.read_hashdag(path)
        self.assertEqual(h.levels, level)
        side = f.grid.voxel_size * (1 << f.depth)
        self.assertEqual(h.bmin, tuple(f.grid.origin))
        self.assertTrue(np.allclose(np.subtract(h.bmax, h.bmin), side, rtol=1e-12))
        voxels, visits = dag.hashdag_voxels(h, with_visits=True)
        self.assertEqual(as_set(voxels), want)
        self.assertEqual(len(voxels), len(want))  # no voxel twice
        # Depth-first with children 4x + 2y + z: ascending keys with x and z exchanged.
        swapped = codecs.morton_encode(voxels[:, [2, 1, 0]]).astype(np.int64)
        self.assertTrue(np.all(np.diff(swapped) > 0))

        colors_path = path.with_name(path.name[: -len(".dag.bin")] + ".uncompressed_colors.bin")
        leaves = visits[-1][0]
        bits = h.words[leaves].astype(np.uint64) | (h.words[leaves + 1].astype(np.uint64) << np.uint64(32))
        leaf_counts = np.array([bin(int(b)).count("1") for b in bits], np.int64)
        counts = counts_below(h.words, visits, leaf_counts)
        if not f.has_color or (f.brick_side == 0 and level < f.depth) or f.is_solid:
            self.assertFalse(colors_path.exists())
            return
        c = dag.read_hashdag_colors(colors_path)
        self.assertEqual(len(c.rgba), len(voxels))
        self.assertTrue(np.all(c.rgba[:, 3] == 255))
        # The loader's voxel counts: inline in a node's upper 24 bits from level top_levels down,
        # above it an index into enclosed (HashDAG's BasicDAGColors lookup).
        self.assertGreaterEqual(len(c.enclosed), 1)
        for lv in range(1, h.levels - 2):
            upper = (h.words[visits[lv][0]] >> np.uint32(8)).astype(np.int64)
            got = upper if lv >= c.top_levels else c.enclosed[upper].astype(np.int64)
            self.assertTrue(np.array_equal(got, counts[lv]), f"level {lv}")
        if level == f.depth:
            v = f.voxels()
            index = np.searchsorted(v.keys, codecs.morton_encode(voxels))
            want_rgb = codecs.srgb8(v.colors[index, :3])
            self.assertLessEqual(int(np.abs(want_rgb.astype(np.int64) - c.rgba[:, :3]).max()), 1)

    def check_svdag(self, f, path, level, want):
        s = dag.read_svdag(path)
        self.assertEqual(s.levels, level)
        side = f.grid.voxel_size * (1 << f.depth)
        self.assertAlmostEqual(s.root_side, side, delta=side * 1e-6)
        self.assertTrue(np.allclose(s.bmin, f.grid.origin, atol=side * 1e-6))
        self.assertTrue(np.allclose(np.subtract(s.bmax, s.bmin), side, rtol=1e-6))
        voxels = dag.svdag_voxels(s)
        self.assertEqual(as_set(voxels), want)
        self.assertEqual(len(voxels), len(want))
        self.assertTrue(np.all(s.words[0] & np.uint32(0xFFFFFF00) == 0))
        # svokit's packed colours beside it, in the same depth-first order.
        packed = path.with_suffix(".dagcolors")
        if not f.has_color or (f.brick_side == 0 and level < f.depth) or f.is_solid:
            self.assertFalse(packed.exists())
            return
        rgba, colors_level = dag.read_packed_colors(packed)
        self.assertEqual(colors_level, level)
        self.assertEqual(len(rgba), len(voxels))
        if level == f.depth:
            v = f.voxels()
            index = np.searchsorted(v.keys, codecs.morton_encode(voxels))
            want_rgb = codecs.srgb8(v.colors[index, :3])
            self.assertLessEqual(int(np.abs(want_rgb.astype(np.int64) - rgba[:, :3]).max()), 1)

    def check_ssvdag(self, f, path, level, want):
        s = dag.read_ssvdag(path)
        self.assertEqual(s.levels, level)
        side = f.grid.voxel_size * (1 << f.depth)
        self.assertAlmostEqual(s.root_side, side, delta=side * 1e-6)
        self.assertEqual(s.level_offsets[0], 0)
        voxels = dag.ssvdag_voxels(s)
        self.assertEqual(as_set(voxels), want)
        self.assertEqual(len(voxels), len(want))

    def test_files_expand_to_the_octrees_voxels(self):
        for name, mesh, options, levels in CASES:
            svo = self.make(name, mesh, options)
            with svokit.open(svo) as f:
                for level in levels:
                    level = f.depth if level is None else level
                    with self.subTest(case=name, level=level):
                        want = as_set(octree_voxels(f, level))
                        hashdag = self.dir / f"{name}-{level}.basic_dag.dag.bin"
                        svdag = self.dir / f"{name}-{level}.svdag"
                        self.run_tool("svo-export", svo, "-o", hashdag, "--level", level)
                        self.run_tool("svo-export", svo, "-o", svdag, "--level", level)
                        self.check_hashdag(f, hashdag, level, want)
                        self.check_svdag(f, svdag, level, want)
                        ssvdag = self.dir / f"{name}-{level}.ssvdag"
                        self.run_tool("svo-export", svo, "-o", ssvdag, "--level", level, "--colors", "none")
                        self.check_ssvdag(f, ssvdag, level, want)

    def test_the_spec_examples(self):
        # formats/dag.md's worked examples, by hand: one voxel at (1, 0, 0) of an 8³ grid, and at
        # (0, 0, 0) of a 4³ grid.
        h = dag.HashDag((0, 0, 0), (8, 8, 8), 3, np.array([0x1, 2, 0x10, 0], np.uint32))
        self.assertEqual(as_set(dag.hashdag_voxels(h)), {(1, 0, 0)})
        s = dag.Svdag((0, 0, 0), (4, 4, 4), 4.0, 2, 2, 3, np.array([0x1, 2, 0x1], np.uint32))
        self.assertEqual(as_set(dag.svdag_voxels(s)), {(0, 0, 0)})
        # (1, 0, 0) and its x mirror (6, 0, 0) in 8³: one leaf, child 4 seen through mirror x.
        m = dag.Ssvdag((0, 0, 0), (8, 8, 8), 8.0, 3, 1, np.array([0x0101, 0x2000, 0x0000], np.uint16),
                       np.array([1 << 16], np.uint64), np.array([0], np.uint32))
        self.assertEqual(as_set(dag.ssvdag_voxels(m)), {(1, 0, 0), (6, 0, 0)})


if __name__ == "__main__":
    unittest.main()
