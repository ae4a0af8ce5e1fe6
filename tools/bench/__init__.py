"""Benchmarks (make bench), scaling charts and the scaling model."""
