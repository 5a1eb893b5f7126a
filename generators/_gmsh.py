"""Safe, deterministic use of the gmsh Python API by the generators.

:func:`gmsh_session` is a context manager that gives the generators a private gmsh model:

- it initialises gmsh without reading the user's configuration files, without installing a
  SIGINT handler (``interruptible=False``: works outside the main thread) and never opens a window
  (the FLTK GUI is only started by ``gmsh.fltk``, which nothing here calls);
- it silences the terminal (``General.Terminal = 0``) and pins the options that could make two
  runs differ (one thread for every meshing stage, a fixed random seed), so the same parameters
  always give the same mesh, node numbers included;
- it always finalises gmsh, also when an exception leaves the model half built, so no global state
  leaks into the next call. If the caller already runs its own gmsh session, that session is left
  alive: the generator works in a model of its own, which it removes afterwards, and the options it
  changed are restored;
- a process-wide lock serialises the sessions (gmsh's state is global).

The helpers read the mesh back from the API (not through a file) into numpy, with element node
lists permuted into masonrydam's (meshio / VTK) order with
:data:`masonrydam.elements.shapes.GMSH_TO_MESHIO_ORDER`.
"""
from __future__ import annotations

import itertools
import threading
from contextlib import contextmanager

import numpy as np

from masonrydam.elements.shapes import GMSH_TO_MESHIO_ORDER
from masonrydam.errors import MissingDependencyError

_LOCK = threading.RLock()
_COUNTER = itertools.count()

#: gmsh element type code (gmsh reference manual, "MSH file format": element types) -> masonrydam type
GMSH_ELEMENT_TYPES = {1: "line2", 8: "line3", 2: "tri3", 9: "tri6", 3: "quad4", 16: "quad8", 10: "quad9",
                      4: "tet4", 11: "tet10", 5: "hex8", 17: "hex20", 15: "vertex"}

#: options set in every session: silent, single-threaded and seeded (deterministic meshes)
DETERMINISTIC_OPTIONS = {
    "General.Terminal": 0,
    "General.NumThreads": 1,
    "Mesh.MaxNumThreads1D": 1,
    "Mesh.MaxNumThreads2D": 1,
    "Mesh.MaxNumThreads3D": 1,
    "Mesh.RandomSeed": 1,
    "Geometry.OCCParallel": 0,
}


#: the Debian / Ubuntu packages of the system libraries the gmsh wheel links to, absent on many headless machines
GMSH_SYSTEM_PACKAGES = ("libglu1-mesa", "libxcursor1", "libxft2", "libxinerama1")


def _import_gmsh():
    """The gmsh module; a :class:`~masonrydam.errors.MissingDependencyError` that says what to install where the
    package is missing or its shared library cannot load (``OSError: libGLU.so.1: cannot open shared object file``)."""
    try:  # gmsh only for the dam generators: the wall, block and grid generators work without it
        import gmsh
    except ImportError as exc:
        raise MissingDependencyError("the dam generators need the gmsh Python package: pip install gmsh") from exc
    except OSError as exc:  # the wheel's library links to system libraries (OpenGL, X11) a server may not have
        first = str(exc).split(":")[0]
        raise MissingDependencyError(
            f"gmsh (the dam generators' mesher) cannot load its library: {first} is missing. On Debian or Ubuntu: "
            f"sudo apt-get install {' '.join(GMSH_SYSTEM_PACKAGES)}") from exc
    return gmsh


@contextmanager
def gmsh_session(name: str = "masonrydam", options: dict | None = None):
    """Context manager yielding the ``gmsh`` module with a fresh current model ``name``.

    ``options``: extra ``{option: number}`` set after :data:`DETERMINISTIC_OPTIONS`.
    """
    gmsh = _import_gmsh()
    opts = {**DETERMINISTIC_OPTIONS, **(options or {})}
    with _LOCK:
        owner = not gmsh.isInitialized()
        saved: dict = {}
        previous = None
        model = f"{name}_{next(_COUNTER)}"
        if owner:
            gmsh.initialize([], readConfigFiles=False, run=False, interruptible=False)
        else:
            previous = gmsh.model.getCurrent()
        try:
            for k, v in opts.items():
                if not owner:
                    saved[k] = gmsh.option.getNumber(k)
                gmsh.option.setNumber(k, v)
            gmsh.model.add(model)
            yield gmsh
        finally:
            if owner:
                gmsh.finalize()
            else:
                try:
                    gmsh.model.setCurrent(model)
                    gmsh.model.remove()
                except Exception:  # noqa: BLE001 - the model may not exist if add() failed
                    pass
                for k, v in saved.items():
                    gmsh.option.setNumber(k, v)
                if previous:
                    try:
                        gmsh.model.setCurrent(previous)
                    except Exception:  # noqa: BLE001
                        pass


def get_nodes(gmsh) -> tuple[np.ndarray, np.ndarray]:
    """All mesh nodes of the current model: (sorted tags (n,), coordinates (n, 3))."""
    tags, coords, _ = gmsh.model.mesh.getNodes()
    tags = np.asarray(tags, dtype=np.int64)
    coords = np.asarray(coords, dtype=np.float64).reshape(-1, 3)
    order = np.argsort(tags, kind="stable")
    return tags[order], coords[order]


def tags_to_index(sorted_tags: np.ndarray, node_tags) -> np.ndarray:
    """Positions of ``node_tags`` in ``sorted_tags`` (the node indices of a numpy mesh)."""
    node_tags = np.asarray(node_tags, dtype=np.int64)
    idx = np.searchsorted(sorted_tags, node_tags)
    if node_tags.size and (idx.max(initial=0) >= len(sorted_tags) or (sorted_tags[idx] != node_tags).any()):
        raise RuntimeError("gmsh element refers to a node tag that getNodes() did not return")
    return idx


def entity_elements(gmsh, dim: int, tag: int) -> list[tuple[str, np.ndarray, np.ndarray]]:
    """Elements of one geometric entity: ``[(type_name, node_tags (n, k) in meshio order,
    element_tags (n,)), ...]``."""
    out = []
    types, etags, ntags = gmsh.model.mesh.getElements(dim, tag)
    for t, et, nt in zip(types, etags, ntags):
        name = GMSH_ELEMENT_TYPES.get(int(t))
        if name is None:
            raise RuntimeError(f"gmsh element type {int(t)} is not supported by masonrydam")
        k = 1 if name == "vertex" else len(GMSH_TO_MESHIO_ORDER[name])
        conn = np.asarray(nt, dtype=np.int64).reshape(-1, k)
        if name != "vertex":
            conn = conn[:, GMSH_TO_MESHIO_ORDER[name]]
        out.append((name, conn, np.asarray(et, dtype=np.int64)))
    return out


def physical_group_elements(gmsh, dim: int, name: str) -> dict[str, np.ndarray]:
    """Elements of the physical group ``name`` of dimension ``dim``: ``{type_name: node_tags}``
    (node tags, not indices: map them with :func:`tags_to_index`)."""
    for d, tag in gmsh.model.getPhysicalGroups(dim):
        if gmsh.model.getPhysicalName(d, tag) == name:
            acc: dict[str, list] = {}
            for ent in gmsh.model.getEntitiesForPhysicalGroup(d, tag):
                for tname, conn, _ in entity_elements(gmsh, d, int(ent)):
                    acc.setdefault(tname, []).append(conn)
            return {k: np.vstack(v) for k, v in acc.items()}
    raise KeyError(f"no physical group '{name}' of dimension {dim}")
