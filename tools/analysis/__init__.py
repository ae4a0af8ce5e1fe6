"""Readers and analyses of a run's output (snapshots, diagnostics), and the 1D reference solution."""
