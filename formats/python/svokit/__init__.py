"""svokit's reference reader in Python: ``f = svokit.open("scene.svo")``, then ``f.voxels()``
(keys, grid coordinates, colours, normals, AO), ``f.level(L)`` (keys, masks, contours, bricks,
AO of a level), ``f.top()`` and ``f.page(i)`` (chunks as stored) as numpy arrays.

Written from the format specs (formats/svo.md, formats/container.md), independently of the C++
readers, which its tests compare it with array by array.
"""

from .errors import FormatError
from .svo import Chunk, ChunkLevel, Grid, Level, SvoFile, Voxels, open  # noqa: A004

__all__ = ["FormatError", "Chunk", "ChunkLevel", "Grid", "Level", "SvoFile", "Voxels", "open"]
__version__ = "0.1.0"
