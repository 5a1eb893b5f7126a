"""Zero-thickness interface (joint) elements of Tzamtzis & Asteris, sec. 3.3, eqs. 1-11 (the "eq." numbers below).

An interface element joins a *bottom* face and a *top* face with coincident (or nearly coincident)
nodes. Supported faces: ``line2`` / ``line3`` (2D, elements of 2+2 / 3+3 nodes) and ``quad4``,
``quad8``, ``tri3`` (3D, 4+4 / 8+8 / 3+3 nodes). Connectivity rows are
``[bottom_0 .. bottom_{ns-1}, top_0 .. top_{ns-1}]``, both faces in the face-type node order
(masonrydam.elements.shapes). The local relative displacement ``delta = B q`` (m; shear, then opening
positive) is taken in the frame of the reference mid-surface; ``fe = sum_ip B^T t j w h`` (N) and
``ke = sum_ip B^T C B j w h`` (N/m) with the joint law's traction ``t`` (Pa) and tangent ``C`` (Pa/m), the
surface Jacobian ``j``, the rule weight ``w`` and the 2D thickness ``h`` (m). Integration (``interface_rule``):
``"lumped"`` (nodal) by default, after Schellekens & de Borst (1993).

Theory: docs/elements.md, sections "Formulation (Tzamtzis & Asteris, eqs. 1–11)" and "Integration" (under
"Zero-thickness interfaces").
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from ..errors import STATUS_BAD_GEOMETRY, STATUS_NAN, STATUS_OK
from ..materials.mohr_coulomb import (P_COHESION, P_KN, P_KS, P_KS_RESIDUAL, P_OPEN_TANGENT, P_TAN_PHI,
                                      P_TENSILE_STRENGTH, S_BACK_STRESS, S_BOND_BROKEN, S_CODE, S_PLASTIC_SLIP,
                                      mohr_coulomb_point, write_tangent, write_trial)
from ..materials.composite import composite_point
from .quadrature import QUADRATURE_SCHEMES, line_rule, tensor_rule, triangle_rule
from .shapes import ELEMENT_TYPES, reference_nodes, shape_functions

INTERFACE_FACE_TYPES = ("line2", "line3", "quad4", "quad8", "tri3")
DEFAULT_INTERFACE_SCHEME = "lumped"

# relative tolerance of the zero-length / zero-area check: j < GEOM_TOL * (face size)^(dim-1)
GEOM_TOL = 1e-12

# integral of each node's shape function over the reference face, in node order
# (line: [-1, 1]; quad: [-1, 1]^2; triangle: unit simplex of area 1/2)
_LUMPED_WEIGHTS = {
    "line2": (1.0, 1.0),
    "line3": (1.0 / 3.0, 1.0 / 3.0, 4.0 / 3.0),
    "quad4": (1.0, 1.0, 1.0, 1.0),
    "tri3": (1.0 / 6.0, 1.0 / 6.0, 1.0 / 6.0),
}


def interface_rule(face_type: str, scheme: str = DEFAULT_INTERFACE_SCHEME, n: int | None = None):
    """Integration rule on the reference face of an interface element.

    Parameters
    ----------
    face_type : ``"line2"``, ``"line3"`` (2D) or ``"quad4"``, ``"quad8"``, ``"tri3"`` (3D).
    scheme :
        ``"lumped"`` (default) - nodal integration: one point at each node (in the face's node order)
        with weight = integral of that node's shape function over the reference face
        (line2: 1, 1; line3: 1/3, 1/3, 4/3 = Simpson; quad4: 1 x 4; tri3: 1/6 x 3);
        ``"lobatto"`` / ``"newton-cotes"`` - Gauss-Lobatto (tensor) rule, default ``n`` = nodes per
        edge so that the points sit on the nodes (line3 / quad8: 3 per direction = Simpson, for quad8
        the 3x3 rule also has a centre point); tri3: the vertex rule (only n = 3);
        ``"gauss"`` - Gauss-Legendre, ``n`` per direction (default = nodes per edge); tri3: the
        symmetric ``n``-point triangle rule (1, 3 or 6; default 3).
    n : points per direction (total for triangles), see above.

    Returns
    -------
    points : float64 (nip, dim_ref) natural coordinates; weights : float64 (nip,).

    The default is nodal ("lumped") integration because Gauss integration of stiff interfaces
    couples the nodes and makes the tractions oscillate (Schellekens & de Borst 1993, IJNME
    36:43-66); nodal / Newton-Cotes integration does not.

    Raises
    ------
    ValueError for an unknown face type or scheme, a bad ``n``, and for ``quad8`` with ``"lumped"``:
    the integrals of the serendipity corner functions are negative (-1/3), which would give
    negative node-pair springs; use ``"lobatto"`` (3x3 Newton-Cotes) or ``"gauss"`` for quad8.
    """
    if face_type not in INTERFACE_FACE_TYPES:
        raise ValueError(f"unknown interface face type {face_type!r}; use one of {INTERFACE_FACE_TYPES}")
    if scheme not in QUADRATURE_SCHEMES:
        raise ValueError(f"unknown interface integration scheme {scheme!r}; use one of {QUADRATURE_SCHEMES}")
    et = ELEMENT_TYPES[face_type]
    per_edge = len(et.edges[0])  # nodes per edge: 2 (linear) or 3 (quadratic)

    if scheme == "lumped":
        if n is not None and n != et.n_nodes:
            raise ValueError(f"{face_type}: the lumped rule has one point per node ({et.n_nodes}), got n={n}")
        if face_type == "quad8":
            raise ValueError(
                "quad8: lumped (row-sum) integration gives negative corner weights (-1/3); "
                "use scheme='lobatto' (3x3 Newton-Cotes) or 'gauss'"
            )
        pts = reference_nodes(face_type).astype(np.float64)
        # exact integrals of the shape functions over the reference face (node order)
        w = np.array(_LUMPED_WEIGHTS[face_type], dtype=np.float64)
        return np.ascontiguousarray(pts), np.ascontiguousarray(w, dtype=np.float64)

    if et.family == "tri":
        if scheme == "gauss":
            n = 3 if n is None else n
            pts, w = triangle_rule(n)
            return np.ascontiguousarray(pts, dtype=np.float64), np.ascontiguousarray(w, dtype=np.float64)
        if n is not None and n != 3:
            raise ValueError(f"tri3: the Newton-Cotes (vertex) rule has 3 points, got n={n}")
        return reference_nodes("tri3").astype(np.float64), np.full(3, 1.0 / 6.0)

    n = per_edge if n is None else int(n)
    minimum = 2 if scheme != "gauss" else 1
    if n < minimum:
        raise ValueError(f"{face_type}: scheme {scheme!r} needs n >= {minimum} points per direction, got {n}")
    if et.dim == 1:
        pts, w = line_rule(scheme, n)
    else:
        pts, w = tensor_rule(scheme, n, et.dim)
    return np.ascontiguousarray(pts, dtype=np.float64), np.ascontiguousarray(w, dtype=np.float64)


def interface_tables(face_type: str, scheme: str = DEFAULT_INTERFACE_SCHEME, n: int | None = None):
    """Rule and shape tables ready for the kernels.

    Returns ``(N (nip, ns), dN (nip, dim_ref, ns), weights (nip,), points (nip, dim_ref))``, float64,
    C-contiguous; see :func:`interface_rule` for the arguments.
    """
    pts, w = interface_rule(face_type, scheme, n)
    N, dN = shape_functions(face_type, pts)
    return N, dN, w, pts


@njit(cache=True)
def mid_surface_derivatives(coords, conn, e, ns, dim, xm):
    """Reference mid-surface node coordinates of element e into xm (ns, dim); returns the face size
    (largest distance of a mid-surface node from the first one, m)."""
    for a in range(ns):
        b = conn[e, a]
        t = conn[e, ns + a]
        for k in range(dim):
            xm[a, k] = 0.5 * (coords[b, k] + coords[t, k])
    size = 0.0
    for a in range(1, ns):
        d2 = 0.0
        for k in range(dim):
            dx = xm[a, k] - xm[0, k]
            d2 += dx * dx
        if d2 > size:
            size = d2
    return math.sqrt(size)


@njit(cache=True)
def local_frame(xm, dN, g, dim, R, size):
    """Local frame R (dim, dim) (rows: tangent(s), normal) and Jacobian j at integration point g.

    Returns j (> 0), 0.0 for a degenerate (zero length / area) point, or NaN for non-finite input.
    """
    ns = xm.shape[0]
    if dim == 2:
        tx = 0.0
        ty = 0.0
        for a in range(ns):
            tx += dN[g, 0, a] * xm[a, 0]
            ty += dN[g, 0, a] * xm[a, 1]
        j = math.sqrt(tx * tx + ty * ty)
        if not math.isfinite(j):
            return np.nan
        if j <= GEOM_TOL * size or j == 0.0:
            return 0.0
        tx /= j
        ty /= j
        R[0, 0] = tx
        R[0, 1] = ty
        R[1, 0] = -ty
        R[1, 1] = tx
        return j
    # dim == 3: covariant base vectors a1 = dx/dxi, a2 = dx/deta
    a1x = 0.0
    a1y = 0.0
    a1z = 0.0
    a2x = 0.0
    a2y = 0.0
    a2z = 0.0
    for a in range(ns):
        a1x += dN[g, 0, a] * xm[a, 0]
        a1y += dN[g, 0, a] * xm[a, 1]
        a1z += dN[g, 0, a] * xm[a, 2]
        a2x += dN[g, 1, a] * xm[a, 0]
        a2y += dN[g, 1, a] * xm[a, 1]
        a2z += dN[g, 1, a] * xm[a, 2]
    nx = a1y * a2z - a1z * a2y
    ny = a1z * a2x - a1x * a2z
    nz = a1x * a2y - a1y * a2x
    j = math.sqrt(nx * nx + ny * ny + nz * nz)
    l1 = math.sqrt(a1x * a1x + a1y * a1y + a1z * a1z)
    if not (math.isfinite(j) and math.isfinite(l1)):
        return np.nan
    if j <= GEOM_TOL * size * size or j == 0.0 or l1 == 0.0:
        return 0.0
    nx /= j
    ny /= j
    nz /= j
    e1x = a1x / l1
    e1y = a1y / l1
    e1z = a1z / l1
    # e2 = n x e1
    R[0, 0] = e1x
    R[0, 1] = e1y
    R[0, 2] = e1z
    R[1, 0] = ny * e1z - nz * e1y
    R[1, 1] = nz * e1x - nx * e1z
    R[1, 2] = nx * e1y - ny * e1x
    R[2, 0] = nx
    R[2, 1] = ny
    R[2, 2] = nz
    return j


# the joint law of the fused kernels (argument ``law``) is the descriptor's ``JointLaw.kernel_id``
# (masonrydam.materials.joint_laws.FUSED_KERNELS): None, the Mohr-Coulomb law of Tzamtzis & Asteris (and the linear
# joint, a Mohr-Coulomb joint that cannot break), or 1, the composite masonry law of
# masonrydam.materials.composite (see joint_law_at for why None)


@njit(cache=True, inline="always")
def displacement_jumps(conn, u, e, ns, dim, du):
    """The jumps ``du[a] = u_top,a - u_bot,a`` (ns, dim) m across element ``e``'s node pairs (eq. 4)."""
    for a in range(ns):
        b = conn[e, a]
        t = conn[e, ns + a]
        for k in range(dim):
            du[a, k] = u[t * dim + k] - u[b * dim + k]


@njit(cache=True, inline="always")
def jump_at_point(N, g, ns, dim, du, Dug):
    """The jump at integration point ``g`` in global axes, ``Dug = sum_a N_a du[a]`` (dim,) m (eq. 5)."""
    for k in range(dim):
        s = 0.0
        for a in range(ns):
            s += N[g, a] * du[a, k]
        Dug[k] = s


@njit(cache=True, inline="always")
def add_point_tangent(ke_out, e, N, g, ns, dim, ndof_half, Cg):
    """Add the tangent of point ``g``, ``Cg`` (dim, dim) in global axes times the point's weight, to the
    element tangent ``ke_out[e]`` (2 ndof_half, 2 ndof_half): ``+-N_a N_b Cg`` on the bottom/top blocks
    (relative displacement = top minus bottom)."""
    for a in range(ns):
        Na = N[g, a]
        if Na == 0.0:
            continue
        for b in range(ns):
            NaNb = Na * N[g, b]
            if NaNb == 0.0:
                continue
            for k in range(dim):
                ra = a * dim + k
                for m in range(dim):
                    cb = b * dim + m
                    v = NaNb * Cg[k, m]
                    ke_out[e, ra, cb] += v
                    ke_out[e, ra, ndof_half + cb] -= v
                    ke_out[e, ndof_half + ra, cb] -= v
                    ke_out[e, ndof_half + ra, ndof_half + cb] += v


@njit(cache=True, inline="always")
def add_point(fe_out, ke_out, e, N, g, ns, dim, ndof_half, R, t, C, jwh, want_tangent, tg, RC, Cg):
    """Add integration point ``g`` to element ``e``: the force ``-+N_a R^T t jwh`` on the bottom/top nodes and,
    with ``want_tangent``, the tangent ``R^T C R jwh`` (:func:`add_point_tangent`). ``R`` (dim, dim) the local
    frame (rows: tangent(s), normal), ``t`` (dim,) the local traction (Pa), ``C`` (dim, dim) its tangent (Pa/m),
    ``jwh`` the point's weight (j w h); ``tg`` (dim,), ``RC`` and ``Cg`` (dim, dim) scratch. Shared by the fused
    and the generic interface kernels (eqs. 7-10)."""
    for k in range(dim):  # global traction R^T t
        s = 0.0
        for r in range(dim):
            s += R[r, k] * t[r]
        tg[k] = s * jwh
    for a in range(ns):
        Na = N[g, a]
        for k in range(dim):
            fe_out[e, a * dim + k] -= Na * tg[k]
            fe_out[e, ndof_half + a * dim + k] += Na * tg[k]
    if want_tangent:  # Cg = R^T C R * jwh
        for k in range(dim):
            for r in range(dim):
                s = 0.0
                for q in range(dim):
                    s += R[q, k] * C[q, r]
                RC[k, r] = s
        for k in range(dim):
            for m in range(dim):
                s = 0.0
                for r in range(dim):
                    s += RC[k, r] * R[r, m]
                Cg[k, m] = s * jwh
        add_point_tangent(ke_out, e, N, g, ns, dim, ndof_half, Cg)


@njit(cache=True, inline="always")
def joint_law_at(params_table, pidx, state_committed, state_trial, delta_out, traction_out, e, g, dim, C, law,
                 want_tangent=True):
    """The joint law at point ``g`` of element ``e`` from its local relative displacement
    ``delta_out[e, g]`` and committed state: writes ``state_trial[e, g]``, ``traction_out[e, g]`` and the
    tangent ``C`` (dim, dim); returns the law's status. Shared by the small- and large-displacement
    interface kernels. The law runs on scalars (row views per point cost more than the law: see
    :func:`~masonrydam.materials.mohr_coulomb.mohr_coulomb_point`).

    ``law``: None for the Mohr-Coulomb law of Tzamtzis & Asteris, an int (``JointLaw.kernel_id``) for another. Why None:
    numba prunes the ``law is not None`` branch of a None argument before typing, so the Mohr-Coulomb
    kernels never compile the composite law (it doubled the first, compiling run of the default scene).
    ``want_tangent`` False: a law may leave ``C`` uncomputed (the composite law does: its tangent is a complex-step
    Jacobian of its local system and a solve per component); the forces and states are the same."""
    if law is not None:
        return composite_point(params_table, pidx, delta_out, dim - 1, state_committed, state_trial, e, g,
                               traction_out, C, want_tangent)
    (status, code, broken, slip1, slip2, back1, back2, tau1, tau2, t_n, C11, C12, C21, C22, C1n, C2n,
     Cnn) = mohr_coulomb_point(
        params_table[pidx, P_KS], params_table[pidx, P_KN], params_table[pidx, P_COHESION],
        params_table[pidx, P_TAN_PHI], params_table[pidx, P_TENSILE_STRENGTH],
        params_table[pidx, P_KS_RESIDUAL], params_table[pidx, P_OPEN_TANGENT], dim - 1,
        delta_out[e, g, 0], delta_out[e, g, 1] if dim == 3 else 0.0, delta_out[e, g, dim - 1],
        state_committed[e, g, S_CODE], state_committed[e, g, S_BOND_BROKEN],
        state_committed[e, g, S_PLASTIC_SLIP], state_committed[e, g, S_PLASTIC_SLIP + 1],
        state_committed[e, g, S_BACK_STRESS], state_committed[e, g, S_BACK_STRESS + 1])
    if status != STATUS_OK:
        return status
    write_trial(state_trial[e, g], traction_out[e, g], dim - 1, code, broken, slip1, slip2, back1, back2,
                tau1, tau2, t_n)
    write_tangent(C, dim - 1, C11, C12, C21, C22, C1n, C2n, Cnn)
    return STATUS_OK


@njit(cache=True)
def interface_evaluate(
    coords,
    conn,
    u,
    N,
    dN,
    weights,
    thickness,
    params_table,
    param_index,
    state_committed,
    state_trial,
    delta_out,
    traction_out,
    fe_out,
    ke_out,
    want_tangent,
    info,
    law=None,
):
    """Internal forces, tangent stiffness and joint state of a group of interface elements.

    Parameters
    ----------
    coords : float64 (n_nodes, dim)
        Reference nodal coordinates (m), dim = 2 or 3.
    conn : int64 (n_elem, 2*ns)
        Bottom nodes in face order, then top nodes in the same order.
    u : float64 (n_dof,)
        Global displacements (m), ``dof = node*dim + comp``.
    N : float64 (nip, ns);  dN : float64 (nip, dim-1, ns);  weights : float64 (nip,)
        Shape tables and rule on the reference face (:func:`interface_tables`).
    thickness : float64 (n_elem,)
        Out-of-plane thickness (m) in 2D; ones in 3D.
    params_table : float64 (n_param_sets, N_JOINT_PARAMS);  param_index : int64 (n_elem,)
        Joint-law parameters (masonrydam.materials.mohr_coulomb.joint_params) and the set of each element.
    state_committed : float64 (n_elem, nip, N_JOINT_STATE)
        Committed joint states; read only.
    state_trial : float64 (n_elem, nip, N_JOINT_STATE), out
    delta_out : float64 (n_elem, nip, dim), out
        Local relative displacements ``[s1, (s2,) n]`` (m), opening positive.
    traction_out : float64 (n_elem, nip, dim), out
        Local tractions ``[tau1, (tau2,) t_n]`` (Pa), tension positive.
    fe_out : float64 (n_elem, 2*ns*dim), out
        Element internal force vectors (N), node-major element DOF order.
    ke_out : float64 (n_elem, 2*ns*dim, 2*ns*dim), out
        Element tangent matrices (N/m); written only if ``want_tangent`` (otherwise it is never
        accessed and may be a dummy array such as ``np.empty((0, 0, 0))``). Non-symmetric while
        a joint slips with friction.
    want_tangent : bool
    info : int64 (1,), out
        Index of the failing element when the status is not OK.

    Returns
    -------
    int : STATUS_OK; STATUS_BAD_GEOMETRY for a zero-length / zero-area element (or integration
    point); STATUS_NAN for non-finite input or output. The element index goes to ``info[0]``.

    Equations: ``Du = sum_i N_i (u_top_i - u_bot_i)``, ``delta = R Du`` (eqs. 4-6, 10);
    ``fe = sum_ip B^T t j w h``, ``ke = sum_ip B^T C B j w h`` with
    ``B = R [-N_1 I .. -N_ns I, N_1 I .. N_ns I]`` (eqs. 5, 7, 9, 10). The global-axes
    blocks are ``fe_{bot,i} = -N_i R^T t jwh``, ``fe_{top,i} = +N_i R^T t jwh`` and
    ``ke_{ai,bk} = s_a s_b N_i N_k R^T C R jwh`` with ``s_bot = -1``, ``s_top = +1``.
    """
    n_elem = conn.shape[0]
    dim = coords.shape[1]
    ns = N.shape[1]

    xm, du, R, C, tg, RC, Cg, Dug = _element_scratch(ns, dim)
    for e in range(n_elem):
        status = _evaluate_element(coords, conn, u, N, dN, weights, thickness, params_table, param_index,
                                   state_committed, state_trial, delta_out, traction_out, fe_out, ke_out, want_tangent,
                                   law, e, xm, du, R, C, tg, RC, Cg, Dug)
        if status != STATUS_OK:
            info[0] = e
            return status
    return STATUS_OK


#: the elements of a group are dealt to this many interleaved chunks by :func:`interface_evaluate_threaded`
#: (element ``e`` to chunk ``e % THREAD_CHUNKS``), so that a plastic zone, where the law costs most, is shared
#: by the threads rather than falling to one of them
THREAD_CHUNKS = 64


@njit(cache=True, parallel=True)
def interface_evaluate_threaded(coords, conn, u, N, dN, weights, thickness, params_table, param_index, state_committed,
                                state_trial, delta_out, traction_out, fe_out, ke_out, want_tangent, info, law=None):
    """:func:`interface_evaluate` with the elements shared among numba's threads: the same arguments, outputs and
    status, and, where every element evaluates, the same outputs bit for bit, whatever the number of threads (each
    element is computed by the same code, on its own rows of the outputs; nothing is summed across elements). Where
    some fail, ``info[0]`` is the first failing element, as in the serial kernel; the outputs of other elements may
    have been written.

    Why: the composite law's return mapping (a local Newton per plastic point, its tangent by complex step) is
    most of a static iteration's evaluation on the Eindhoven walls (docs/masonry_softening.md), and its points
    are independent. Joints whose law is Mohr-Coulomb keep the serial kernel (a point costs little there, and the
    default scene's first run compiles no second kernel); they were not timed on threads."""
    n_elem = conn.shape[0]
    dim = coords.shape[1]
    ns = N.shape[1]
    n_chunks = min(n_elem, THREAD_CHUNKS)
    first_failed = np.full(max(n_chunks, 1), n_elem, dtype=np.int64)
    failed_status = np.zeros(max(n_chunks, 1), dtype=np.int64)
    for chunk in prange(n_chunks):
        xm, du, R, C, tg, RC, Cg, Dug = _element_scratch(ns, dim)
        for e in range(chunk, n_elem, n_chunks):
            status = _evaluate_element(coords, conn, u, N, dN, weights, thickness, params_table, param_index,
                                       state_committed, state_trial, delta_out, traction_out, fe_out, ke_out,
                                       want_tangent, law, e, xm, du, R, C, tg, RC, Cg, Dug)
            if status != STATUS_OK:
                first_failed[chunk] = e
                failed_status[chunk] = status
                break
    # each chunk stops at its own first failure, so the smallest of those is the group's first failing element
    worst = n_elem
    status = STATUS_OK
    for chunk in range(n_chunks):
        if first_failed[chunk] < worst:
            worst = first_failed[chunk]
            status = failed_status[chunk]
    if worst < n_elem:
        info[0] = worst
    return status


@njit(cache=True, inline="always")
def _element_scratch(ns, dim):
    """The scratch arrays of :func:`_evaluate_element`: mid-surface derivatives ``xm`` and nodal jumps ``du``
    (ns, dim), the frame ``R``, the law's tangent ``C``, ``R^T C`` and ``R^T C R`` (dim, dim), the traction in
    global axes ``tg`` and the jump at a point ``Dug`` (dim,)."""
    return (np.empty((ns, dim)), np.empty((ns, dim)), np.zeros((dim, dim)), np.empty((dim, dim)), np.empty(dim),
            np.empty((dim, dim)), np.empty((dim, dim)), np.empty(dim))


@njit(cache=True, inline="always")
def _evaluate_element(coords, conn, u, N, dN, weights, thickness, params_table, param_index, state_committed,
                      state_trial, delta_out, traction_out, fe_out, ke_out, want_tangent, law, e, xm, du, R, C, tg, RC,
                      Cg, Dug):
    """Element ``e`` of :func:`interface_evaluate` (its arguments, and the scratch arrays the caller allocates once):
    writes the element's rows of the outputs and returns its status."""
    dim = coords.shape[1]
    nip = N.shape[0]
    ns = N.shape[1]
    ndof_half = ns * dim
    for r in range(2 * ndof_half):
        fe_out[e, r] = 0.0
    if want_tangent:
        for r in range(2 * ndof_half):
            for c2 in range(2 * ndof_half):
                ke_out[e, r, c2] = 0.0

    size = mid_surface_derivatives(coords, conn, e, ns, dim, xm)
    displacement_jumps(conn, u, e, ns, dim, du)
    h = thickness[e]
    pidx = param_index[e]

    for g in range(nip):
        j = local_frame(xm, dN, g, dim, R, size)
        if not math.isfinite(j):
            return STATUS_NAN
        if j == 0.0:
            return STATUS_BAD_GEOMETRY

        # relative displacement in global then local axes
        jump_at_point(N, g, ns, dim, du, Dug)
        for r in range(dim):
            s = 0.0
            for k in range(dim):
                s += R[r, k] * Dug[k]
            delta_out[e, g, r] = s

        status = joint_law_at(params_table, pidx, state_committed, state_trial, delta_out, traction_out, e, g,
                              dim, C, law, want_tangent)
        if status != STATUS_OK:
            return status

        jwh = j * weights[g] * h
        add_point(fe_out, ke_out, e, N, g, ns, dim, ndof_half, R, traction_out[e, g], C, jwh, want_tangent, tg,
                  RC, Cg)

    for r in range(2 * ndof_half):
        if not math.isfinite(fe_out[e, r]):
            return STATUS_NAN
    return STATUS_OK


@njit(cache=True)
def interface_forces(conn, u, N, frame, jw, thickness, params_table, param_index, state_committed, state_trial,
                     delta_out, traction_out, fe_out, info, law=None):
    """Internal forces and joint state of a group of small-displacement interface elements, no tangent: the
    forces of :func:`interface_evaluate` with ``want_tangent = False``, bit for bit, from the frames and
    tributary areas of the reference mid-surface computed once (:func:`interface_geometry`: ``frame`` (n_elem,
    nip, dim, dim), ``jw`` (n_elem, nip) = j w) instead of at every call. What an explicit step asks of its
    joints: the frames are a third of the kernel's work, and they do not change under small displacements.
    Other arguments and the status as in :func:`interface_evaluate` (eqs. 4-10)."""
    n_elem = conn.shape[0]
    dim = frame.shape[2]
    nip = N.shape[0]
    ns = N.shape[1]
    ndof_half = ns * dim
    du = np.empty((ns, dim))
    R = np.empty((dim, dim))
    C = np.empty((dim, dim))
    tg = np.empty(dim)
    Dug = np.empty(dim)
    no_tangent = np.empty((0, 0, 0))
    scratch = np.empty((dim, dim))
    for e in range(n_elem):
        for r in range(2 * ndof_half):
            fe_out[e, r] = 0.0
        displacement_jumps(conn, u, e, ns, dim, du)
        h = thickness[e]
        pidx = param_index[e]
        for g in range(nip):
            jump_at_point(N, g, ns, dim, du, Dug)
            for r in range(dim):
                s = 0.0
                for k in range(dim):
                    R[r, k] = frame[e, g, r, k]
                    s += R[r, k] * Dug[k]
                delta_out[e, g, r] = s
            status = joint_law_at(params_table, pidx, state_committed, state_trial, delta_out, traction_out, e, g,
                                  dim, C, law, False)
            if status != STATUS_OK:
                info[0] = e
                return status
            add_point(fe_out, no_tangent, e, N, g, ns, dim, ndof_half, R, traction_out[e, g], C, jw[e, g] * h,
                      False, tg, scratch, scratch)
        for r in range(2 * ndof_half):
            if not math.isfinite(fe_out[e, r]):
                info[0] = e
                return STATUS_NAN
    return STATUS_OK


@njit(cache=True)
def interface_point_tangents(params_table, param_index, state_base, delta, dim, law, state_scratch, traction_scratch,
                             tangent_out, info):
    """The joint law's tangent ``dt/d delta`` (local axes) at every integration point, for the relative
    displacements ``delta`` of the last evaluation from the state that evaluation read (``state_base``): the
    same law call as :func:`interface_evaluate`, so the tangent is that of the assembled stiffness, kept per
    point. Used by dissipation-based path following (:mod:`masonrydam.solvers.static.dissipation`), whose
    constraint needs each point's dissipation derivative, not only the assembled matrix.

    Parameters
    ----------
    params_table, param_index, state_base : as in :func:`interface_evaluate` (read only)
    delta : float64 (n_elem, nip, dim)
        Local relative displacements (m) of the last evaluation.
    dim : int;  law : None or int, as in :func:`interface_evaluate`
    state_scratch : float64 (n_elem, nip, n_state);  traction_scratch : float64 (n_elem, nip, dim)
        Written (the trial state and tractions again); not read.
    tangent_out : float64 (n_elem, nip, dim, dim), out
        Local tangent (Pa/m), rows tractions ``[tau1, (tau2,) t_n]``, columns ``delta``.
    info : int64 (1,), out
        Failing element, where the status is not OK.

    Returns the law's status (STATUS_OK when every point evaluated).
    """
    C = np.empty((dim, dim))
    for e in range(delta.shape[0]):
        pidx = param_index[e]
        for g in range(delta.shape[1]):
            status = joint_law_at(params_table, pidx, state_base, state_scratch, delta, traction_scratch, e, g,
                                  dim, C, law)
            if status != STATUS_OK:
                info[0] = e
                return status
            for r in range(dim):
                for c in range(dim):
                    tangent_out[e, g, r, c] = C[r, c]
    return STATUS_OK


# ---- the generic path: kinematics -> point law (from Python) -> assembly -------------------------------
# For a joint law without a fused kernel (a plug-in, masonrydam.materials.joint_laws): the same arithmetic
# as interface_evaluate, split where the law is called, so that the law may be any function over the
# points' arrays and these kernels stay cached (they take no function argument).


@njit(cache=True)
def interface_relative_displacements(conn, u, N, frame, delta_out, info):
    """Local relative displacements at every integration point (the kinematics of :func:`interface_evaluate`).

    Parameters
    ----------
    conn : int64 (n_elem, 2*ns);  u : float64 (n_dof,) m, ``dof = node*dim + comp``
    N : float64 (nip, ns)
    frame : float64 (n_elem, nip, dim, dim)
        Local frames R of the reference mid-surface (:func:`interface_geometry`).
    delta_out : float64 (n_elem, nip, dim), out
        ``delta = R sum_a N_a (u_top,a - u_bot,a)`` (m), ``[s1, (s2,) n]``, opening positive (eqs. 4-6, 10).
    info : int64 (1,), out — the element of a non-finite displacement.

    Returns STATUS_OK, or STATUS_NAN (non-finite displacement).
    """
    n_elem = conn.shape[0]
    dim = frame.shape[2]
    nip = N.shape[0]
    ns = N.shape[1]
    du = np.empty((ns, dim))
    Dug = np.empty(dim)
    for e in range(n_elem):
        displacement_jumps(conn, u, e, ns, dim, du)
        for g in range(nip):
            jump_at_point(N, g, ns, dim, du, Dug)
            for r in range(dim):
                s = 0.0
                for k in range(dim):
                    s += frame[e, g, r, k] * Dug[k]
                if not math.isfinite(s):
                    info[0] = e
                    return STATUS_NAN
                delta_out[e, g, r] = s
    return STATUS_OK


@njit(cache=True)
def interface_assemble(N, frame, jw, thickness, traction, tangent, want_tangent, fe_out, ke_out, info):
    """Element forces and tangents from the tractions and tangents at the points (the assembly of
    :func:`interface_evaluate`): ``fe = sum_ip B^T t j w h``, ``ke = sum_ip B^T C B j w h`` (eqs. 7-10).

    Parameters
    ----------
    N : float64 (nip, ns);  frame : float64 (n_elem, nip, dim, dim) local frames R
    jw : float64 (n_elem, nip)
        ``j * w`` of the reference mid-surface (:func:`interface_geometry`; m in 2D, m^2 in 3D).
    thickness : float64 (n_elem,) m (2D; ones in 3D)
    traction : float64 (n_elem, nip, dim) Pa;  tangent : float64 (n_elem, nip, dim, dim) Pa/m (local axes)
    want_tangent : bool
    fe_out : float64 (n_elem, 2*ns*dim), out;  ke_out : float64 (n_elem, 2*ns*dim, 2*ns*dim), out (if wanted)
    info : int64 (1,), out — the element of a non-finite force.

    Returns STATUS_OK or STATUS_NAN.
    """
    n_elem = frame.shape[0]
    dim = frame.shape[2]
    nip = N.shape[0]
    ns = N.shape[1]
    ndof_half = ns * dim
    tg = np.empty(dim)
    RC = np.empty((dim, dim))
    Cg = np.empty((dim, dim))
    for e in range(n_elem):
        for r in range(2 * ndof_half):
            fe_out[e, r] = 0.0
        if want_tangent:
            for r in range(2 * ndof_half):
                for c2 in range(2 * ndof_half):
                    ke_out[e, r, c2] = 0.0
        h = thickness[e]
        for g in range(nip):
            jwh = jw[e, g] * h
            add_point(fe_out, ke_out, e, N, g, ns, dim, ndof_half, frame[e, g], traction[e, g], tangent[e, g], jwh,
                      want_tangent, tg, RC, Cg)
        for r in range(2 * ndof_half):
            if not math.isfinite(fe_out[e, r]):
                info[0] = e
                return STATUS_NAN
    return STATUS_OK


@njit(cache=True)
def interface_geometry(coords, conn, N, dN, weights, points_out, frame_out, jw_out, info):
    """Integration-point coordinates, local frames and tributary lengths / areas.

    Parameters
    ----------
    coords : float64 (n_nodes, dim);  conn : int64 (n_elem, 2*ns)
    N : float64 (nip, ns);  dN : float64 (nip, dim-1, ns);  weights : float64 (nip,)
    points_out : float64 (n_elem, nip, dim), out
        Integration points on the reference mid-surface (m).
    frame_out : float64 (n_elem, nip, dim, dim), out
        Local frame R, rows = unit tangent(s) then unit normal (global components).
    jw_out : float64 (n_elem, nip), out
        ``j * w``: tributary length (2D, m; multiply by the thickness for an area) or area (3D, m^2).
    info : int64 (1,), out — failing element index.

    Returns
    -------
    int : STATUS_OK, STATUS_BAD_GEOMETRY (zero length / area) or STATUS_NAN.
    """
    n_elem = conn.shape[0]
    dim = coords.shape[1]
    nip = N.shape[0]
    ns = N.shape[1]
    xm = np.empty((ns, dim))
    R = np.zeros((dim, dim))
    for e in range(n_elem):
        size = mid_surface_derivatives(coords, conn, e, ns, dim, xm)
        for g in range(nip):
            j = local_frame(xm, dN, g, dim, R, size)
            if not math.isfinite(j):
                info[0] = e
                return STATUS_NAN
            if j == 0.0:
                info[0] = e
                return STATUS_BAD_GEOMETRY
            for k in range(dim):
                s = 0.0
                for a in range(ns):
                    s += N[g, a] * xm[a, k]
                points_out[e, g, k] = s
                for m in range(dim):
                    frame_out[e, g, k, m] = R[k, m]
            jw_out[e, g] = j * weights[g]
    return STATUS_OK
