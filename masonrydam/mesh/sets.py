"""Named node and facet sets of a mesh as the scene refers to them."""
from __future__ import annotations

import numpy as np

from ..errors import SceneError
from .model import Mesh


def node_set(mesh: Mesh, name: str, key: str) -> np.ndarray:
    """The node indices (int64) of the node set ``name``, or the nodes of the facet set ``name``; a
    :class:`~masonrydam.errors.SceneError` naming the scene key ``key`` when the mesh has neither."""
    if name in mesh.node_sets:
        return mesh.node_sets[name]
    if name in mesh.facet_sets:
        return np.unique(mesh.facet_sets[name].facets)
    raise SceneError(key, f"no node set '{name}' in the mesh (node sets: {sorted(mesh.node_sets)}, "
                          f"facet sets: {sorted(mesh.facet_sets)})")


def facet_set(mesh: Mesh, name: str, key: str):
    """The :class:`~masonrydam.mesh.model.FacetSet` ``name``; a SceneError naming ``key`` when it is missing."""
    if name not in mesh.facet_sets:
        what = "edge" if mesh.dim == 2 else "face"
        raise SceneError(key, f"no facet ({what}) set '{name}' in the mesh (facet sets: {sorted(mesh.facet_sets)})")
    return mesh.facet_sets[name]
