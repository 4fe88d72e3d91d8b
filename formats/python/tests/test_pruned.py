"""A pruned octree (mesh2svo --prune) read by the Python reader against the full octree of the
same build: its voxels are the full octree's but those below its pruned leaves, each pruned leaf
is a node of the full octree with voxels below it, and every voxel it dropped lies below a leaf.

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
from tool_env import ToolCase  # noqa: E402

# name, mesh (folder variable, file), mesh2svo options.
CASES = [
    ("torus", ("SVOKIT_DATA_DIR", "uv-torus.obj"), ["-r", "300", "--attributes", "color,normal"]),
    ("armadillo", ("SVOKIT_CGAL_MESHES", "armadillo.off"), ["-r", "200"]),
    # Geometry alone: every 2³ node meets √3, so no voxel is kept and the voxel level is empty.
    ("armadillo-geometry", ("SVOKIT_CGAL_MESHES", "armadillo.off"), ["-r", "200", "--attributes", "none"]),
]


class PrunedOctrees(ToolCase):
    def test_dropped_voxels_lie_below_the_leaves(self):
        for name, mesh, options in CASES:
            with self.subTest(name):
                full_path, pruned_path = self.dir / f"{name}.svo", self.dir / f"{name}-p.svo"
                self.run_tool("mesh2svo", self.mesh(*mesh), "-o", full_path, *options)
                self.run_tool("mesh2svo", self.mesh(*mesh), "-o", pruned_path, *options,
                              "--prune", "default")
                with svokit.open(full_path) as full, svokit.open(pruned_path) as pruned:
                    self.assertTrue(pruned.is_pruned)
                    self.assertFalse(full.is_pruned)
                    depth = full.depth
                    full_voxels = full.level(depth, bricks=False).keys
                    kept = pruned.level(depth, bricks=False).keys
                    self.assertTrue(np.all(np.isin(kept, full_voxels)))
                    dropped = full_voxels[~np.isin(full_voxels, kept)]
                    self.assertGreater(len(dropped), 0)
                    covered = np.zeros(len(dropped), bool)
                    leaves = 0
                    for level in range(depth):
                        keys = pruned.pruned_leaves(level)
                        leaves += len(keys)
                        self.assertTrue(np.all(np.isin(keys, full.level(level, bricks=False).keys)))
                        shift = np.uint64(3 * (depth - level))
                        below = np.isin(dropped >> shift, keys)
                        self.assertFalse(np.any(covered & below), "leaves nested in leaves")
                        covered |= below
                        # Every leaf stands for voxels of the full octree.
                        self.assertTrue(np.all(np.isin(keys, dropped >> shift)))
                    self.assertGreater(leaves, 0)
                    self.assertTrue(np.all(covered), "a dropped voxel below no leaf")


if __name__ == "__main__":
    unittest.main()
