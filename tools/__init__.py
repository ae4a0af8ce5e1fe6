"""sphseg's tools as one package, run from the repository root as modules:
`python3 -m tools.studies.chute_study ...`, `from tools.analysis import snap`.

studies/   the validation and method studies (they run sphseg and write docs/data/<study>/)
analysis/  readers and analyses of a run's output, and the 1D reference solution
bench/     benchmarks, scaling charts and the scaling model
dev/       the developer's checks: dependencies, bit-identity, mutants, sizes, links
"""
import os

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))  # the repository root
