"""What the tests that run svokit's tools take from ctest's environment (tests/CMakeLists.txt)."""

import os
import pathlib
import subprocess
import tempfile
import unittest


def env_path(name):
    """The path in environment variable ``name``; the test is skipped when it is not set."""
    value = os.environ.get(name)
    if not value:
        raise unittest.SkipTest(f"{name} is not set (run through ctest)")
    return pathlib.Path(value)


class ToolCase(unittest.TestCase):
    """Tests that run svokit's tools: ``bin`` (their folder) and ``dir`` (a scratch folder for the
    class, removed after it)."""

    @classmethod
    def setUpClass(cls):
        cls.bin = env_path("SVOKIT_BIN_DIR")
        cls.tmp = tempfile.TemporaryDirectory()
        cls.dir = pathlib.Path(cls.tmp.name)

    @classmethod
    def tearDownClass(cls):
        cls.tmp.cleanup()

    def run_tool(self, *args):
        """Runs tool ``args[0]`` with the other arguments and ``-q``; a failure fails the test."""
        subprocess.run([str(self.bin / args[0]), *map(str, args[1:]), "-q"], check=True)

    def mesh(self, folder, file):
        """Test mesh ``file`` in the folder of environment variable ``folder``."""
        path = env_path(folder) / file
        if not path.exists():
            self.fail(f"test mesh {path} is missing (scripts/deps --test-data)")
        return path
