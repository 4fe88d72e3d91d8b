"""The Python reader against the C++ readers on octrees of the test meshes, made here by svokit's
tools: every array of svo-format-dump's JSON (formats/golden/README.md, "The JSON") equal.

Needs SVOKIT_BIN_DIR (mesh2svo, svo-bake), SVOKIT_FORMAT_DUMP, SVOKIT_DATA_DIR, SVOKIT_CGAL_MESHES
and SVOKIT_ASSIMP_MODELS, as ctest sets them (tests/CMakeLists.txt).
"""

import json
import pathlib
import subprocess
import sys
import unittest

HERE = pathlib.Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))
sys.path.insert(0, str(HERE))

import numpy as np  # noqa: E402

import svokit  # noqa: E402
from compare import check  # noqa: E402
from tool_env import ToolCase, env_path  # noqa: E402


# name, mesh (folder variable, file), mesh2svo options, then svo-bake options (None: no bake).
CASES = [
    ("torus-pages", ("SVOKIT_DATA_DIR", "uv-torus.obj"), ["-r", "150"], None),
    ("torus-bricks2", ("SVOKIT_DATA_DIR", "uv-torus.obj"), ["-r", "140", "--bricks", "2"], None),
    ("room-no-bricks", ("SVOKIT_DATA_DIR", "box-room.ply"), ["-r", "160", "--bricks", "none"], None),
    ("armadillo-geometry", ("SVOKIT_CGAL_MESHES", "armadillo.off"),
     ["-r", "136", "--attributes", "none", "--no-contours"], None),
    ("armadillo-solid", ("SVOKIT_CGAL_MESHES", "armadillo.off"), ["-r", "140", "--fill", "solid"], None),
    ("spider-ao", ("SVOKIT_ASSIMP_MODELS", "OBJ/spider.obj"), ["-r", "132"], ["--ao"]),
    ("tetra-by-pages", ("SVOKIT_DATA_DIR", "tetra.off"), ["-r", "200", "--memory-limit", "64M"], None),
]


class CppReaders(ToolCase):
    @classmethod
    def setUpClass(cls):
        super().setUpClass()
        cls.dump = env_path("SVOKIT_FORMAT_DUMP")

    def make(self, name, mesh, options, bake):
        mesh_path = self.mesh(*mesh)
        out = self.dir / f"{name}.svo"
        subprocess.run([str(self.bin / "mesh2svo"), str(mesh_path), "-o", str(out), "-q", *options],
                       check=True)
        if bake is not None:
            baked = self.dir / f"{name}-baked.svo"
            subprocess.run([str(self.bin / "svo-bake"), str(out), *bake, "-o", str(baked), "-q"], check=True)
            out = baked
        text = subprocess.run([str(self.dump), str(out)], check=True, capture_output=True).stdout
        return out, json.loads(text)

    def test_every_array_equals_the_cpp_readers(self):
        for name, mesh, options, bake in CASES:
            with self.subTest(case=name):
                path, want = self.make(name, mesh, options, bake)
                check(path, want, self.assertEqual)

    def test_the_cases_cover_every_kind_of_file(self):
        kinds = set()
        for name, mesh, options, bake in CASES:
            path, _ = self.make(name, mesh, options, bake)
            with svokit.open(path) as f:
                kinds |= {f"side {f.brick_side}", "solid" if f.is_solid else "surface"}
                kinds |= {k for k, on in (("pages", f.page_count > 1), ("contours", f.has_contours),
                                          ("color", f.has_color), ("normal", f.has_normal),
                                          ("ao", f.has_ao), ("halo", any(len(f.page(i).halo_keys)
                                                                         for i in range(f.page_count))))
                          if on}
        self.assertEqual(kinds, {"side 0", "side 2", "side 3", "solid", "surface", "pages", "contours",
                                 "color", "normal", "ao", "halo"})

    def test_voxels_with_attributes_match_the_levels(self):
        path, want = self.make(*CASES[0])
        with svokit.open(path) as f:
            v = f.voxels()
            voxel_level = want["levels"][-1]
            self.assertTrue(np.array_equal(v.keys, np.array(voxel_level["keys"], np.uint64)))
            self.assertEqual(v.coords.shape, (len(v.keys), 3))
            self.assertTrue(np.all(v.coords < np.array(f.grid.dims)))
            self.assertTrue(np.allclose(np.linalg.norm(v.normals, axis=1), 1, atol=1e-5))
            self.assertTrue(np.all((v.colors >= 0) & (v.colors <= 1)))
            # Each voxel in the page the page table says, with the page's count.
            counts = [len(f.page(i).levels[-1].keys) for i in range(f.page_count)]
            self.assertEqual(counts, list(f.page_table["voxels"]))


if __name__ == "__main__":
    unittest.main()
