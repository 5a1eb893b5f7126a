"""The acoustic reservoir in the implicit step, condensed on the wetted face (the dam's fast path kept).

:class:`AcousticStep` takes the matrices of :mod:`masonrydam.effects.reservoir.acoustic` (``G``, ``H``, ``L``
(n_p, n_p), ``Q`` (n_dof, n_p), ``B`` (n_p, dim), density kg/m3), binds them to a stage's free DOFs and
integrator, and per step eliminates the water's pressures: the dam's step gets the water force and the dense
block ``M_w(h) = (1 - af) beta h^2 rho Q A^-1 Q^T`` on the wetted DOFs, and after the dam's step converged
:meth:`AcousticStep.finish` advances the water (:class:`FluidState`: pressures (n_p,) Pa and their two time
derivatives). Pressure formulation of Zienkiewicz & Bettess (1978) and Chopra & Chakrabarti (1981), integrated
with the dam's generalized-alpha scheme.

Theory: docs/dam_reservoir_foundation.md, section "The water in the implicit step".
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..linear.direct import SingularMatrix, SymmetricFactorization


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

    def attach(self, eq_of_dof: np.ndarray, coefficients) -> None:
        """Bind to the free DOFs (``eq_of_dof`` (n_dof,), -1 where constrained) and the integrator's
        (beta, gamma, am, af); wetted DOFs that are constrained carry no acceleration."""
        eq = eq_of_dof[self.wet]
        keep = eq >= 0
        self.wet_eq = eq[keep]
        self.Qw = self.Q[self.wet[keep]]  # (n_w, n_p) CSR
        #: constrained wetted DOFs (full-DOF) and their rows of Q: the water's force there is a reaction
        self.wet_fixed = self.wet[~keep]
        self.Qc = self.Q[self.wet_fixed]
        self.QwT = sp.csr_matrix(self.Qw.T)
        self.coef = tuple(float(c) for c in coefficients)
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
