"""Compares what the Python reader makes of an .svo with the C++ readers' JSON dump of it
(formats/golden/README.md, "The JSON"), array by array."""

import numpy as np

import svokit


def _flat(a):
    return np.asarray(a if a is not None else [], dtype=np.float64).ravel()


class Mismatch(AssertionError):
    pass


def check(path, want, expect_equal):
    """Raises Mismatch naming the first JSON path whose value the Python reader does not give."""
    f = svokit.open(path)

    def same(name, got, expected):
        got_a = _flat(got)
        exp_a = _flat(expected)
        if got_a.shape != exp_a.shape or not np.array_equal(got_a, exp_a):
            first = next((i for i in range(min(len(got_a), len(exp_a))) if got_a[i] != exp_a[i]), None)
            raise Mismatch(f"{path}: {name}: {len(got_a)} values against {len(exp_a)}"
                           + ("" if first is None else f", first difference at {first}: "
                              f"{got_a[first]} against {exp_a[first]}"))

    def scalar(name, got, expected):
        if got != expected:
            raise Mismatch(f"{path}: {name}: {got!r} against {expected!r}")

    container = want["container"]
    scalar("container/version", f.version, container["version"])
    tags = [s["tag"] for s in container["sections"]]
    scalar("container/sections", list(f._c.sections), tags)
    for s in container["sections"]:
        got = f._c.sections[s["tag"]]
        scalar(f"container/{s['tag']}", (got.offset, got.size, got.crc), (s["offset"], s["size"], s["crc32c"]))
    g = want["grid"]
    same("grid/origin", f.grid.origin, g["origin"])
    scalar("grid/voxel_size", f.grid.voxel_size, g["voxel_size"])
    same("grid/dims", f.grid.dims, g["dims"])
    scalar("grid/mode", f.grid.mode, g["mode"])
    h = want["head"]
    for key, got in (("depth", f.depth), ("brick_side", f.brick_side), ("flags", f.flags),
                     ("page_level", f.page_level), ("pages", f.page_count), ("codec", f.codec)):
        scalar(f"head/{key}", got, h[key])
    same("head/shared_color", f.shared_color, h["shared_color"])
    same("head/levels/nodes", f.level_nodes, [lv["nodes"] for lv in h["levels"]])
    same("head/levels/contours", f.level_contours, [lv["contours"] for lv in h["levels"]])
    same("head/levels/samples", f.level_samples, [lv["samples"] for lv in h["levels"]])
    expect_equal(f.meta, want["meta"], f"{path}: meta")
    for key in ("key", "offset", "stored_bytes", "crc32c", "voxels"):
        same(f"page_table/{key}", f.page_table[key], [e[key] for e in want["page_table"]])

    chunks = list(f.chunks())
    scalar("chunks", len(chunks), len(want["chunks"]))
    for i, (chunk, wc) in enumerate(zip(chunks, want["chunks"])):
        at = f"chunks/{i}"
        scalar(f"{at}/root_level", chunk.root_level, wc["root_level"])
        scalar(f"{at}/root_key", chunk.root_key, wc["root_key"])
        scalar(f"{at}/levels", len(chunk.levels), len(wc["levels"]))
        for lv, wl in zip(chunk.levels, wc["levels"]):
            la = f"{at}/level {lv.level}"
            scalar(la, lv.level, wl["level"])
            same(f"{la}/masks", lv.masks, wl["masks"])
            same(f"{la}/full_masks", lv.full_masks if f.is_solid else [], wl["full_masks"])
            same(f"{la}/contours", lv.contours, wl["contours"])
            same(f"{la}/opacity", lv.opacity, wl["opacity"])
            same(f"{la}/color", lv.color, wl["color"])
            same(f"{la}/normal", lv.normal, wl["normal"])
        for key in ("voxel_colors", "voxel_normals", "halo_keys", "halo_colors", "halo_normals"):
            same(f"{at}/{key}", getattr(chunk, key), wc[key])

    aocc = want["aocc"]
    scalar("aocc", f.has_ao, aocc is not None)
    for lv_want in want["levels"]:
        level = lv_want["level"]
        la = f"levels/{level}"
        lv = f.level(level)
        same(f"{la}/keys", lv.keys, lv_want["keys"])
        same(f"{la}/contours", lv.contours[lv.contours != 0], lv_want["contours"])
        same(f"{la}/opacity", lv.opacity, lv_want["opacity"])
        same(f"{la}/color", lv.color, lv_want["color"])
        same(f"{la}/normal", lv.normal, lv_want["normal"])
        same(f"{la}/ao", lv.ao, lv_want["ao"])
        if level == f.depth:
            same(f"{la}/child_masks", [], lv_want["child_masks"])
            continue
        # The node records ReadSvo builds (version 1's), from the masks and the next level.
        below = f.level(level + 1, bricks=False)
        counts = np.unpackbits(lv.masks[:, None], axis=1, bitorder="little")
        first_child = np.concatenate([[0], np.cumsum(counts.sum(axis=1), dtype=np.int64)[:-1]])
        child_has_children = np.zeros(len(below.keys), bool)
        if level + 1 < f.depth:
            child_has_children = below.masks != 0
        child_contour = below.contours != 0
        leaf = np.zeros(len(lv.keys), np.uint8)
        contour = np.zeros(len(lv.keys), np.uint8)
        rows, cols = np.nonzero(counts)
        child = first_child[rows] + np.cumsum(counts, axis=1, dtype=np.int64)[rows, cols] - 1
        np.bitwise_or.at(leaf, rows, (~child_has_children[child]).astype(np.uint8) << cols.astype(np.uint8))
        np.bitwise_or.at(contour, rows, child_contour[child].astype(np.uint8) << cols.astype(np.uint8))
        contour_before = np.concatenate([[0], np.cumsum(child_contour, dtype=np.int64)])
        same(f"{la}/child_masks", lv.masks, lv_want["child_masks"])
        same(f"{la}/full_masks", lv.full_masks, lv_want["full_masks"])
        same(f"{la}/leaf_masks", leaf, lv_want["leaf_masks"])
        same(f"{la}/contour_masks", contour, lv_want["contour_masks"])
        same(f"{la}/first_child", first_child, lv_want["first_child"])
        same(f"{la}/first_contour", contour_before[first_child], lv_want["first_contour"])
    f.close()
