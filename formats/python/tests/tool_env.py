"""What the tests that run svokit's tools take from ctest's environment (tests/CMakeLists.txt)."""

import os
import pathlib
import unittest


def env_path(name):
    """The path in environment variable ``name``; the test is skipped when it is not set."""
    value = os.environ.get(name)
    if not value:
        raise unittest.SkipTest(f"{name} is not set (run through ctest)")
    return pathlib.Path(value)
