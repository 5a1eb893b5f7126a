"""Element kernels (numba) and element tables: shape functions, quadrature, continuum and interface elements."""
