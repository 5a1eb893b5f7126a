"""The acoustic reservoir in the implicit step, condensed on the wetted face (the dam's fast path kept).

:class:`AcousticStep` takes the matrices of :mod:`masonrydam.effects.reservoir.acoustic` (``G``, ``H``, ``L``
(n_p, n_p), ``Q`` (n_dof, n_p), ``B`` (n_p, dim), density kg/m3), binds them to a stage's free DOFs and
integrator, and per step eliminates the water's pressures: the dam's step gets the water force and the dense
block ``M_w(h) = (1 - af) beta h^2 rho Q A^-1 Q^T`` on the wetted DOFs, and after the dam's step converged
:meth:`AcousticStep.finish` advances the water (:class:`FluidState`: pressures (n_p,) Pa and their two time
derivatives). Pressure formulation of Zienkiewicz & Bettess (1978) and Chopra & Chakrabarti (1981), integrated
with the dam's generalized-alpha scheme.

:class:`ExplicitAcoustic` steps the same water with the dam's central difference (the explicit stages): the
pressures advance with the dam's predictor, the dam's acceleration takes the water force of the predicted
pressures, then the water's acceleration takes the dam's (the central difference of the coupled system, whose
mass matrix is block lower triangular), with the water's capacity ``G`` and radiation ``L`` lumped.

Theory: docs/dam_reservoir_foundation.md, sections "The water in the implicit step" and "The water in the
explicit step".
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ...errors import STATUS_OK
from ..linear.direct import SingularMatrix, SymmetricFactorization
from .explicit_kernels import acoustic_correct, acoustic_predict


@dataclass
class FluidState:
    """Pressures (Pa) and their first two time derivatives on the free pressure unknowns (n_p,)."""

    p: np.ndarray
    pd: np.ndarray
    pdd: np.ndarray


class AcousticStep:
    """The compressible reservoir of one dynamic stage (see the module docstring).

    G, H, L: (n_p, n_p) sparse (s2/m2, 1, s/m; times thickness in 2D); Q: (n_dof, n_p) sparse (m2);
    B_face, B_bottom: (n_p, dim) (m2), the ground's load split into the face translating with the frame
    (``Q^T iota``) and the reservoir bottom and banks, which move with the ground surface
    (:class:`masonrydam.effects.reservoir.acoustic.AcousticMatrices`); density: kg/m3. :meth:`attach` binds it to
    the stage's free DOFs and integrator."""

    def __init__(self, G, H, L, Q, B_face, B_bottom, density):
        self.G, self.H, self.L = (sp.csr_matrix(x) for x in (G, H, L))
        self.Q = sp.csr_matrix(Q)
        self.B_face = np.asarray(B_face, dtype=np.float64)
        self.B_bottom = np.asarray(B_bottom, dtype=np.float64)
        self.rho = float(density)
        self.n_p = self.G.shape[0]
        #: wetted DOFs (full-DOF indices, sorted)
        self.wet = np.unique(self.Q.nonzero()[0])
        self._systems = {}

    def attach(self, eq_of_dof: np.ndarray, coefficients=None) -> None:
        """Bind to the free DOFs (``eq_of_dof`` (n_dof,), -1 where constrained) and the implicit integrator's
        (beta, gamma, am, af) (None for the explicit scheme: :class:`ExplicitAcoustic` steps the water);
        wetted DOFs that are constrained carry no acceleration."""
        eq = eq_of_dof[self.wet]
        keep = eq >= 0
        self.wet_eq = eq[keep]
        self.Qw = self.Q[self.wet[keep]]  # (n_w, n_p) CSR
        #: constrained wetted DOFs (full-DOF) and their rows of Q: the water's force there is a reaction
        self.wet_fixed = self.wet[~keep]
        self.Qc = self.Q[self.wet_fixed]
        self.QwT = sp.csr_matrix(self.Qw.T)
        self.coef = None if coefficients is None else tuple(float(c) for c in coefficients)
        self._systems = {}

    def initial_state(self) -> FluidState:
        z = np.zeros(self.n_p)
        return FluidState(z, z.copy(), z.copy())

    def system(self, h: float):
        """(factor of A, Z = A^-1 Q_w^T (n_p, n_w), M_w (n_w, n_w), (C_p, C_pd, C_pdd)) for step h
        (cached): the matrices that give the known part of the step's right-hand side from the last
        state, ``r_n = -(C_p p + C_pd p' + C_pdd p'') - am rho Q^T a_n - rho B a_g``."""
        out = self._systems.get(h)
        if out is None:
            beta, gamma, am, af = self.coef
            A = ((1.0 - am) * self.G + (1.0 - af) * (gamma * h * self.L + beta * h * h * self.H)).tocsr()
            A = 0.5 * (A + A.T)
            try:  # L D L^T with numba substitutions: about 2x faster per solve than SuperLU's (linear/direct.py)
                fact = SymmetricFactorization(A.tocsr())
            except (SingularMatrix, ValueError):
                fact = spla.splu(sp.csc_matrix(A))
            Z = fact.solve(np.ascontiguousarray(self.Qw.T.toarray()))
            Mw = (1.0 - af) * beta * h * h * self.rho * (self.Qw @ Z)
            Mw = 0.5 * (Mw + Mw.T)
            # r_n expanded in the last state: -(1 - af)(L pd~ + H p~) - af (L pd + H p) - am G pdd
            C_p = self.H
            C_pd = (self.L + (1.0 - af) * h * self.H).tocsr()
            C_pdd = ((1.0 - af) * h * (1.0 - gamma) * self.L + (1.0 - af) * h * h * (0.5 - beta) * self.H
                     + am * self.G).tocsr()
            if len(self._systems) > 16:
                self._systems.clear()
            out = self._systems[h] = (fact, Z, Mw, (C_p, C_pd, C_pdd))
        return out

    def mass_block(self, h: float) -> np.ndarray:
        """``M_w(h)`` (n_w, n_w), kg, on the free wetted DOFs ``wet_eq``."""
        return self.system(h)[2]

    def force(self, state: FluidState) -> np.ndarray:
        """The water force ``Q p`` on the free wetted DOFs (n_w,), N."""
        return self.Qw @ state.p

    def start(self, state: FluidState, h: float, a_n_w: np.ndarray, frame_n, frame_1, bottom_n, bottom_1):
        """What the dam's step needs: ``g`` (n_w,) N (the water force at the end of the step less its
        ``M_w a1`` part) and a context for :meth:`finish`. ``frame_*`` (dim,) m/s2: the acceleration of
        the frame the dam's accelerations are measured in at the ends of the step (the ground's in the
        relative formulation, zero when they are total); ``bottom_*``: the total acceleration of the
        reservoir bottom (the ground's, or the free field at the rock's surface)."""
        beta, gamma, am, af = self.coef
        fact, Z, _, (C_p, C_pd, C_pdd) = self.system(h)
        p_pred = state.p + h * state.pd + h * h * (0.5 - beta) * state.pdd
        pd_pred = state.pd + h * (1.0 - gamma) * state.pdd
        r = -(C_p @ state.p + C_pd @ state.pd + C_pdd @ state.pdd)
        if am != 0.0:
            r -= am * self.rho * (self.QwT @ a_n_w)
        r -= self.rho * (self.B_face @ ((1.0 - af) * np.asarray(frame_1) + af * np.asarray(frame_n))
                         + self.B_bottom @ ((1.0 - af) * np.asarray(bottom_1) + af * np.asarray(bottom_n)))
        y = fact.solve(r)
        g = self.Qw @ (p_pred + beta * h * h * y)
        return g, (h, p_pred, pd_pred, y)

    def finish(self, ctx, a1_w: np.ndarray) -> FluidState:
        """The water at the end of the step, from the dam's converged acceleration ``a1_w`` (n_w,)."""
        beta, gamma, am, af = self.coef
        h, p_pred, pd_pred, y = ctx
        Z = self.system(h)[1]
        pdd = y - (1.0 - am) * self.rho * (Z @ a1_w)
        return FluidState(p_pred + beta * h * h * pdd, pd_pred + gamma * h * pdd, pdd)


def row_sum_lumped(A, name: str) -> np.ndarray:
    """The row sums (n,) of the sparse matrix ``A`` (n, n): the lumped diagonal of a consistent "mass" of
    linear (bilinear, trilinear) elements, whose shape functions are nonnegative, so each row sum is the
    integral of one shape function (Hughes 2000, sec. 7.3.2; Zienkiewicz, Taylor & Zhu 2013, sec. 16.2.4).
    ValueError where one is negative (``name`` says which matrix)."""
    d = np.ascontiguousarray(np.asarray(sp.csr_matrix(A).sum(axis=1)).ravel(), dtype=np.float64)
    if (d < 0.0).any() or not np.isfinite(d).all():
        raise ValueError(f"the lumped {name} has a negative or non-finite entry")
    return d


class ExplicitAcoustic:
    """The compressible reservoir of an explicit (central difference) stage: the water's pressures stepped with
    the dam's central difference (velocity form).

    Per step, with the dam's (:func:`~.explicit.run_central_difference`):

        p'_{n+1/2} = p'_n + h/2 p''_n,   p_{n+1} = p_n + h p'_{n+1/2}                      (:meth:`predict`)
        M a_{n+1} = ... + Q_w p_{n+1}                                                    (the dam's corrector)
        (g + h/2 l) p''_{n+1} = -H p_{n+1} - l p'_{n+1/2} - rho (Q_w^T a_{n+1} + B_face a_f + B_bottom a_b)
        p'_{n+1} = p'_{n+1/2} + h/2 p''_{n+1}                                           (:meth:`correct`)

    This is central difference applied to the coupled system ``[M 0; rho Q^T G] [u; p]'' + [C 0; 0 L] [u; p]' +
    [K -Q; 0 H] [u; p] = f`` whose mass matrix is block lower triangular: the dam's row is solved first (the
    water force of the predicted pressures), then the water's (the dam's new acceleration), both explicitly,
    no iteration and no lag between the two fields: the partitioned explicit-explicit scheme of Belytschko &
    Mullen (1978, "Stability of explicit-implicit mesh partitions in time integration", IJNME 12:1575-1586)
    and Felippa & Park (1980, "Staggered transient analysis procedures for coupled mechanical systems:
    formulation", CMAME 24:61-111), as explicit codes step acoustic elements with a structure (Abaqus
    Analysis User's Guide, "Acoustic, shock, and coupled acoustic-structural analysis"). Its stable step is
    that of central difference, ``omega_max h <= 2``, with ``omega_max`` the highest frequency of the coupled
    undamped system (:func:`~.stability.coupled_highest_frequency`).

    ``G`` and ``L`` are row-sum lumped (``g``, ``l`` (n_p,)) rather than ``G + h/2 L`` factorized once per stage.
    Why, measured (docs/dam_reservoir_foundation.md, "The water in the explicit step"): on the 3D dam of
    examples/dam_3d_earthquake.toml with acoustic water (13 920 pressure unknowns) one substitution with the
    L D L^T factor of the consistent matrix takes 8.1 ms, twice the dam's whole explicit step, against 0.25 ms
    for the lumped update (``H p`` and one pass); and the lumped capacity lowers the water's highest frequency
    2.4-fold (2D) to 2.9-fold (3D), so that where the water sets the stable step (a soft dam, a fine fluid
    mesh) the step is that much larger. The price is in the pressure, not the dam: on a 10 m dam the heel
    pressure history differs from the mesh-converged one by 3.1 % of its peak on 1 m elements (consistent
    2.1 %) and 1.6 % on 0.5 m (0.6 %), the crest displacement by 1.9 % (2.0 %) and 0.4 % (0.5 %). With ``L``
    lumped too, the radiation term is taken at the end-of-step rate at no cost (a diagonal ``g + h/2 l``),
    which keeps the absorbing far end and bottom out of the stable step: at the half-step rate, lagged like
    the dam's viscous damping, a fully absorbing bottom made the steps between 0.7 and 0.8 of the critical
    one grow without bound.

    ``fluid``: the stage's :class:`AcousticStep`, attached (:meth:`AcousticStep.attach`); ``free``: the
    stage's free DOFs (n_eq,). Vectors: pressures on the free pressure unknowns (n_p,) Pa; the dam's on its
    free wetted DOFs (n_w,)."""

    def __init__(self, fluid: AcousticStep, free: np.ndarray):
        self.fluid = fluid
        self.rho = fluid.rho
        #: (n_p,) the lumped capacity G (s2 m; s2 in 2D per the thickness) and radiation L (s m2)
        self.capacity = row_sum_lumped(fluid.G, "capacity G of the acoustic water")
        if not (self.capacity > 0.0).all():
            raise ValueError("the acoustic water of an explicit stage needs a sound speed (a positive capacity G at "
                             "every pressure unknown)")
        self.radiation = row_sum_lumped(fluid.L, "radiation matrix L of the acoustic water")
        #: (n_w,) the full-DOF indices of the free wetted DOFs
        self.wet_dofs = np.ascontiguousarray(np.asarray(free)[fluid.wet_eq])
        self._B_face = np.ascontiguousarray(fluid.B_face)
        self._B_bottom = np.ascontiguousarray(fluid.B_bottom)

    def force(self, p: np.ndarray) -> np.ndarray:
        """The water force ``Q_w p`` (n_w,) N on the free wetted DOFs."""
        return self.fluid.Qw @ p

    def _accelerate(self, p, pd_half, a_wet, frame, bottom, h, pdd, pd):
        f = self.fluid
        return acoustic_correct(f.H @ p, f.QwT @ a_wet, pd_half, self._B_face, np.asarray(frame, dtype=np.float64),
                                self._B_bottom, np.asarray(bottom, dtype=np.float64), self.capacity, self.radiation,
                                self.rho, h, pdd, pd)

    def start(self, state: FluidState, a_wet: np.ndarray, frame, bottom) -> FluidState:
        """The water at the stage's start: the pressures and rates of ``state`` (at rest, or carried over from
        the stage before), the pressure acceleration from the water's equation with the lumped matrices and
        the dam's initial acceleration ``a_wet`` (n_w,) m/s2 (``frame``, ``bottom`` (dim,) m/s2: see
        :meth:`AcousticStep.start`), as the dam's initial acceleration comes from its own equation."""
        pdd = np.empty(self.fluid.n_p)
        pd = np.empty(self.fluid.n_p)
        self._accelerate(state.p, state.pd, a_wet, frame, bottom, 0.0, pdd, pd)
        return FluidState(state.p.copy(), state.pd.copy(), pdd)

    def predict(self, state: FluidState, h: float):
        """``(p_{n+1}, p'_{n+1/2})`` (n_p,) each from the state at the start of a step of ``h`` s."""
        p1 = np.empty(self.fluid.n_p)
        pd_half = np.empty(self.fluid.n_p)
        acoustic_predict(state.p, state.pd, state.pdd, h, p1, pd_half)
        return p1, pd_half

    def correct(self, p1: np.ndarray, pd_half: np.ndarray, a_wet: np.ndarray, frame, bottom, h: float):
        """The water at the end of the step (a :class:`FluidState`) from the dam's acceleration there
        ``a_wet`` (n_w,) m/s2, or None where a pressure acceleration is not finite."""
        pdd = np.empty(self.fluid.n_p)
        pd = np.empty(self.fluid.n_p)
        if self._accelerate(p1, pd_half, a_wet, frame, bottom, h, pdd, pd) != STATUS_OK:
            return None
        return FluidState(p1, pd, pdd)
