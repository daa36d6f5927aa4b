"""Scenes in physical units: materials and fluids, units, validity checks, the scene command."""
