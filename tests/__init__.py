"""The test suite (tests/run.sh); its Python tests run as modules from the repository root: python3 -m tests.validate_drum ..."""
