"""Visual meshes of the table and specimens, made with trimesh (SI, metres)."""

from __future__ import annotations

import itertools

import numpy as np
import trimesh


def _box(extents, center) -> trimesh.Trimesh:
    return trimesh.creation.box(extents=extents,
                                transform=trimesh.transformations.translation_matrix(center))


def slab_with_ribs(width: float, thickness: float, rib_width: float, rib_depth: float,
                   rib_offset: float, top_z: float) -> trimesh.Trimesh:
    """The 20 x 20 ft slab and its two central transverse ribs (§2.2); `top_z` is the
    height of the table top in the mesh frame."""
    parts = [_box((width, width, thickness), (0, 0, top_z - thickness / 2))]
    for sx in (-1, 1):
        parts.append(_box((rib_width, width, rib_depth),
                          (sx * rib_offset, 0, top_z - thickness - rib_depth / 2)))
    return trimesh.util.concatenate(parts)


def braced_frame(length: float, spacing: float, storey_heights: list[float], top: float,
                 column: float = 0.1, beam: float = 0.15) -> trimesh.Trimesh:
    """Two parallel braced frames (§2.4): columns at the four corners, beams at every
    floor and X braces in each storey, from the table top (z = 0) to `top`."""
    parts = []
    xs, ys = (-length / 2, length / 2), (-spacing / 2, spacing / 2)
    levels = [0.0, *np.cumsum(storey_heights)]
    levels[-1] = top
    for x in xs:
        for y in ys:
            parts.append(_box((column, column, top), (x, y, top / 2)))
    for z in levels[1:]:
        for y in ys:
            parts.append(_box((length, column, beam), (0, y, z)))
    for z0, z1 in itertools.pairwise(levels):
        for y in ys:
            for s in (-1, 1):
                a, b = np.array([-s * length / 2, y, z0]), np.array([s * length / 2, y, z1])
                parts.append(_strut(a, b, column / 2))
    return trimesh.util.concatenate(parts)


def _strut(a: np.ndarray, b: np.ndarray, r: float) -> trimesh.Trimesh:
    return trimesh.creation.cylinder(radius=r, segment=np.vstack([a, b]), sections=8)


def block(extents, center=(0.0, 0.0, 0.0)) -> trimesh.Trimesh:
    return _box(extents, center)


def to_stl(mesh: trimesh.Trimesh) -> bytes:
    """Binary STL bytes (deterministic for the same mesh)."""
    return mesh.export(file_type="stl")
