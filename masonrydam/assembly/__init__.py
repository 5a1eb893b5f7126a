"""Assembly: DOF map, sparsity pattern and scatter maps, element groups and the model."""
