"""Discretisation and time integration: radial grid, dense linear algebra, the compiled BDF2 loop."""
