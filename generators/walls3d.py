"""3D masonry wall generator: hexahedral units in stretcher, stack, header, English or Flemish bond,
with bed, head and (multi-wythe bonds) collar joints, openings with lintels, beams and potential
unit cracks, for the simplified micro-model (Lourenco 1996, PhD thesis TU Delft, ch. 6).

The bond layout, the validation of the parameters and the joint classification are shared with the
2D generator (:mod:`generators.walls`, whose docstring describes the bonds, their sources and the
choice of structured grids over gmsh); the mesh is built by :func:`generators.grid3d.boxes_to_mesh`.

Axes: x along the wall, y across the thickness (front face y = 0), z up.
"""
from __future__ import annotations

import numbers


from masonrydam.errors import SceneError

from .grid3d import Box, boxes_to_mesh
from .walls import HEADER_BONDS, add_common_sets, check_mesh_options, joint_classifier, wall_parts, wall_spec


def wall_thickness(bond: str, lu: float, wu: float, thickness: float, key: str) -> tuple[float, int]:
    """Wall thickness and number of stretcher wythes for ``bond`` (expanded unit length lu, width wu).

    Stretcher and stack bond: ``thickness / wu`` wythes (default 1; with 2 or more, the wythes are
    joined by collar joints only, as in a collar-jointed wall); header, English and Flemish bond:
    one brick thick (thickness = lu, two stretcher wythes)."""
    if isinstance(thickness, bool) or not isinstance(thickness, numbers.Real) or thickness < 0:
        raise SceneError(f"{key}.thickness", f"must be >= 0 (0: from the bond), got {thickness!r}")
    if bond in HEADER_BONDS:
        if thickness and abs(thickness - lu) > 1e-6 * lu:
            raise SceneError(f"{key}.thickness", f"a wall in {bond} bond is one unit length thick: {lu:g} m "
                                                 f"(unit_length + joint_thickness), got {thickness:g} m")
        return lu, 2
    if not thickness:
        return wu, 1
    n = int(round(thickness / wu))
    if n < 1 or abs(n * wu - thickness) > 1e-6 * wu:
        raise SceneError(f"{key}.thickness", f"a {bond}-bond wall is a whole number of wythes of {wu:g} m "
                                             f"(unit_width + joint_thickness) thick, got {thickness:g} m")
    return n * wu, n


def masonry_wall_3d(
    length: float,
    height: float,
    unit_length: float,
    unit_height: float,
    unit_width: float,
    joint_thickness: float = 0.0,
    bond: str = "stretcher",
    thickness: float = 0.0,
    elements_per_unit: int = 1,
    order: int = 1,
    element_size: float = 0.0,
    unit_cracks: bool = False,
    openings: list | None = None,
    base_beam_height: float = 0.0,
    top_beam_height: float = 0.0,
    beam_joints: bool = True,
    key: str = "mesh.parameters",
):
    """A 3D wall of hexahedral units (hex8, or hex20 with ``order=2``) joined by interfaces.

    Lengths in m; unit size is the real brick (length, height, width) plus ``joint_thickness``
    (expanded units meet at zero-thickness joints). ``bond``: 'stretcher' (= 'running'), 'stack',
    'header', 'english' or 'flemish' (see :mod:`generators.walls`). ``thickness``: 0 for the bond's
    own (one wythe for stretcher / stack, one unit length for the others), or a whole number of
    wythes for stretcher / stack bond. ``unit_cracks``: a potential crack interface at mid-length
    of every whole unit, normal to the unit's length (stretchers: plane x = mid; headers: plane
    y = mid), set 'unit_cracks'. ``openings``: list of {x0, z0, width, height, lintel_height=0,
    lintel_bearing=0} through the thickness, z0 from the underside of the masonry.
    Element size: ``element_size`` if > 0, else min(expanded unit length, height, width) /
    elements_per_unit.

    Element groups: 'units', 'lintels', 'base_beam', 'top_beam'. Joint sets: 'bed_joints' (normal
    z), 'head_joints' (x), 'collar_joints' (y), 'unit_cracks', 'lintel_joints', 'base_joint' and
    'top_joint' (with ``beam_joints``). Node sets: base, top, left, right, front, back,
    '<group>_nodes', beams. Facet sets: base_face, top_face, left_face, right_face, front_face,
    back_face, opening_<i>.
    """
    spec = wall_spec(length, height, unit_length, unit_height, unit_width, joint_thickness, bond, openings,
                     base_beam_height, top_beam_height, key, dim=3, vertical="z0")
    T, n_wythes = wall_thickness(spec.bond, spec.lu, spec.wu, thickness, key)
    check_mesh_options(order, elements_per_unit, element_size, key)
    wu = spec.wu
    stretcher_rows = [(round(i * wu, 12), round((i + 1) * wu, 12) if i < n_wythes - 1 else T, "x")
                      for i in range(n_wythes)]
    through = [(0.0, T, "y")]

    def wythes_of(slot):
        if slot is None:
            return [(0.0, T, None)]
        return stretcher_rows if slot.role in ("S", "half") else through

    parts = wall_parts(spec, unit_cracks, wythes_of)
    boxes = [Box(p.x0, p.y0, p.z0, p.x1, p.y1, p.z1, p.group, p.kind) for p in parts]
    cls = joint_classifier(beam_joints)

    def classify(a: Box, b: Box, axis: str):
        return cls(a.kind, a.group, b.kind, b.group, axis)

    size = element_size if element_size > 0 else min(spec.lu, spec.hu, wu) / elements_per_unit
    mesh = boxes_to_mesh(boxes, size, order, classify)
    return add_common_sets(mesh, spec)
