"""Sweeps: the plan (TOML), the task a worker runs, executors, the store and its single writer, analysis."""
