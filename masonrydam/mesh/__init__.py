"""Mesh data model, interface insertion and mesh I/O."""
from .interfaces import insert_interfaces
from .model import INTERFACE_FACE_TYPE, CellBlock, FacetSet, Mesh

__all__ = ["Mesh", "CellBlock", "FacetSet", "insert_interfaces", "INTERFACE_FACE_TYPE"]
