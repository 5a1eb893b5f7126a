"""Solvers: sparse direct linear solvers, nonlinear static solution, mechanism diagnosis."""
