#!/usr/bin/env bash
# `pip install formats/python` without a network, into a virtual environment over Debian's
# python3-numpy and python3-zstandard: the package imports from there and reads a golden file.
set -euo pipefail
src="$1"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
# setuptools builds in the source folder: a copy keeps the tree clean and parallel runs apart.
mkdir "$tmp/src"
cp -r "$src/pyproject.toml" "$src/README.md" "$src/svokit" "$tmp/src/"
/usr/bin/python3 -m venv --system-site-packages "$tmp/venv"
"$tmp/venv/bin/pip" install --quiet --no-index --no-build-isolation "$tmp/src" >"$tmp/pip.log" 2>&1 ||
  { cat "$tmp/pip.log"; exit 1; }
cd "$tmp"
"$tmp/venv/bin/python" - "$(cd "$src/.." && pwd)/golden/pair-r130-pages.svo" <<'PY'
import sys, pathlib
import svokit
where = pathlib.Path(svokit.__file__).resolve()
assert "site-packages" in where.parts, f"imported {where}, not the installed package"
f = svokit.open(sys.argv[1])
v = f.voxels()
assert len(v) == int(f.page_table["voxels"].sum()) == 11, len(v)
print(f"installed svokit {svokit.__version__} read {len(v)} voxels")
PY
