"""The Python reader against the golden files' JSON (what the C++ readers make of each file)."""

import json
import pathlib
import sys
import tempfile
import unittest

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))

import svokit  # noqa: E402
from compare import check  # noqa: E402

GOLDEN = pathlib.Path(__file__).resolve().parents[2] / "golden"


class GoldenFiles(unittest.TestCase):
    def test_every_paged_svo_equals_its_json(self):
        files = sorted(p for p in GOLDEN.glob("*.svo") if json.loads((GOLDEN / (p.name + ".json")).read_text())
                       ["container"]["version"] >= 2)
        self.assertGreaterEqual(len(files), 10)
        for path in files:
            with self.subTest(file=path.name):
                want = json.loads((GOLDEN / (path.name + ".json")).read_text())
                check(path, want, self.assertEqual)

    def test_version_1_is_refused_by_name(self):
        with self.assertRaisesRegex(svokit.FormatError, r"tetra-uv-r5-bricks2-v1\.svo: version 1"):
            svokit.open(GOLDEN / "tetra-uv-r5-bricks2-v1.svo")


def read_everything(path):
    with svokit.open(path) as f:
        for level in range(f.depth + 1):
            f.level(level)
        f.voxels()


class BadInput(unittest.TestCase):
    """A damaged file is a FormatError naming the file, never another exception or wrong data."""

    def damaged(self, data, name="damaged.svo"):
        tmp = tempfile.TemporaryDirectory()
        self.addCleanup(tmp.cleanup)
        path = pathlib.Path(tmp.name) / name
        path.write_bytes(data)
        return path

    def assert_refused(self, path):
        with self.assertRaises(svokit.FormatError) as caught:
            read_everything(path)
        message = str(caught.exception)
        self.assertTrue(message.startswith(str(path) + ": "), message)
        self.assertNotIn("\n", message)

    def test_every_flipped_byte_is_refused(self):
        for name in ("pair-r130-pages.svo", "tetra-uv-r5-bricks2-ao.svo"):
            good = (GOLDEN / name).read_bytes()
            read_everything(GOLDEN / name)
            for at in range(0, len(good), 3):
                with self.subTest(file=name, byte=at):
                    data = bytearray(good)
                    data[at] ^= 0x10
                    self.assert_refused(self.damaged(bytes(data)))

    def test_truncated_empty_and_missing_files_are_refused(self):
        good = (GOLDEN / "pair-r130-pages.svo").read_bytes()
        for size in (0, 7, 31, 100, len(good) - 1):
            with self.subTest(size=size):
                self.assert_refused(self.damaged(good[:size]))
        self.assert_refused(self.damaged(good + b"\0" * 64))
        self.assert_refused(pathlib.Path(tempfile.gettempdir()) / "no-such-file.svo")
        self.assert_refused(GOLDEN / "tetra-uv.svm")  # another format


if __name__ == "__main__":
    unittest.main()
