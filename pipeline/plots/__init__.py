"""Figures: sweep maps (from a store), one collision in depth, the paper figures 2-11."""
